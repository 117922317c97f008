#include "workbench/gui/phasing_view.h"

#include <qcustomplot.h>
#include <unistd.h>

#include <QComboBox>
#include <QFileDialog>
#include <QHBoxLayout>
#include <QLabel>
#include <QPushButton>
#include <QTabWidget>
#include <QVBoxLayout>
#include <algorithm>
#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/file_util.h"
#include "core/json_util.h"
#include "workbench/gui/figure_export.h"
#include "workbench/gui/job_runner.h"
#include "workbench/gui/log_panel.h"
#include "workbench/jobs/keys_job.h"
#include "workbench/jobs/phasing_job.h"

namespace csw::gui {

namespace fs = std::filesystem;
using nlohmann::json;

const char* const PhasingView::kTypes[3] = {"CV", "V", "C"};
const char* const PhasingView::kComponents[4] = {"placement onset", "placement target", "shape onset", "shape target"};

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const char* const kMethods[2] = {"kinematic", "posterior"};
const char* const kCsvComponents[4] = {"placement_onset", "placement_target", "shape_onset", "shape_target"};
const char* const kFigureFilter = "PNG image (*.png);;SVG drawing (*.svg);;PDF document (*.pdf)";

// One CSV line split into fields (double quotes: "" inside a quoted field).
std::vector<std::string> SplitCsv(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        out.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      out.emplace_back();
    } else if (c != '\r') {
      out.back() += c;
    }
  }
  return out;
}

// A summary entry {"mean_ms", "sd_ms", "ci95_ms", "count"} of a phasing result, or null.
const json* Summary(const json& phasing, int method, int type, int component) {
  if (!phasing.is_object()) return nullptr;
  const char* comp = component < 2 ? "placement" : "shape";
  const char* land = component % 2 == 0 ? "onset" : "target";
  const auto m = phasing.find(kMethods[method]);
  if (m == phasing.end() || !m->is_object()) return nullptr;
  const auto t = m->find(PhasingView::kTypes[type]);
  if (t == m->end() || !t->is_object() || !t->contains(comp) || !(*t)[comp].contains(land)) return nullptr;
  return &(*t)[comp][land];
}

}  // namespace

std::vector<PhasingKeyTimes> ReadPhasingCsv(const std::string& path) {
  std::istringstream in(ReadTextFile(path));
  std::string line;
  if (!std::getline(in, line))
    throw ParseError({path, std::nullopt, std::nullopt}, "empty file, expected csw phasing's CSV");
  const std::vector<std::string> header = SplitCsv(line);
  std::map<std::string, size_t> column;
  for (size_t i = 0; i < header.size(); ++i) column[header[i]] = i;
  if (!column.count("type")) throw ParseError({path, std::nullopt, 1}, "no column 'type' (not csw phasing's CSV)");
  std::array<std::array<size_t, 4>, 2> index{};
  for (int m = 0; m < 2; ++m)
    for (int c = 0; c < 4; ++c) {
      const std::string name = std::string(kMethods[m]) + "_" + kCsvComponents[c] + "_rel_a1_ms";
      if (!column.count(name)) throw ParseError({path, std::nullopt, 1}, "no column '" + name + "'");
      index[m][c] = column[name];
    }
  std::vector<PhasingKeyTimes> keys;
  int number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line == "\r") continue;
    const std::vector<std::string> f = SplitCsv(line);
    if (f.size() != header.size())
      throw ParseError({path, std::nullopt, number},
                       std::to_string(f.size()) + " fields, " + std::to_string(header.size()) + " expected");
    PhasingKeyTimes k;
    k.type = f[column["type"]];
    for (int m = 0; m < 2; ++m)
      for (int c = 0; c < 4; ++c) {
        const std::string& v = f[index[m][c]];
        if (v.empty()) {
          k.rel_ms[m][c] = kNaN;
          continue;
        }
        try {
          size_t used = 0;
          k.rel_ms[m][c] = std::stod(v, &used);
          if (used != v.size()) throw std::invalid_argument(v);
        } catch (const std::exception&) {
          throw ParseError({path, std::nullopt, number}, "'" + v + "' is not a number");
        }
      }
    keys.push_back(k);
  }
  return keys;
}

AnalysisData LoadAnalysisJson(const std::string& path) {
  const json doc = ParseJsonText(ReadTextFile(path), path);
  AnalysisData data;
  auto take_phasing = [&](const json& r) {
    data.phasing = r;
    if (r.contains("csv") && r["csv"].is_string()) {
      const std::string csv = r["csv"].get<std::string>();
      std::error_code ec;
      if (fs::exists(csv, ec)) {
        data.keys = ReadPhasingCsv(csv);
      } else {
        data.notes << QStringLiteral("per-key CSV %1 not found: histograms show the means only")
                          .arg(QString::fromStdString(csv));
      }
    } else {
      data.notes << QStringLiteral("no per-key CSV (csw phasing --csv): histograms show the means only");
    }
  };
  if (doc.is_object() && doc.contains("kinematic") && doc.contains("posterior")) {
    take_phasing(doc);
  } else if (doc.is_object() && doc.contains("shape") && doc["shape"].is_object() &&
             doc["shape"].contains("confusion")) {
    data.keys_score = doc;
  } else if (doc.is_object() && doc.contains("stages") && doc["stages"].is_array()) {
    // csw demo's report.json.
    for (const json& s : doc["stages"]) {
      if (!s.contains("result")) continue;
      if (s.value("name", "") == "phasing") take_phasing(s["result"]);
      if (s.value("name", "") == "keys" && s["result"].contains("score") && s["result"]["score"].contains("shape"))
        data.keys_score = s["result"]["score"];
    }
  }
  if (data.empty())
    throw InvalidInput(path +
                       ": neither a result of csw phasing --json nor of csw keys score --json (with labelled takes)");
  return data;
}

AnalysisData RunAnalysis(const std::string& corpus, const std::string& keys_file, Progress& progress) {
  AnalysisData data;
  QStringList failures;
  try {
    jobs::KeysScoreOptions ks;
    ks.corpus = corpus;
    ks.keys = keys_file;
    ks.dry_run = true;
    json r = jobs::KeysScore(ks, progress);
    if (r.contains("shape")) {
      data.keys_score = std::move(r);
    } else {
      data.notes << QStringLiteral("keys score: no take has a key tier to compare with");
    }
  } catch (const Cancelled&) {
    throw;
  } catch (const std::exception& e) {
    data.notes << QStringLiteral("keys score: %1").arg(QString::fromStdString(e.what()));
  }
  static std::atomic<int> counter{0};
  const fs::path csv = fs::temp_directory_path() /
                       ("csw-gui-phasing-" + std::to_string(::getpid()) + "-" + std::to_string(counter++) + ".csv");
  try {
    jobs::PhasingOptions po;
    po.corpus = corpus;
    po.keys = keys_file;
    po.csv = csv.string();
    json r = jobs::Phasing(po, progress);
    r.erase("csv");  // a temporary file
    data.keys = ReadPhasingCsv(csv.string());
    data.phasing = std::move(r);
  } catch (const Cancelled&) {
    std::error_code ec;
    fs::remove(csv, ec);
    throw;
  } catch (const std::exception& e) {
    data.notes << QStringLiteral("phasing: %1").arg(QString::fromStdString(e.what()));
  }
  std::error_code ec;
  fs::remove(csv, ec);
  if (data.empty()) throw InvalidInput(data.notes.join("; ").toStdString());
  return data;
}

PhasingView::PhasingView(LogPanel* log, QWidget* parent)
    : QWidget(parent), log_(log), runner_(new JobRunner(QStringLiteral("csw-phasing-view"), this)) {
  setObjectName("phasingView");
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  auto* bar = new QHBoxLayout();
  auto* open = new QPushButton(tr("Open JSON…"), this);
  open->setToolTip(tr("A result of csw phasing --json or csw keys score --json"));
  auto* run = new QPushButton(tr("Run on Corpus…"), this);
  run->setToolTip(tr("Runs csw phasing and csw keys score (a dry run) on the open corpus with a key recogniser"));
  cancel_ = new QPushButton(tr("Cancel"), this);
  cancel_->setEnabled(false);
  method_combo_ = new QComboBox(this);
  method_combo_->addItem(tr("kinematic landmarks"));
  method_combo_->addItem(tr("posterior landmarks"));
  auto* export_button = new QPushButton(tr("Export Figure…"), this);
  bar->addWidget(open);
  bar->addWidget(run);
  bar->addWidget(cancel_);
  bar->addWidget(method_combo_);
  bar->addStretch(1);
  bar->addWidget(export_button);
  layout->addLayout(bar);
  tabs_ = new QTabWidget(this);
  phasing_plot_ = new QCustomPlot(tabs_);
  phasing_plot_->setObjectName("phasingPlot");
  confusion_plot_ = new QCustomPlot(tabs_);
  confusion_plot_->setObjectName("confusionPlot");
  tabs_->addTab(phasing_plot_, tr("Phasing"));
  tabs_->addTab(confusion_plot_, tr("Confusion"));
  layout->addWidget(tabs_, 1);
  status_ = new QLabel(tr("Open a JSON result, or run the analysis on the open corpus."), this);
  status_->setWordWrap(true);
  layout->addWidget(status_);

  connect(open, &QPushButton::clicked, this, &PhasingView::ChooseJson);
  connect(run, &QPushButton::clicked, this, &PhasingView::ChooseRun);
  connect(cancel_, &QPushButton::clicked, this, &PhasingView::Cancel);
  connect(export_button, &QPushButton::clicked, this, [this] { ChooseExport(tabs_->currentIndex() == 1); });
  connect(method_combo_, qOverload<int>(&QComboBox::activated), this, [this](int m) { SetMethod(m); });
  connect(runner_, &JobRunner::ProgressChanged, this, [this](const QString& stage, double fraction) {
    status_->setText(tr("%1 (%2 %)").arg(stage).arg(std::lround(100 * fraction)));
  });
  connect(runner_, &JobRunner::Succeeded, this, [this] {
    cancel_->setEnabled(false);
    AnalysisData data = pending_ ? std::move(*pending_) : AnalysisData{};
    pending_.reset();
    for (const QString& n : data.notes) log_->Warning(n);
    SetData(std::move(data));
    emit Finished(QStringLiteral("succeeded"));
  });
  connect(runner_, &JobRunner::Canceled, this, [this] {
    cancel_->setEnabled(false);
    pending_.reset();
    status_->setText(tr("Cancelled."));
    log_->Info(tr("Phasing and confusion: cancelled"));
    emit Finished(QStringLiteral("canceled"));
  });
  connect(runner_, &JobRunner::Failed, this, [this](const QString& message) {
    cancel_->setEnabled(false);
    pending_.reset();
    status_->setText(tr("Failed: %1").arg(message));
    log_->Error(tr("Phasing and confusion: %1").arg(message));
    emit Finished(QStringLiteral("failed"));
  });
  SetData(AnalysisData{});
}

bool PhasingView::running() const { return runner_->running(); }

void PhasingView::Cancel() { runner_->Cancel(); }

void PhasingView::Start(std::function<AnalysisData(Progress&)> work, const QString& what) {
  auto out = std::make_shared<AnalysisData>();
  pending_ = out;
  runner_->Start([work = std::move(work), out](Progress& progress) { *out = work(progress); });
  cancel_->setEnabled(true);
  status_->setText(what);
}

bool PhasingView::OpenJson(const QString& path) {
  if (running()) return false;
  const std::string p = path.toStdString();
  Start([p](Progress&) { return LoadAnalysisJson(p); }, tr("Reading %1…").arg(path));
  return true;
}

bool PhasingView::Run(const QString& corpus, const QString& keys_file) {
  if (running()) return false;
  if (corpus.isEmpty()) {
    log_->Error(tr("Open a corpus before running the phasing analysis."));
    return false;
  }
  const std::string c = corpus.toStdString(), k = keys_file.toStdString();
  Start([c, k](Progress& progress) { return RunAnalysis(c, k, progress); },
        tr("Running csw keys score and csw phasing on %1…").arg(corpus));
  log_->Info(tr("Phasing and confusion of %1 with %2…").arg(corpus, keys_file));
  return true;
}

void PhasingView::ChooseJson() {
  const QString path = QFileDialog::getOpenFileName(this, tr("Open Phasing or Key-Score Result"), QString(),
                                                    tr("JSON (*.json);;All files (*)"));
  if (!path.isEmpty()) OpenJson(path);
}

void PhasingView::ChooseRun() {
  const QString path = QFileDialog::getOpenFileName(this, tr("Key Recogniser File"), QString(),
                                                    tr("csw model file (*.h5);;All files (*)"));
  if (!path.isEmpty()) Run(corpus_, path);
}

void PhasingView::ChooseExport(bool confusion) {
  const QString path = QFileDialog::getSaveFileName(
      this, confusion ? tr("Export Confusion Figure") : tr("Export Phasing Figure"), QString(), kFigureFilter);
  if (path.isEmpty()) return;
  try {
    confusion ? ExportConfusion(path) : ExportPhasing(path);
    log_->Info(tr("Figure saved to %1").arg(path));
  } catch (const std::exception& e) {
    log_->Error(tr("Figure not saved: %1").arg(QString::fromStdString(e.what())));
  }
}

void PhasingView::SetData(AnalysisData data) {
  data_ = std::move(data);
  DrawPhasing();
  DrawConfusion();
  QStringList parts;
  if (!data_.phasing.is_null())
    parts << tr("phasing of %1 keys").arg(data_.phasing.value("keys_measured", static_cast<int64_t>(0)));
  if (!data_.keys_score.is_null())
    parts << tr("shape accuracy %1 %, placement %2 %")
                 .arg(100 * data_.keys_score["shape"].value("accuracy", 0.0), 0, 'f', 1)
                 .arg(100 * data_.keys_score["placement"].value("accuracy", 0.0), 0, 'f', 1);
  if (!parts.isEmpty()) status_->setText(parts.join(QStringLiteral("; ")) + QStringLiteral("."));
  if (data_.phasing.is_null() && !data_.keys_score.is_null()) tabs_->setCurrentIndex(1);
  if (!data_.phasing.is_null()) tabs_->setCurrentIndex(0);
}

void PhasingView::SetMethod(int method) {
  method_ = method == 1 ? 1 : 0;
  if (method_combo_->currentIndex() != method_) method_combo_->setCurrentIndex(method_);
  DrawPhasing();
}

void PhasingView::DrawPhasing() {
  QCustomPlot* p = phasing_plot_;
  p->clearItems();
  p->clearPlottables();
  p->plotLayout()->clear();
  totals_ = {};
  if (data_.phasing.is_null()) {
    p->plotLayout()->addElement(0, 0, new QCPTextElement(p, tr("No phasing result")));
    p->replot();
    return;
  }
  auto* title = new QCPTextElement(
      p, method_ == 0 ? tr("Phasing, kinematic landmarks: time from A1 (ms), bins of %1 ms").arg(kBinMs)
                      : tr("Phasing, posterior landmarks: time from A1 (ms), bins of %1 ms").arg(kBinMs));
  QFont bold = font();
  bold.setBold(true);
  title->setFont(bold);
  p->plotLayout()->addElement(0, 0, title);
  auto* grid = new QCPLayoutGrid;
  p->plotLayout()->addElement(1, 0, grid);
  QFont small = font();
  small.setPointSizeF(std::max(6.0, small.pointSizeF() * 0.8));
  // One common time range for every panel: the values' (or the means') span.
  double lo = 1e300, hi = -1e300;
  for (const PhasingKeyTimes& k : data_.keys)
    for (double v : k.rel_ms[static_cast<size_t>(method_)])
      if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
  for (int t = 0; t < 3; ++t)
    for (int c = 0; c < 4; ++c)
      if (const json* s = Summary(data_.phasing, method_, t, c); s && s->value("count", 0) > 0) {
        const double m = s->value("mean_ms", 0.0), sd = s->value("sd_ms", 0.0);
        lo = std::min(lo, m - sd), hi = std::max(hi, m + sd);
      }
  if (!(hi >= lo)) lo = -300, hi = 300;
  lo = std::floor(lo / kBinMs) * kBinMs - kBinMs;
  hi = std::ceil(hi / kBinMs) * kBinMs + kBinMs;
  const int bins = static_cast<int>(std::lround((hi - lo) / kBinMs));
  for (int t = 0; t < 3; ++t) {
    for (int c = 0; c < 4; ++c) {
      auto* rect = new QCPAxisRect(p);
      grid->addElement(t, c, rect);
      rect->setMinimumMargins(QMargins(2, 2, 2, 2));
      QCPAxis* x = rect->axis(QCPAxis::atBottom);
      QCPAxis* y = rect->axis(QCPAxis::atLeft);
      x->setTickLabelFont(small);
      y->setTickLabelFont(small);
      x->setLabelFont(small);
      x->setRange(lo, hi);
      x->ticker()->setTickCount(4);
      y->ticker()->setTickCount(3);
      if (t == 2) x->setLabel(tr("ms from A1"));
      std::vector<int> counts(static_cast<size_t>(bins), 0);
      int total = 0;
      for (const PhasingKeyTimes& k : data_.keys) {
        if (k.type != kTypes[t]) continue;
        const double v = k.rel_ms[static_cast<size_t>(method_)][static_cast<size_t>(c)];
        if (!std::isfinite(v)) continue;
        const int b = std::clamp(static_cast<int>(std::floor((v - lo) / kBinMs)), 0, bins - 1);
        ++counts[static_cast<size_t>(b)];
        ++total;
      }
      totals_[static_cast<size_t>(t)][static_cast<size_t>(c)] = total;
      int top = 1;
      if (total > 0) {
        auto* bars = new QCPBars(x, y);
        bars->setWidth(kBinMs * 0.95);
        bars->setPen(Qt::NoPen);
        bars->setBrush(c < 2 ? QColor(70, 130, 200) : QColor(220, 120, 60));
        QVector<double> keys, values;
        for (int b = 0; b < bins; ++b) {
          keys << lo + (b + 0.5) * kBinMs;
          values << counts[static_cast<size_t>(b)];
          top = std::max(top, counts[static_cast<size_t>(b)]);
        }
        bars->setData(keys, values, true);
      }
      y->setRange(0, top * 1.9);  // room for the caption above the bars
      QString caption = QStringLiteral("%1 %2").arg(kTypes[t], kComponents[c]);
      if (const json* s = Summary(data_.phasing, method_, t, c); s && s->value("count", 0) > 0) {
        const double mean = s->value("mean_ms", 0.0);
        auto* line = new QCPItemStraightLine(p);
        line->setClipAxisRect(rect);
        for (QCPItemPosition* pos : {line->point1, line->point2}) pos->setAxes(x, y);
        line->point1->setCoords(mean, 0);
        line->point2->setCoords(mean, 1);
        line->setPen(QPen(QColor(20, 20, 20), 1.2, Qt::DashLine));
        const double ci = s->value("ci95_ms", 0.0);
        if (ci > 0) {
          auto* band = new QCPItemRect(p);
          band->setClipAxisRect(rect);
          for (QCPItemPosition* pos : {band->topLeft, band->bottomRight}) pos->setAxes(x, y);
          band->topLeft->setCoords(mean - ci, top * 1.9);
          band->bottomRight->setCoords(mean + ci, 0);
          band->setPen(Qt::NoPen);
          band->setBrush(QColor(0, 0, 0, 30));
        }
        caption += QStringLiteral("\n%1 ± %2 ms, n = %3")
                       .arg(mean, 0, 'f', 0)
                       .arg(s->value("sd_ms", 0.0), 0, 'f', 0)
                       .arg(s->value("count", 0));
      } else {
        caption += tr("\nno key");
      }
      auto* text = new QCPItemText(p);
      text->setClipAxisRect(rect);
      text->position->setType(QCPItemPosition::ptAxisRectRatio);
      text->position->setAxisRect(rect);
      text->position->setCoords(0.02, 0.02);
      text->setPositionAlignment(Qt::AlignLeft | Qt::AlignTop);
      text->setTextAlignment(Qt::AlignLeft);
      text->setFont(small);
      text->setText(caption);
    }
  }
  p->replot();
}

void PhasingView::DrawConfusion() {
  QCustomPlot* p = confusion_plot_;
  p->clearItems();
  p->clearPlottables();
  p->plotLayout()->clear();
  cells_ = {};
  if (data_.keys_score.is_null()) {
    p->plotLayout()->addElement(0, 0, new QCPTextElement(p, tr("No key-recogniser result")));
    p->replot();
    return;
  }
  QFont small = font();
  small.setPointSizeF(std::max(6.0, small.pointSizeF() * 0.85));
  QFont bold = font();
  bold.setBold(true);
  const char* which[2] = {"shape", "placement"};
  for (int w = 0; w < 2; ++w) {
    const json& part = data_.keys_score[which[w]];
    const json& rows = part["confusion"];
    const int n = static_cast<int>(rows.size());
    auto& cells = cells_[static_cast<size_t>(w)];
    for (const json& r : rows) {
      std::vector<int> row;
      for (const json& v : r) row.push_back(v.get<int>());
      cells.push_back(row);
    }
    auto* title = new QCPTextElement(p, tr("%1 at the labelled frames: %2 % of %3")
                                            .arg(which[w])
                                            .arg(100 * part.value("accuracy", 0.0), 0, 'f', 1)
                                            .arg(part.value("count", 0)));
    title->setFont(bold);
    p->plotLayout()->addElement(0, w, title);
    auto* rect = new QCPAxisRect(p);
    p->plotLayout()->addElement(1, w, rect);
    QCPAxis* x = rect->axis(QCPAxis::atBottom);
    QCPAxis* y = rect->axis(QCPAxis::atLeft);
    x->setLabel(tr("decided (posterior argmax)"));
    y->setLabel(tr("labelled"));
    for (QCPAxis* a : {x, y}) {
      a->setTickLabelFont(small);
      a->setLabelFont(small);
      auto ticker = QSharedPointer<QCPAxisTickerFixed>::create();
      ticker->setTickStep(1.0);
      a->setTicker(ticker);
      a->setSubTicks(false);
      a->grid()->setVisible(false);
      a->setRange(-0.5, n - 0.5);
    }
    y->setRangeReversed(true);
    auto* map = new QCPColorMap(x, y);
    map->data()->setSize(n, n);
    map->data()->setRange(QCPRange(0, n - 1), QCPRange(0, n - 1));
    for (int t = 0; t < n; ++t) {
      int total = 0;
      for (int d = 0; d < static_cast<int>(cells[static_cast<size_t>(t)].size()); ++d)
        total += cells[static_cast<size_t>(t)][static_cast<size_t>(d)];
      for (int d = 0; d < n && d < static_cast<int>(cells[static_cast<size_t>(t)].size()); ++d) {
        const int count = cells[static_cast<size_t>(t)][static_cast<size_t>(d)];
        // Colour: the share of the labelled class's frames (recall).
        map->data()->setCell(d, t, total > 0 ? static_cast<double>(count) / total : 0.0);
        if (count == 0) continue;
        auto* text = new QCPItemText(p);
        text->setClipAxisRect(rect);
        text->position->setAxes(x, y);
        text->position->setCoords(d, t);
        text->setFont(small);
        text->setText(QString::number(count));
        text->setColor(total > 0 && count * 2 > total ? Qt::white : Qt::black);
      }
    }
    QCPColorGradient gradient(QCPColorGradient::gpGrayscale);
    gradient.setColorStopAt(0.0, QColor(250, 250, 250));
    gradient.setColorStopAt(1.0, QColor(30, 60, 140));
    map->setGradient(gradient);
    map->setDataRange(QCPRange(0, 1));
    map->setInterpolate(false);
  }
  p->replot();
}

int PhasingView::HistogramTotal(int type, int component) const {
  return totals_.at(static_cast<size_t>(type)).at(static_cast<size_t>(component));
}

int PhasingView::ConfusionCell(int which, int truth, int decided) const {
  const auto& cells = cells_.at(static_cast<size_t>(which));
  if (truth < 0 || truth >= static_cast<int>(cells.size())) return -1;
  const auto& row = cells[static_cast<size_t>(truth)];
  if (decided < 0 || decided >= static_cast<int>(row.size())) return -1;
  return row[static_cast<size_t>(decided)];
}

void PhasingView::ExportPhasing(const QString& path, int width, int height) {
  ExportFigure(phasing_plot_, path, width > 0 ? width : std::max(phasing_plot_->width(), 1000),
               height > 0 ? height : std::max(phasing_plot_->height(), 700));
}

void PhasingView::ExportConfusion(const QString& path, int width, int height) {
  ExportFigure(confusion_plot_, path, width > 0 ? width : std::max(confusion_plot_->width(), 1000),
               height > 0 ? height : std::max(confusion_plot_->height(), 520));
}

}  // namespace csw::gui
