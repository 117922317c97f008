#include "workbench/report/report.h"

#include <qcustomplot.h>
#include <unistd.h>

#include <QApplication>
#include <QDir>
#include <QFile>
#include <QFontMetrics>
#include <QThread>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>

#include "core/error.h"
#include "workbench/report/figure_file.h"
#include "workbench/report/plot_util.h"

namespace csw::report {

using namespace plot_util;  // NOLINT(build/namespaces): the shared drawing helpers

void EnsureGuiApplication() {
  static std::mutex mutex;
  std::lock_guard lock(mutex);
  if (QCoreApplication* core = QCoreApplication::instance()) {
    if (qobject_cast<QApplication*>(core) == nullptr)
      throw InvalidInput(
          "figures need a QApplication, but the program made a "
          "QCoreApplication");
    if (QThread::currentThread() != core->thread())
      throw InvalidInput("figures must be drawn on the thread that made the QApplication");
    return;
  }
  bool display = !qEnvironmentVariableIsEmpty("DISPLAY") || !qEnvironmentVariableIsEmpty("WAYLAND_DISPLAY");
  QByteArray platform = qgetenv("QT_QPA_PLATFORM");
  bool needs_display = platform.startsWith("xcb") || platform.startsWith("wayland");
  if (platform.isEmpty() || (needs_display && !display)) qputenv("QT_QPA_PLATFORM", "offscreen");
  // Headless runs (CI, ssh) often lack XDG_RUNTIME_DIR; Qt then falls back to
  // /tmp/runtime-<user> with a warning on stderr for every command. Do the same quietly.
  if (qEnvironmentVariableIsEmpty("XDG_RUNTIME_DIR")) {
    const QString dir = QDir::tempPath() + "/runtime-csw-" + QString::number(getuid());
    QDir().mkpath(dir);
    QFile::setPermissions(dir, QFileDevice::ReadOwner | QFileDevice::WriteOwner | QFileDevice::ExeOwner);
    qputenv("XDG_RUNTIME_DIR", dir.toLocal8Bit());
  }
  static int argc = 1;
  static char name[] = "csw";
  static char* argv[] = {name, nullptr};
  // Never destroyed: Qt does not support a QApplication outliving main(), and
  // the process ends right after the CLI's last figure anyway.
  new QApplication(argc, argv);
}

void SaveErrorBars(const std::string& path, const std::string& title, const std::vector<ErrorBar>& bars,
                   double target_mm) {
  FigureFormat(Q(path));
  if (bars.empty()) throw InvalidInput(path + ": no utterances to plot");
  for (const ErrorBar& b : bars) {
    std::string what = path + ": utterance " + b.label + ": error must be a finite number >= 0";
    CheckFinite(b.mean, false, what);
    CheckFinite(b.sd, false, what);
    CheckFinite(b.max, false, what);
  }
  CheckFinite(target_mm, false, path + ": the target error must be a finite number >= 0");
  EnsureGuiApplication();

  Canvas plot(kFigureWidth, kFigureHeight);
  int n = static_cast<int>(bars.size());
  QCPAxis* x = plot.xAxis;
  QCPAxis* y = plot.yAxis;
  StyleAxes(plot.axisRect());

  // Scale: every mean + sd and the target; maxima too unless far above those.
  double base = target_mm;
  double top_max = 0;
  for (const ErrorBar& b : bars) {
    base = std::max(base, b.mean + b.sd);
    top_max = std::max(top_max, b.max);
  }
  if (base <= 0) base = std::max(top_max, 1.0);
  double top = std::min(std::max(top_max, base), 2 * base) * 1.1;

  double bar_width = 0.7;
  double bar_px = (kFigureWidth - 120) * bar_width / n;
  auto make_bars = [&](const QString& name, Rgb c) {
    auto* b = new QCPBars(x, y);
    b->setName(name);
    b->setWidth(bar_width);
    b->setBrush(Colour(c));
    // Outlines only while bars are wide enough for them not to blacken the figure.
    b->setPen(bar_px >= 10 ? QPen(Colour(c).darker(130), 1) : QPen(Qt::NoPen));
    b->setAntialiased(false);
    b->setAntialiasedFill(false);
    auto* e = new QCPErrorBars(x, y);
    e->removeFromLegend();
    e->setDataPlottable(b);
    e->setPen(QPen(QColor(30, 30, 30), 1.2));
    e->setSymbolGap(0);
    return std::make_pair(b, e);
  };
  auto [train, train_err] = make_bars(QStringLiteral("training"), kTrainingColour);
  auto [held, held_err] = make_bars(QStringLiteral("held out"), kHeldOutColour);
  auto* maxima = new QCPGraph(x, y);
  maxima->setName(QStringLiteral("maximum"));
  maxima->setLineStyle(QCPGraph::lsNone);
  maxima->setScatterStyle(QCPScatterStyle(QCPScatterStyle::ssCross, QPen(QColor(70, 70, 70), 1.3), Qt::NoBrush, 7));
  auto* off_scale = new QCPGraph(x, y);
  off_scale->setName(QStringLiteral("maximum off the scale"));
  off_scale->setLineStyle(QCPGraph::lsNone);
  off_scale->setScatterStyle(
      QCPScatterStyle(QCPScatterStyle::ssTriangle, QPen(QColor(70, 70, 70), 1.3), QBrush(QColor(70, 70, 70)), 8));

  QVector<double> train_minus, train_plus, held_minus, held_plus;
  std::vector<QString> labels;
  for (int i = 0; i < n; ++i) {
    const ErrorBar& b = bars[static_cast<size_t>(i)];
    (b.held_out ? held : train)->addData(i, b.mean);
    // Errors are not negative: the lower whisker stops at 0.
    (b.held_out ? held_minus : train_minus).push_back(std::min(b.sd, b.mean));
    (b.held_out ? held_plus : train_plus).push_back(b.sd);
    if (b.max <= top) {
      maxima->addData(i, b.max);
    } else {
      off_scale->addData(i, top * 0.975);
    }
    labels.push_back(Elide(b.label, Font(9)));
  }
  train_err->setData(train_minus, train_plus);
  held_err->setData(held_minus, held_plus);
  // Whiskers about half a bar wide, within limits.
  train_err->setWhiskerWidth(std::clamp(bar_px * 0.5, 2.0, 14.0));
  held_err->setWhiskerWidth(std::clamp(bar_px * 0.5, 2.0, 14.0));
  if (train->data()->isEmpty()) train->removeFromLegend();
  if (held->data()->isEmpty()) held->removeFromLegend();
  if (off_scale->data()->isEmpty()) off_scale->removeFromLegend();

  if (target_mm > 0) {
    auto* target = new QCPGraph(x, y);
    target->setName(QStringLiteral("target %1 mm").arg(target_mm, 0, 'g', 3));
    target->setPen(QPen(QColor(20, 20, 20), 1.5, Qt::DashLine));
    target->addData(-0.6, target_mm);
    target->addData(n - 0.4, target_mm);
  }

  SetCategoryTicks(x, labels, kFigureWidth - 120);
  y->setRange(0, top);
  y->setLabel(QStringLiteral("mean absolute error (mm)"));
  AddHeader(plot, title, plot.legend);
  plot.Save(path);
}

void SaveVarianceExplained(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                           const std::vector<double>& fractions) {
  FigureFormat(Q(path));
  if (fractions.empty()) throw InvalidInput(path + ": no parameters to plot");
  if (names.size() != fractions.size())
    throw InvalidInput(path + ": " + std::to_string(names.size()) + " parameter names for " +
                       std::to_string(fractions.size()) + " fractions");
  for (size_t i = 0; i < fractions.size(); ++i)
    if (!std::isfinite(fractions[i]) || fractions[i] < 0 || fractions[i] > 1)
      throw InvalidInput(path + ": parameter " + names[i] + ": variance fraction must be within 0..1");
  EnsureGuiApplication();

  Canvas plot(kFigureWidth, kFigureHeight);
  int n = static_cast<int>(fractions.size());
  QCPAxis* x = plot.xAxis;
  QCPAxis* y = plot.yAxis;
  QCPAxis* y2 = plot.yAxis2;
  y2->setVisible(true);
  StyleAxes(plot.axisRect());
  y2->grid()->setVisible(false);

  auto* bars = new QCPBars(x, y);
  bars->setName(QStringLiteral("each parameter (left axis)"));
  bars->setWidth(0.7);
  bars->setBrush(Colour(kTrainingColour));
  bars->setPen(QPen(Colour(kTrainingColour).darker(130), 1));
  bars->setAntialiased(false);
  bars->setAntialiasedFill(false);
  auto* cumulative = new QCPGraph(x, y2);
  cumulative->setName(QStringLiteral("cumulative (right axis)"));
  cumulative->setPen(QPen(QColor(40, 40, 40), 2));
  cumulative->setScatterStyle(
      QCPScatterStyle(QCPScatterStyle::ssCircle, QPen(QColor(40, 40, 40), 1.5), QBrush(Qt::white), 7));

  double sum = 0, largest = 0;
  std::vector<QString> labels;
  for (int i = 0; i < n; ++i) {
    double f = fractions[static_cast<size_t>(i)] * 100;
    sum += f;
    largest = std::max(largest, f);
    bars->addData(i, f);
    cumulative->addData(i, sum);
    labels.push_back(Elide(names[static_cast<size_t>(i)], Font(9)));
  }
  double top = largest > 0 ? largest * 1.15 : 1;
  // Values over the bars while there is room for them.
  if (n <= 24) {
    for (int i = 0; i < n; ++i) {
      auto* text = new QCPItemText(&plot);
      text->setClipToAxisRect(false);
      text->position->setAxes(x, y);
      text->position->setCoords(i, fractions[static_cast<size_t>(i)] * 100);
      text->setPositionAlignment(Qt::AlignHCenter | Qt::AlignBottom);
      text->setPadding(QMargins(0, 0, 0, 3));
      text->setFont(Font(n <= 12 ? 9 : 7));
      text->setColor(Colour(kTrainingColour).darker(150));
      text->setText(QString::number(fractions[static_cast<size_t>(i)] * 100, 'f', 1));
    }
  }
  SetCategoryTicks(x, labels, kFigureWidth - 160);
  y->setRange(0, top);
  y->setLabel(QStringLiteral("variance explained (%)"));
  y2->setRange(0, std::max(100.0, sum) * 1.04);
  y2->setLabel(QStringLiteral("cumulative variance explained (%)"));
  y2->setTickLabels(true);
  AddHeader(plot, title, plot.legend);
  plot.Save(path);
}

std::pair<int, int> ParameterEffectsSize(int parameters) {
  int cols = std::clamp(parameters, 1, 4);
  int rows = (std::max(parameters, 1) + cols - 1) / cols;
  return {std::max(600, cols * 300), 90 + rows * 360};
}

void SaveParameterEffects(const std::string& path, const std::string& title, const Eigen::Matrix3Xd& neutral,
                          const std::vector<ParameterEffect>& effects, const std::vector<std::pair<int, int>>& sticks) {
  FigureFormat(Q(path));
  if (effects.empty()) throw InvalidInput(path + ": no parameters to plot");
  const Eigen::Index m = neutral.cols();
  if (m == 0) throw InvalidInput(path + ": no markers to plot");
  for (const ParameterEffect& e : effects)
    if (e.low.cols() != m || e.high.cols() != m)
      throw InvalidInput(path + ": parameter " + e.name + ": " + std::to_string(e.low.cols()) + " and " +
                         std::to_string(e.high.cols()) + " markers at its extremes, the neutral shape has " +
                         std::to_string(m));
  for (const auto& [a, b] : sticks)
    if (a < 0 || b < 0 || a >= m || b >= m)
      throw InvalidInput(path + ": stick " + std::to_string(a) + "-" + std::to_string(b) +
                         " names a marker outside 0.." + std::to_string(m - 1));

  // One scale for every panel: the box around every finite marker (x, z).
  double x0 = INFINITY, x1 = -INFINITY, z0 = INFINITY, z1 = -INFINITY;
  auto extend = [&](const Eigen::Matrix3Xd& s) {
    for (Eigen::Index k = 0; k < m; ++k)
      if (s.col(k).allFinite()) {
        x0 = std::min(x0, s(0, k));
        x1 = std::max(x1, s(0, k));
        z0 = std::min(z0, s(2, k));
        z1 = std::max(z1, s(2, k));
      }
  };
  extend(neutral);
  for (const ParameterEffect& e : effects) {
    extend(e.low);
    extend(e.high);
  }
  if (!(x0 <= x1)) throw InvalidInput(path + ": no marker has finite coordinates");
  double span = std::max({x1 - x0, z1 - z0, 1.0});
  double pad = 0.06 * span;
  double xc = (x0 + x1) / 2, zc = (z0 + z1) / 2;
  double xspan = x1 - x0 + 2 * pad, zspan = z1 - z0 + 2 * pad;
  EnsureGuiApplication();

  int n = static_cast<int>(effects.size());
  auto [width, height] = ParameterEffectsSize(n);
  int cols = std::clamp(n, 1, 4);
  Canvas plot(width, height);
  QCPLegend* legend = plot.legend;
  plot.axisRect()->insetLayout()->take(legend);
  plot.plotLayout()->clear();
  plot.setAutoAddPlottableToLegend(false);
  auto* grid = new QCPLayoutGrid;
  plot.plotLayout()->addElement(0, 0, grid);
  AddHeader(plot, title, legend);

  struct Style {
    QString name;
    QColor colour;
    double width;
  };
  // The extremes first, the neutral shape over them: what a parameter leaves in
  // place stays grey, what it moves shows in blue and red.
  const Style styles[3] = {{QStringLiteral("low (\u22122 sd)"), Colour(kLowColour), 2.0},
                           {QStringLiteral("high (+2 sd)"), Colour(kHighColour), 2.0},
                           {QStringLiteral("neutral (mean)"), Colour(kNeutralColour), 2.0}};
  std::vector<QCPAxisRect*> rects;
  for (int p = 0; p < n; ++p) {
    const ParameterEffect& e = effects[static_cast<size_t>(p)];
    auto* panel = new QCPLayoutGrid;
    grid->addElement(p / cols, p % cols, panel);
    panel->addElement(0, 0, new QCPTextElement(&plot, Q(e.name), Font(11, true)));
    auto* rect = new QCPAxisRect(&plot);
    panel->addElement(1, 0, rect);
    panel->setRowStretchFactor(0, 0.001);
    panel->setRowSpacing(0);
    // Fixed margins: every panel's plotting area has the same size whatever its tick labels.
    rect->setAutoMargins(QCP::msNone);
    rect->setMargins(QMargins(62, 4, 14, 40));
    StyleAxes(rect);
    QCPAxis* ax = rect->axis(QCPAxis::atBottom);
    QCPAxis* az = rect->axis(QCPAxis::atLeft);
    az->setLabelPadding(2);
    if (p % cols == 0) az->setLabel(QStringLiteral("z (mm)"));
    if (p + cols >= n) ax->setLabel(QStringLiteral("x (mm)"));
    rects.push_back(rect);

    const Eigen::Matrix3Xd* shapes[3] = {&e.low, &e.high, &neutral};
    for (int s = 0; s < 3; ++s) {
      const Eigen::Matrix3Xd& shape = *shapes[s];
      QPen pen(styles[s].colour, styles[s].width);
      QCPScatterStyle dot(QCPScatterStyle::ssDisc, styles[s].colour, 5);
      // Sticks: one curve, broken by NaN between segments (its ends get dots
      // too, which coincide with the markers' dots; the legend shows a stick with a dot).
      auto* lines = new QCPCurve(ax, az);
      lines->setName(styles[s].name);
      lines->setPen(pen);
      lines->setScatterStyle(dot);
      QVector<double> t, xs, zs;
      for (const auto& [a, b] : sticks) {
        if (!shape.col(a).allFinite() || !shape.col(b).allFinite()) continue;
        for (double v : {shape(0, a), shape(0, b), static_cast<double>(NAN)}) xs.push_back(v);
        for (double v : {shape(2, a), shape(2, b), static_cast<double>(NAN)}) zs.push_back(v);
      }
      for (int i = 0; i < xs.size(); ++i) t.push_back(i);
      lines->setData(t, xs, zs);
      auto* dots = new QCPCurve(ax, az);
      dots->setPen(pen);
      dots->setLineStyle(QCPCurve::lsNone);
      dots->setScatterStyle(dot);
      t.clear();
      xs.clear();
      zs.clear();
      for (Eigen::Index k = 0; k < m; ++k)
        if (shape.col(k).allFinite()) {
          t.push_back(static_cast<double>(k));
          xs.push_back(shape(0, k));
          zs.push_back(shape(2, k));
        }
      dots->setData(t, xs, zs);
      if (p == 0) lines->addToLegend(legend);
    }
  }
  // Legend in the order neutral, low, high.
  if (legend->itemCount() == 3) {
    QCPAbstractLegendItem* neutral_item = legend->item(2);
    legend->take(neutral_item);
    legend->simplify();
    legend->insertColumn(0);
    legend->addElement(0, 0, neutral_item);
  }
  // Equal aspect: the same millimetres per pixel across and up, and in every panel.
  plot.Layout();
  QRect area = rects.front()->rect();
  double mm_per_px = std::max(xspan / std::max(area.width(), 1), zspan / std::max(area.height(), 1));
  for (QCPAxisRect* rect : rects) {
    rect->axis(QCPAxis::atBottom)->setRange(xc - area.width() * mm_per_px / 2, xc + area.width() * mm_per_px / 2);
    rect->axis(QCPAxis::atLeft)->setRange(zc - area.height() * mm_per_px / 2, zc + area.height() * mm_per_px / 2);
  }
  plot.Save(path);
}

void SaveGapMap(const std::string& path, const std::string& title, const std::vector<std::string>& names,
                const std::vector<std::vector<std::pair<int64_t, int64_t>>>& gaps, int64_t frames, double rate_hz) {
  FigureFormat(Q(path));
  if (names.empty()) throw InvalidInput(path + ": no markers to plot");
  if (names.size() != gaps.size())
    throw InvalidInput(path + ": " + std::to_string(names.size()) + " marker names for " + std::to_string(gaps.size()) +
                       " gap lists");
  if (frames <= 0 || !(rate_hz > 0)) throw InvalidInput(path + ": frames and rate must be positive");
  for (size_t m = 0; m < gaps.size(); ++m)
    for (const auto& [start, length] : gaps[m])
      if (start < 0 || length <= 0 || start + length > frames)
        throw InvalidInput(path + ": marker " + names[m] + ": gap (" + std::to_string(start) + ", " +
                           std::to_string(length) + ") outside the take's " + std::to_string(frames) + " frames");
  EnsureGuiApplication();

  const int n = static_cast<int>(names.size());
  const int height = std::clamp(170 + 11 * n, 420, 1500);
  Canvas plot(kFigureWidth, height);
  StyleAxes(plot.axisRect());
  const int bins = static_cast<int>(std::min<int64_t>(frames, 1000));
  const double duration = static_cast<double>(frames) / rate_hz;
  auto* map = new QCPColorMap(plot.xAxis, plot.yAxis);
  map->data()->setSize(bins, n);
  map->data()->setRange(QCPRange(0.5 * duration / bins, duration - 0.5 * duration / bins), QCPRange(0, n - 1));
  std::vector<double> missing(static_cast<size_t>(bins));
  for (int m = 0; m < n; ++m) {
    std::fill(missing.begin(), missing.end(), 0.0);
    for (const auto& [start, length] : gaps[static_cast<size_t>(m)]) {
      for (int64_t f = start; f < start + length; ++f) {
        const int b = static_cast<int>(f * bins / frames);
        missing[static_cast<size_t>(b)] += 1.0;
      }
    }
    for (int b = 0; b < bins; ++b) {
      const int64_t lo = static_cast<int64_t>(b) * frames / bins, hi = static_cast<int64_t>(b + 1) * frames / bins;
      const double per_bin = static_cast<double>(std::max<int64_t>(1, hi - lo));
      // Row 0 at the top: the first marker is drawn first, as in the take.
      map->data()->setCell(b, n - 1 - m, missing[static_cast<size_t>(b)] / per_bin);
    }
  }
  QCPColorGradient gradient;
  gradient.setColorStopAt(0.0, QColor(255, 255, 255));
  gradient.setColorStopAt(0.02, QColor(250, 215, 190));
  gradient.setColorStopAt(1.0, QColor(150, 20, 20));
  gradient.setLevelCount(64);
  map->setGradient(gradient);
  map->setDataRange(QCPRange(0, 1));
  map->setInterpolate(false);
  auto* scale = new QCPColorScale(&plot);
  plot.plotLayout()->addElement(0, 1, scale);
  scale->setType(QCPAxis::atRight);
  scale->setDataRange(QCPRange(0, 1));
  scale->setGradient(gradient);
  scale->axis()->setLabel(QStringLiteral("fraction of frames missing"));
  scale->axis()->setTickLabelFont(Font(9));
  scale->axis()->setLabelFont(Font(10));
  map->setColorScale(scale);

  auto ticker = QSharedPointer<QCPAxisTickerText>::create();
  QFontMetrics fm(Font(8));
  const double row_px = static_cast<double>(height - 170) / n;
  const int step = std::max(1, static_cast<int>(std::ceil(fm.height() * 1.05 / std::max(row_px, 1.0))));
  for (int m = 0; m < n; m += step) ticker->addTick(n - 1 - m, Elide(names[static_cast<size_t>(m)], Font(8)));
  plot.yAxis->setTicker(ticker);
  plot.yAxis->setTickLabelFont(Font(8));
  plot.yAxis->setSubTicks(false);
  plot.yAxis->grid()->setVisible(false);
  plot.yAxis->setRange(-0.5, n - 0.5);
  plot.yAxis->setLabel(step == 1 ? QStringLiteral("marker")
                                 : QStringLiteral("marker (one name in %1 shown)").arg(step));
  plot.xAxis->setRange(0, duration);
  plot.xAxis->setLabel(QStringLiteral("time (s)"));
  plot.xAxis->grid()->setVisible(false);
  AddHeader(plot, title, nullptr);
  plot.Save(path);
}

void SaveGapFill(const std::string& path, const std::string& title, const std::vector<double>& time_s,
                 const Eigen::Matrix3Xd& measured, const Eigen::Matrix3Xd& truth, const std::vector<FillSeries>& fills,
                 double gap_start_s, double gap_end_s) {
  FigureFormat(Q(path));
  const Eigen::Index n = static_cast<Eigen::Index>(time_s.size());
  if (n < 2) throw InvalidInput(path + ": fewer than 2 samples to plot");
  if (measured.cols() != n || (truth.cols() != 0 && truth.cols() != n))
    throw InvalidInput(path + ": series and times differ in length");
  for (const FillSeries& f : fills)
    if (f.xyz.cols() != n) throw InvalidInput(path + ": fill '" + f.name + "' and times differ in length");
  EnsureGuiApplication();

  static const Rgb kFillColours[] = {{215, 40, 40}, {30, 80, 220}, {30, 150, 60}, {235, 130, 30}, {140, 60, 170}};
  Canvas plot(kFigureWidth, 900);
  plot.setAutoAddPlottableToLegend(false);
  const char* axis_names[] = {"x (mm)", "y (mm)", "z (mm)"};
  QCPLegend* legend = plot.legend;
  std::vector<QCPAxisRect*> rects;
  for (int c = 0; c < 3; ++c) {
    QCPAxisRect* rect = c == 0 ? plot.axisRect() : new QCPAxisRect(&plot);
    if (c > 0) plot.plotLayout()->addElement(c, 0, rect);
    StyleAxes(rect);
    rects.push_back(rect);
    QCPAxis* x = rect->axis(QCPAxis::atBottom);
    QCPAxis* y = rect->axis(QCPAxis::atLeft);
    y->setLabel(QString::fromLatin1(axis_names[c]));
    if (c == 2) x->setLabel(QStringLiteral("time (s)"));
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    auto track = [&](double v) {
      if (std::isfinite(v)) {
        lo = std::min(lo, v);
        hi = std::max(hi, v);
      }
    };
    if (truth.cols() == n) {
      auto* g = new QCPGraph(x, y);
      g->setPen(QPen(Colour(kNeutralColour), 2.5));
      if (c == 0) {
        g->setName(QStringLiteral("truth (clean capture)"));
        legend->addItem(new QCPPlottableLegendItem(legend, g));
      }
      for (Eigen::Index i = 0; i < n; ++i) {
        g->addData(time_s[static_cast<size_t>(i)], truth(c, i));
        track(truth(c, i));
      }
    }
    for (size_t k = 0; k < fills.size(); ++k) {
      auto* g = new QCPGraph(x, y);
      g->setPen(QPen(Colour(kFillColours[k % std::size(kFillColours)]), 1.8));
      if (c == 0) {
        g->setName(Q(fills[k].name));
        legend->addItem(new QCPPlottableLegendItem(legend, g));
      }
      for (Eigen::Index i = 0; i < n; ++i) {
        const double t = time_s[static_cast<size_t>(i)];
        if (t < gap_start_s - 1e-9 || t > gap_end_s + 1e-9) continue;
        g->addData(t, fills[k].xyz(c, i));
        track(fills[k].xyz(c, i));
      }
    }
    auto* dots = new QCPGraph(x, y);
    dots->setLineStyle(QCPGraph::lsNone);
    dots->setScatterStyle(QCPScatterStyle(QCPScatterStyle::ssDisc, QColor(20, 20, 20), 4));
    if (c == 0) {
      dots->setName(QStringLiteral("measured"));
      legend->addItem(new QCPPlottableLegendItem(legend, dots));
    }
    for (Eigen::Index i = 0; i < n; ++i) {
      if (!std::isfinite(measured(c, i))) continue;
      dots->addData(time_s[static_cast<size_t>(i)], measured(c, i));
      track(measured(c, i));
    }
    if (!std::isfinite(lo)) lo = hi = 0;
    const double pad = std::max(0.5, 0.08 * (hi - lo));
    y->setRange(lo - pad, hi + pad);
    x->setRange(time_s.front(), time_s.back());
    auto* shade = new QCPItemRect(&plot);
    shade->setClipAxisRect(rect);
    shade->topLeft->setAxes(x, y);
    shade->bottomRight->setAxes(x, y);
    shade->topLeft->setCoords(gap_start_s, hi + pad);
    shade->bottomRight->setCoords(gap_end_s, lo - pad);
    shade->setPen(Qt::NoPen);
    shade->setBrush(QColor(120, 120, 120, 28));
    shade->setLayer(QStringLiteral("background"));
  }
  auto* group = new QCPMarginGroup(&plot);
  for (QCPAxisRect* r : rects) r->setMarginGroup(QCP::msLeft | QCP::msRight, group);
  AddHeader(plot, title, legend);
  plot.Save(path);
}

}  // namespace csw::report
