#include "workbench/gui/error_inspector.h"

#include <qcustomplot.h>

#include <QComboBox>
#include <QFileInfo>
#include <QHBoxLayout>
#include <QHeaderView>
#include <QLabel>
#include <QProgressBar>
#include <QPushButton>
#include <QSplitter>
#include <QTableWidget>
#include <QVBoxLayout>
#include <cmath>
#include <limits>
#include <map>

#include "workbench/gui/job_runner.h"
#include "workbench/gui/log_panel.h"

namespace csw::gui {

using nlohmann::json;

namespace {

double Stat(const json& stats, const char* key) {
  return stats.contains(key) && stats[key].is_number() ? stats[key].get<double>() : std::nan("");
}

// A table cell showing a number with fixed decimals and sorting by its exact
// value (not the rounded text: equal-looking cells keep their true order);
// empty when not finite, sorted below every number.
class NumberItem : public QTableWidgetItem {
 public:
  NumberItem(double v, int decimals)
      : QTableWidgetItem(std::isfinite(v) ? QString::number(v, 'f', decimals) : QString()), value_(v) {
    setTextAlignment(Qt::AlignRight | Qt::AlignVCenter);
  }
  bool operator<(const QTableWidgetItem& other) const override {
    const auto* o = dynamic_cast<const NumberItem*>(&other);
    if (o == nullptr) return QTableWidgetItem::operator<(other);
    return Key(value_) < Key(o->value_);
  }

 private:
  static double Key(double v) { return std::isfinite(v) ? v : -std::numeric_limits<double>::infinity(); }
  double value_;
};

}  // namespace

std::vector<ModelErrors> SummariseInversion(const json& summary, const std::vector<jobs::FrameReport>& frames) {
  std::vector<ModelErrors> out;
  for (const char* kind : {"face", "hand"}) {
    if (!summary.contains(kind)) continue;
    const json& m = summary[kind];
    ModelErrors e;
    e.kind = kind;
    e.target_mm = m.value("target_mm", 0.0);
    // The per-frame reports of this model, by take name.
    std::map<std::string, std::vector<const jobs::FrameReport*>> by_take;
    for (const jobs::FrameReport& r : frames) {
      if (r.model == kind) by_take[r.take].push_back(&r);
    }
    for (const json& t : m["takes"]) {
      UtteranceError u;
      u.take = t["name"].get<std::string>();
      u.spec = t["take"].get<std::string>();
      u.role = t["role"].get<std::string>();
      u.first_frame = t["first_frame"].get<int64_t>();
      u.frames = t["frames"].get<int64_t>();
      const json& v = t["visible"];
      u.samples = v.value("count", int64_t{0});
      u.mean_mm = Stat(v, "mean_mm");
      u.sd_mm = Stat(v, "sd_mm");
      u.max_mm = Stat(v, "max_mm");
      // The worst frame of the range: the largest max visible error (the
      // first of equal ones), as `csw invert` ranks its worst frames.
      for (const jobs::FrameReport* r : by_take[u.take]) {
        if (r->frame < u.first_frame || r->frame >= u.first_frame + u.frames) continue;
        if (!std::isfinite(r->max_error_mm)) continue;
        if (u.worst_frame < 0 || r->max_error_mm > u.worst_frame_error_mm) {
          u.worst_frame = r->frame;
          u.worst_time_s = r->time_s;
          u.worst_frame_error_mm = r->max_error_mm;
          u.worst_marker = r->max_marker;
        }
      }
      e.utterances.push_back(u);
    }
    for (const json& k : m["markers"]) {
      MarkerError me;
      me.marker = k["marker"].get<std::string>();
      me.role = k["role"].get<std::string>();
      const json& v = k["visible"];
      me.count = v.value("count", int64_t{0});
      me.mean_mm = Stat(v, "mean_mm");
      me.sd_mm = Stat(v, "sd_mm");
      me.p99_mm = Stat(v, "p99_mm");
      me.max_mm = Stat(v, "max_mm");
      e.markers.push_back(me);
    }
    out.push_back(std::move(e));
  }
  return out;
}

ErrorInspector::ErrorInspector(LogPanel* log, QWidget* parent) : QWidget(parent), log_(log) {
  setObjectName("errorInspector");
  runner_ = new JobRunner(QStringLiteral("csw-invert"), this);
  recon_runner_ = new JobRunner(QStringLiteral("csw-reconstruct"), this);

  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(2, 2, 2, 2);
  auto* bar = new QHBoxLayout();
  source_ = new QLabel(tr("No model inverted yet (Models ▸ Inspect Reconstruction Errors…)"), this);
  source_->setWordWrap(true);
  model_combo_ = new QComboBox(this);
  model_combo_->setObjectName("errorModelCombo");
  progress_ = new QProgressBar(this);
  progress_->setRange(0, 1000);
  progress_->setMaximumWidth(160);
  progress_->setVisible(false);
  cancel_ = new QPushButton(tr("Cancel"), this);
  cancel_->setObjectName("errorCancelButton");
  cancel_->setVisible(false);
  bar->addWidget(source_, 1);
  bar->addWidget(new QLabel(tr("Model:"), this));
  bar->addWidget(model_combo_);
  bar->addWidget(progress_);
  bar->addWidget(cancel_);
  layout->addLayout(bar);

  auto* split = new QSplitter(Qt::Vertical, this);
  plot_ = new QCustomPlot(split);
  plot_->setObjectName("errorBarsPlot");
  plot_->setMinimumHeight(160);
  plot_->yAxis->setLabel(tr("reconstruction error (mm)"));
  plot_->xAxis->setLabel(tr("utterance (take) — click a bar to see its worst frame"));
  plot_->legend->setVisible(true);
  plot_->legend->setFont(QFont(font().family(), 8));
  plot_->axisRect()->insetLayout()->setInsetAlignment(0, Qt::AlignTop | Qt::AlignRight);
  table_ = new QTableWidget(split);
  table_->setObjectName("markerErrorTable");
  table_->setColumnCount(7);
  table_->setHorizontalHeaderLabels(
      {tr("Marker"), tr("Role"), tr("Mean (mm)"), tr("SD (mm)"), tr("p99 (mm)"), tr("Max (mm)"), tr("Samples")});
  table_->horizontalHeader()->setSectionResizeMode(QHeaderView::ResizeToContents);
  table_->verticalHeader()->setVisible(false);
  table_->setEditTriggers(QAbstractItemView::NoEditTriggers);
  table_->setSelectionBehavior(QAbstractItemView::SelectRows);
  table_->setSortingEnabled(true);
  split->addWidget(plot_);
  split->addWidget(table_);
  split->setStretchFactor(0, 3);
  split->setStretchFactor(1, 2);
  layout->addWidget(split, 1);
  info_ = new QLabel(this);
  info_->setObjectName("errorInfo");
  info_->setWordWrap(true);
  layout->addWidget(info_);

  connect(cancel_, &QPushButton::clicked, this, &ErrorInspector::Cancel);
  connect(model_combo_, qOverload<int>(&QComboBox::activated), this,
          [this](int) { ShowModel(model_combo_->currentData().toString()); });
  connect(plot_, &QCustomPlot::mouseRelease, this, [this](QMouseEvent* event) {
    const int i = BarAt(event->position());
    if (i >= 0) ChooseUtterance(i);
  });
  connect(runner_, &JobRunner::ProgressChanged, this, [this](const QString& stage, double fraction) {
    progress_->setValue(static_cast<int>(std::lround(fraction * 1000)));
    progress_->setFormat(stage + QStringLiteral(" %p%"));
  });
  auto done = [this] {
    progress_->setVisible(false);
    cancel_->setVisible(false);
  };
  connect(runner_, &JobRunner::Succeeded, this, [this, done] {
    done();
    results_ = std::move(pending_);
    pending_.clear();
    skipped_ = pending_skipped_;
    pending_skipped_.clear();
    model_combo_->clear();
    for (const ModelErrors& m : results_)
      model_combo_->addItem(QString::fromStdString(m.kind), QString::fromStdString(m.kind));
    shown_ = results_.empty() ? -1 : 0;
    source_->setText(tr("%1 on %2").arg(QFileInfo(models_).fileName(), QFileInfo(corpus_).fileName()));
    Refresh();
    if (log_ != nullptr) {
      log_->Info(tr("Reconstruction errors of %1 computed on %2").arg(models_, corpus_));
      if (!skipped_.isEmpty()) {
        log_->Warning(tr("Left out of the error inspection (they lack the models' markers): %1")
                          .arg(skipped_.join(QStringLiteral(", "))));
      }
    }
    emit Finished(QStringLiteral("succeeded"));
  });
  connect(runner_, &JobRunner::Canceled, this, [this, done] {
    done();
    if (log_ != nullptr) log_->Info(tr("Error inspection cancelled."));
    emit Finished(QStringLiteral("canceled"));
  });
  connect(runner_, &JobRunner::Failed, this, [this, done](const QString& message) {
    done();
    if (log_ != nullptr) log_->Error(tr("Error inspection failed: %1").arg(message));
    info_->setText(tr("Failed: %1").arg(message));
    emit Finished(QStringLiteral("failed"));
  });
  connect(recon_runner_, &JobRunner::Succeeded, this, [this] {
    reconstruction_ = recon_pending_;
    reconstruction_take_ = QString::fromStdString(recon_running_->name);
    recon_pending_.reset();
    const bool again = recon_request_ != recon_running_;
    recon_running_.reset();
    emit ReconstructionReady(reconstruction_take_);
    if (again) StartReconstruction();
  });
  auto recon_ended = [this] {
    recon_pending_.reset();
    const bool again = recon_request_ && recon_request_ != recon_running_;
    recon_running_.reset();
    if (again) StartReconstruction();
  };
  connect(recon_runner_, &JobRunner::Canceled, this, recon_ended);
  connect(recon_runner_, &JobRunner::Failed, this, [this, recon_ended](const QString& message) {
    if (log_ != nullptr) {
      log_->Warning(tr("No model reconstruction of %1: %2")
                        .arg(QString::fromStdString(recon_running_ ? recon_running_->name : std::string()), message));
    }
    recon_ended();
  });
  Refresh();
}

ErrorInspector::~ErrorInspector() = default;

bool ErrorInspector::Start(const QString& corpus, const QString& models, const QStringList& takes) {
  if (runner_->running()) {
    if (log_ != nullptr) log_->Warning(tr("An error inspection is already running."));
    return false;
  }
  jobs::InvertOptions options;
  options.corpus = corpus.toStdString();
  options.models = models.toStdString();
  options.worst_frames = 0;  // the inspector ranks frames itself from the per-frame reports
  for (const QString& t : takes) options.takes.push_back(t.toStdString());
  options.skip_unbound = takes.isEmpty();
  if (const std::string why = options.Check(); !why.empty()) {
    if (log_ != nullptr) log_->Error(tr("Error inspection not started: %1").arg(QString::fromStdString(why)));
    return false;
  }
  corpus_ = corpus;
  models_ = models;
  pending_.clear();
  const bool started = runner_->Start([this, options](Progress& progress) {
    std::vector<jobs::FrameReport> frames;
    const json summary = jobs::Invert(options, progress, &frames);
    pending_ = SummariseInversion(summary, frames);
    pending_skipped_.clear();
    if (summary.contains("skipped_takes")) {
      for (const json& k : summary["skipped_takes"])
        pending_skipped_ << QString::fromStdString(k["take"].get<std::string>());
    }
  });
  if (!started) return false;
  progress_->setValue(0);
  progress_->setVisible(true);
  cancel_->setVisible(true);
  source_->setText(tr("Inverting %1 on %2…").arg(QFileInfo(models).fileName(), QFileInfo(corpus).fileName()));
  if (log_ != nullptr) log_->Info(tr("Inverting the models of %1 on %2…").arg(models, corpus));
  return true;
}

void ErrorInspector::Cancel() {
  runner_->Cancel();
  recon_runner_->Cancel();
}

bool ErrorInspector::running() const { return runner_->running(); }

bool ErrorInspector::ShowModel(const QString& kind) {
  for (size_t i = 0; i < results_.size(); ++i) {
    if (QString::fromStdString(results_[i].kind) != kind) continue;
    shown_ = static_cast<int>(i);
    model_combo_->setCurrentIndex(model_combo_->findData(kind));
    Refresh();
    return true;
  }
  return false;
}

const ModelErrors* ErrorInspector::shown() const {
  return shown_ >= 0 && shown_ < static_cast<int>(results_.size()) ? &results_[static_cast<size_t>(shown_)] : nullptr;
}

int ErrorInspector::BarCount() const { return shown() ? static_cast<int>(shown()->utterances.size()) : 0; }

std::optional<QPointF> ErrorInspector::BarCenter(int index) const {
  if (index < 0 || index >= BarCount()) return std::nullopt;
  const UtteranceError& u = shown()->utterances[static_cast<size_t>(index)];
  const double y = std::isfinite(u.mean_mm) ? 0.5 * u.mean_mm : 0.0;
  return QPointF(plot_->xAxis->coordToPixel(index + 1.0), plot_->yAxis->coordToPixel(y));
}

int ErrorInspector::BarAt(QPointF plot_pos) const {
  if (BarCount() == 0 || !plot_->axisRect()->rect().contains(plot_pos.toPoint())) return -1;
  const double key = plot_->xAxis->pixelToCoord(plot_pos.x());
  const long i = std::lround(key) - 1;
  if (i < 0 || i >= BarCount() || std::abs(key - static_cast<double>(i + 1)) > 0.4) return -1;
  return static_cast<int>(i);
}

void ErrorInspector::ChooseUtterance(int index) {
  if (index < 0 || index >= BarCount()) return;
  chosen_ = index;
  const UtteranceError& u = shown()->utterances[static_cast<size_t>(index)];
  if (u.worst_frame < 0) {
    info_->setText(tr("%1: no frame with a visible %2 marker")
                       .arg(QString::fromStdString(u.spec), QString::fromStdString(shown()->kind)));
    return;
  }
  info_->setText(tr("%1 (%2): mean %3 ± %4 mm; worst frame at t = %5 s: %6 mm at %7")
                     .arg(QString::fromStdString(u.spec), QString::fromStdString(u.role))
                     .arg(u.mean_mm, 0, 'f', 2)
                     .arg(u.sd_mm, 0, 'f', 2)
                     .arg(u.worst_time_s, 0, 'f', 3)
                     .arg(u.worst_frame_error_mm, 0, 'f', 2)
                     .arg(QString::fromStdString(u.worst_marker)));
  Refresh();
  emit UtteranceChosen(QString::fromStdString(u.take), u.worst_frame);
}

void ErrorInspector::Refresh() {
  plot_->clearPlottables();
  plot_->clearItems();
  table_->setSortingEnabled(false);
  table_->setRowCount(0);
  const ModelErrors* m = shown();
  if (m == nullptr) {
    plot_->xAxis->setRange(0, 1);
    plot_->yAxis->setRange(0, 1);
    plot_->replot();
    return;
  }
  // Figure 3 of the seed: mean ± sd of the error per utterance; training and
  // held-out utterances in two colours; the model's target as a dashed line.
  QCPBars* training = new QCPBars(plot_->xAxis, plot_->yAxis);
  QCPBars* held_out = new QCPBars(plot_->xAxis, plot_->yAxis);
  training->setName(tr("training"));
  held_out->setName(tr("held out"));
  training->setBrush(QColor(70, 120, 200));
  training->setPen(QPen(QColor(40, 70, 130)));
  held_out->setBrush(QColor(230, 140, 50));
  held_out->setPen(QPen(QColor(150, 80, 20)));
  auto* training_err = new QCPErrorBars(plot_->xAxis, plot_->yAxis);
  auto* held_err = new QCPErrorBars(plot_->xAxis, plot_->yAxis);
  training_err->removeFromLegend();
  held_err->removeFromLegend();
  training_err->setPen(QPen(Qt::black));
  held_err->setPen(QPen(Qt::black));
  QVector<double> tk, tv, te, hk, hv, he;
  QSharedPointer<QCPAxisTickerText> ticker(new QCPAxisTickerText);
  double top = m->target_mm;
  const bool many = m->utterances.size() > 24;
  for (size_t i = 0; i < m->utterances.size(); ++i) {
    const UtteranceError& u = m->utterances[i];
    const double key = static_cast<double>(i + 1);
    const double v = std::isfinite(u.mean_mm) ? u.mean_mm : 0.0;
    const double sd = std::isfinite(u.sd_mm) ? u.sd_mm : 0.0;
    (u.role == "held_out" ? hk : tk).push_back(key);
    (u.role == "held_out" ? hv : tv).push_back(v);
    (u.role == "held_out" ? he : te).push_back(sd);
    top = std::max(top, v + sd);
    if (!many || i % ((m->utterances.size() + 23) / 24) == 0) ticker->addTick(key, QString::fromStdString(u.spec));
  }
  training->setData(tk, tv);
  held_out->setData(hk, hv);
  training_err->setDataPlottable(training);
  held_err->setDataPlottable(held_out);
  training_err->setData(te);
  held_err->setData(he);
  if (tk.isEmpty()) training->removeFromLegend();
  if (hk.isEmpty()) held_out->removeFromLegend();
  plot_->xAxis->setTicker(ticker);
  plot_->xAxis->setTickLabelRotation(m->utterances.size() > 6 ? 45 : 0);
  plot_->xAxis->setRange(0.3, static_cast<double>(m->utterances.size()) + 0.7);
  plot_->yAxis->setRange(0, std::max(0.1, 1.15 * top));
  if (m->target_mm > 0) {
    auto* line = new QCPItemStraightLine(plot_);
    line->point1->setCoords(0, m->target_mm);
    line->point2->setCoords(1, m->target_mm);
    line->setPen(QPen(QColor(120, 120, 120), 1, Qt::DashLine));
    auto* label = new QCPItemText(plot_);
    label->position->setCoords(0.35, m->target_mm);
    label->setPositionAlignment(Qt::AlignLeft | Qt::AlignBottom);
    label->setText(tr("target %1 mm").arg(m->target_mm));
    label->setColor(QColor(90, 90, 90));
  }
  if (chosen_ >= 0 && chosen_ < BarCount()) {
    auto* mark = new QCPItemText(plot_);
    const UtteranceError& u = m->utterances[static_cast<size_t>(chosen_)];
    mark->position->setCoords(chosen_ + 1.0,
                              (std::isfinite(u.mean_mm) ? u.mean_mm : 0.0) + (std::isfinite(u.sd_mm) ? u.sd_mm : 0.0));
    mark->setPositionAlignment(Qt::AlignHCenter | Qt::AlignBottom);
    mark->setText(QStringLiteral("▼"));
  }
  plot_->replot();

  table_->setRowCount(static_cast<int>(m->markers.size()));
  for (size_t i = 0; i < m->markers.size(); ++i) {
    const MarkerError& e = m->markers[i];
    const int r = static_cast<int>(i);
    table_->setItem(r, 0, new QTableWidgetItem(QString::fromStdString(e.marker)));
    table_->setItem(r, 1, new QTableWidgetItem(QString::fromStdString(e.role)));
    table_->setItem(r, 2, new NumberItem(e.mean_mm, 2));
    table_->setItem(r, 3, new NumberItem(e.sd_mm, 2));
    table_->setItem(r, 4, new NumberItem(e.p99_mm, 2));
    table_->setItem(r, 5, new NumberItem(e.max_mm, 2));
    table_->setItem(r, 6, new NumberItem(static_cast<double>(e.count), 0));
  }
  table_->setSortingEnabled(true);
  table_->sortByColumn(2, Qt::DescendingOrder);
}

void ErrorInspector::ReconstructTake(std::shared_ptr<const Take> take) {
  recon_request_ = std::move(take);
  if (!recon_request_ || models_.isEmpty()) return;
  if (recon_runner_->running()) {
    recon_runner_->Cancel();  // its end starts the latest request
    return;
  }
  StartReconstruction();
}

void ErrorInspector::StartReconstruction() {
  if (!recon_request_ || models_.isEmpty() || recon_runner_->running()) return;
  recon_running_ = recon_request_;
  auto out = std::make_shared<MarkerArray>();
  recon_pending_ = out;
  jobs::InvertOptions options;
  options.corpus = corpus_.toStdString();
  options.models = models_.toStdString();
  std::shared_ptr<const Take> take = recon_running_;
  const std::string where = options.corpus + ": take '" + take->name + "'";
  recon_runner_->Start([take, options, where, out](Progress& progress) {
    *out = jobs::ModelReconstruction(*take, options, where, progress);
  });
}

}  // namespace csw::gui
