#include "workbench/report/analysis_figures.h"

#include <qcustomplot.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "core/error.h"
#include "workbench/report/plot_util.h"

namespace csw::report {

using namespace plot_util;  // NOLINT(build/namespaces): the shared drawing helpers

namespace {

// Ten colours told apart by most readers (the "tab10" qualitative palette).
QColor ClassColour(int i) {
  static const Rgb kPalette[] = {{31, 119, 180}, {255, 127, 14},  {44, 160, 44},   {214, 39, 40},  {148, 103, 189},
                                 {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
  return Colour(kPalette[i % 10]);
}

QCPAxisRect* AddRect(QCustomPlot& plot, int row, QCPMarginGroup* margins) {
  auto* rect = new QCPAxisRect(&plot);
  plot.plotLayout()->addElement(row, 0, rect);
  rect->setMarginGroup(QCP::msLeft | QCP::msRight, margins);
  StyleAxes(rect);
  return rect;
}

QCPGraph* AddGraph(QCustomPlot& plot, QCPAxisRect* rect) {
  return plot.addGraph(rect->axis(QCPAxis::atBottom), rect->axis(QCPAxis::atLeft));
}

// A line in plot coordinates of one axis rect, clipped to it.
QCPItemLine* AddLine(QCustomPlot& plot, QCPAxisRect* rect, double x0, double y0, double x1, double y1,
                     const QPen& pen) {
  auto* line = new QCPItemLine(&plot);
  line->setClipAxisRect(rect);
  line->setClipToAxisRect(true);
  for (QCPItemPosition* p : {line->start, line->end})
    p->setAxes(rect->axis(QCPAxis::atBottom), rect->axis(QCPAxis::atLeft));
  line->start->setCoords(x0, y0);
  line->end->setCoords(x1, y1);
  line->setPen(pen);
  return line;
}

QCPItemText* AddText(QCustomPlot& plot, QCPAxisRect* rect, double x, double y, const QString& text, double points,
                     Qt::Alignment align = Qt::AlignCenter) {
  auto* item = new QCPItemText(&plot);
  item->setClipAxisRect(rect);
  item->setClipToAxisRect(true);
  item->position->setAxes(rect->axis(QCPAxis::atBottom), rect->axis(QCPAxis::atLeft));
  item->position->setCoords(x, y);
  item->setText(text);
  item->setFont(Font(points));
  item->setPositionAlignment(align);
  return item;
}

// Hides a panel's x tick labels (all but the bottom panel share the axis).
void HideTimeLabels(QCPAxisRect* rect) {
  rect->axis(QCPAxis::atBottom)->setTickLabels(false);
  rect->axis(QCPAxis::atBottom)->setLabel(QString());
}

}  // namespace

void SaveGesturalScore(const std::string& path, const std::string& title, const std::vector<float>& audio,
                       double audio_rate_hz, double audio_start_s, const std::vector<PosteriorLane>& lanes,
                       double frame_rate_hz, const std::vector<LabelTier>& tiers, double start_s, double end_s) {
  FigureFormat(Q(path));
  if (!(std::isfinite(start_s) && std::isfinite(end_s) && end_s > start_s))
    throw InvalidInput(path + ": the time range must be finite and end after it starts");
  if (!audio.empty() && !(audio_rate_hz > 0)) throw InvalidInput(path + ": the audio rate must be positive");
  if (!lanes.empty() && !(frame_rate_hz > 0)) throw InvalidInput(path + ": the frame rate must be positive");
  if (audio.empty() && lanes.empty() && tiers.empty()) throw InvalidInput(path + ": nothing to draw");
  for (const PosteriorLane& lane : lanes) {
    if (static_cast<Eigen::Index>(lane.classes.size()) != lane.posteriors.cols())
      throw InvalidInput(path + ": lane " + lane.name + ": " + std::to_string(lane.classes.size()) +
                         " class names for " + std::to_string(lane.posteriors.cols()) + " columns");
    for (Eigen::Index f = 0; f < lane.posteriors.rows(); ++f)
      for (Eigen::Index c = 0; c < lane.posteriors.cols(); ++c) {
        const double p = lane.posteriors(f, c);
        if (!std::isnan(p) && !(p >= -1e-6 && p <= 1 + 1e-6))
          throw InvalidInput(path + ": lane " + lane.name + ": frame " + std::to_string(f) + ": probability " +
                             std::to_string(p) + " outside [0, 1]");
      }
  }
  EnsureGuiApplication();

  const int wave_px = audio.empty() ? 0 : 130;
  const int tier_px = 48, lane_px = 190;
  const int height =
      110 + wave_px + tier_px * static_cast<int>(tiers.size()) + lane_px * static_cast<int>(lanes.size());
  Canvas plot(kFigureWidth, height);
  plot.setAutoAddPlottableToLegend(false);  // each lane has its own legend
  plot.plotLayout()->clear();
  auto* margins = new QCPMarginGroup(&plot);
  std::vector<QCPAxisRect*> rects;
  std::vector<int> stretch;
  int row = 0;

  if (!audio.empty()) {
    QCPAxisRect* rect = AddRect(plot, row++, margins);
    rects.push_back(rect);
    stretch.push_back(wave_px);
    // Min/max envelope per output column, so long recordings stay one pixel thick.
    const int columns = 2000;
    const auto first = static_cast<int64_t>(std::max(0.0, std::floor((start_s - audio_start_s) * audio_rate_hz)));
    const auto last = std::min<int64_t>(static_cast<int64_t>(audio.size()),
                                        static_cast<int64_t>(std::ceil((end_s - audio_start_s) * audio_rate_hz)));
    QVector<double> t, v;
    double peak = 1e-6;
    if (last > first) {
      const int64_t per = std::max<int64_t>(1, (last - first) / columns);
      for (int64_t s = first; s < last; s += per) {
        float lo = audio[static_cast<size_t>(s)], hi = lo;
        for (int64_t k = s; k < std::min(last, s + per); ++k) {
          lo = std::min(lo, audio[static_cast<size_t>(k)]);
          hi = std::max(hi, audio[static_cast<size_t>(k)]);
        }
        const double time = audio_start_s + static_cast<double>(s) / audio_rate_hz;
        t << time << time;
        v << lo << hi;
        peak = std::max({peak, std::abs(static_cast<double>(lo)), std::abs(static_cast<double>(hi))});
      }
    }
    QCPGraph* g = AddGraph(plot, rect);
    g->setData(t, v, true);
    g->setPen(QPen(QColor(60, 60, 60), 1));
    g->setAdaptiveSampling(false);
    rect->axis(QCPAxis::atLeft)->setRange(-peak * 1.05, peak * 1.05);
    rect->axis(QCPAxis::atLeft)->setLabel(QStringLiteral("audio"));
    rect->axis(QCPAxis::atLeft)->setTickLabels(false);
  }

  for (const LabelTier& tier : tiers) {
    QCPAxisRect* rect = AddRect(plot, row++, margins);
    rects.push_back(rect);
    stretch.push_back(tier_px);
    QCPAxis* y = rect->axis(QCPAxis::atLeft);
    y->setRange(0, 1);
    // The tier's name written across, left of the lane (a rotated axis label
    // would not fit a lane this low).
    auto name = QSharedPointer<QCPAxisTickerText>::create();
    name->addTick(0.5, Q(tier.name));
    y->setTicker(name);
    y->setTickLength(0, 0);
    y->setSubTicks(false);
    y->setTickLabelFont(Font(8));
    y->grid()->setVisible(false);
    rect->axis(QCPAxis::atBottom)->grid()->setVisible(false);
    const QPen boundary(QColor(40, 90, 160), 1.2);
    for (const Label& l : tier.labels) {
      if (l.end_s < start_s || l.start_s > end_s) continue;
      if (tier.kind == LabelTier::Kind::kPoint || l.end_s <= l.start_s) {
        AddLine(plot, rect, l.start_s, 0.0, l.start_s, 0.45, QPen(QColor(200, 40, 40), 1.6));
        AddText(plot, rect, l.start_s, 0.72, Q(l.text), 8);
      } else {
        AddLine(plot, rect, l.start_s, 0.0, l.start_s, 1.0, boundary);
        AddLine(plot, rect, l.end_s, 0.0, l.end_s, 1.0, boundary);
        if (!l.text.empty()) AddText(plot, rect, 0.5 * (l.start_s + l.end_s), 0.5, Q(l.text), 8);
      }
    }
  }

  for (const PosteriorLane& lane : lanes) {
    QCPAxisRect* rect = AddRect(plot, row, margins);
    rects.push_back(rect);
    stretch.push_back(lane_px);
    auto* legend = new QCPLegend;
    plot.plotLayout()->addElement(row, 1, legend);
    legend->setLayer(QStringLiteral("legend"));
    legend->setFont(Font(8));
    legend->setBorderPen(Qt::NoPen);
    legend->setBrush(Qt::NoBrush);
    legend->setRowSpacing(-3);
    ++row;
    for (Eigen::Index c = 0; c < lane.posteriors.cols(); ++c) {
      QVector<double> t, p;
      for (Eigen::Index f = 0; f < lane.posteriors.rows(); ++f) {
        const double time = static_cast<double>(f) / frame_rate_hz;
        if (time < start_s - 1.0 / frame_rate_hz || time > end_s + 1.0 / frame_rate_hz) continue;
        t << time;
        p << lane.posteriors(f, c);
      }
      QCPGraph* g = AddGraph(plot, rect);
      g->setData(t, p, true);
      g->setPen(QPen(ClassColour(static_cast<int>(c)), 1.6));
      g->setName(Q(lane.classes[static_cast<size_t>(c)]));
      g->addToLegend(legend);
    }
    rect->axis(QCPAxis::atLeft)->setRange(-0.03, 1.05);
    rect->axis(QCPAxis::atLeft)->setLabel(Q(lane.name + "\nposterior"));
  }

  for (size_t i = 0; i < rects.size(); ++i) {
    rects[i]->axis(QCPAxis::atBottom)->setRange(start_s, end_s);
    if (i + 1 < rects.size()) HideTimeLabels(rects[i]);
    plot.plotLayout()->setRowStretchFactor(static_cast<int>(i), stretch[i]);
    if (i > 0) rects[i]->setMargins(QMargins(0, 0, 0, 0));
  }
  if (!lanes.empty()) plot.plotLayout()->setColumnStretchFactors({1.0, 0.001});
  rects.back()->axis(QCPAxis::atBottom)->setLabel(QStringLiteral("time (s)"));
  for (QCPAxisRect* r : rects) {
    r->setAutoMargins(QCP::msLeft | QCP::msRight | (r == rects.back() ? QCP::msBottom : QCP::msNone) |
                      (r == rects.front() ? QCP::msTop : QCP::msNone));
  }
  plot.plotLayout()->setRowSpacing(2);
  AddHeader(plot, title, nullptr);
  plot.Save(path);
}

void SaveHistograms(const std::string& path, const std::string& title, const std::vector<HistogramPanel>& panels,
                    double bin_ms, const std::string& x_label) {
  FigureFormat(Q(path));
  if (panels.empty()) throw InvalidInput(path + ": no histogram to draw");
  if (!(std::isfinite(bin_ms) && bin_ms > 0)) throw InvalidInput(path + ": the bin width must be a positive number");
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (const HistogramPanel& p : panels) {
    for (double v : p.values_ms) {
      if (std::isinf(v)) throw InvalidInput(path + ": panel " + p.title + ": an infinite value");
      if (std::isnan(v)) continue;
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
    if (std::isfinite(p.reference_ms)) {
      lo = std::min(lo, p.reference_ms);
      hi = std::max(hi, p.reference_ms);
    }
  }
  if (!std::isfinite(lo)) lo = -bin_ms, hi = bin_ms;
  const double first_edge = std::floor(lo / bin_ms) * bin_ms;
  const int bins = std::max(1, static_cast<int>(std::ceil((hi - first_edge) / bin_ms + 1e-9)) + (hi == lo ? 1 : 0));
  EnsureGuiApplication();

  const int n = static_cast<int>(panels.size());
  const int columns = std::min(4, n), rows = (n + columns - 1) / columns;
  Canvas plot(std::max(700, 320 * columns), 90 + 300 * rows);
  plot.plotLayout()->clear();
  auto* grid = new QCPLayoutGrid;
  plot.plotLayout()->addElement(0, 0, grid);
  auto* margins = new QCPMarginGroup(&plot);
  bool any_reference = false;
  QCPGraph* mean_entry = nullptr;
  QCPGraph* reference_entry = nullptr;
  std::string reference_name;
  for (int i = 0; i < n; ++i) {
    const HistogramPanel& p = panels[static_cast<size_t>(i)];
    auto* cell = new QCPLayoutGrid;
    grid->addElement(i / columns, i % columns, cell);
    std::vector<double> values;
    for (double v : p.values_ms)
      if (!std::isnan(v)) values.push_back(v);
    QString head = Q(p.title);
    double mean = std::numeric_limits<double>::quiet_NaN();
    if (!values.empty()) {
      mean = std::accumulate(values.begin(), values.end(), 0.0) / static_cast<double>(values.size());
      double ss = 0;
      for (double v : values) ss += (v - mean) * (v - mean);
      const double sd = values.size() > 1 ? std::sqrt(ss / static_cast<double>(values.size() - 1)) : 0.0;
      head +=
          QStringLiteral("\nn = %1, mean %2 ms, sd %3 ms").arg(values.size()).arg(mean, 0, 'f', 1).arg(sd, 0, 'f', 1);
    } else {
      head += QStringLiteral("\nno data");
    }
    cell->addElement(0, 0, new QCPTextElement(&plot, head, Font(9, true)));
    auto* rect = new QCPAxisRect(&plot);
    cell->addElement(1, 0, rect);
    cell->setRowStretchFactors({0.001, 1});
    rect->setMarginGroup(QCP::msLeft, margins);
    StyleAxes(rect);
    QVector<double> centres(bins), counts(bins, 0.0);
    for (int b = 0; b < bins; ++b) centres[b] = first_edge + (b + 0.5) * bin_ms;
    for (double v : values) {
      const int b = std::clamp(static_cast<int>(std::floor((v - first_edge) / bin_ms)), 0, bins - 1);
      counts[b] += 1;
    }
    auto* bars = new QCPBars(rect->axis(QCPAxis::atBottom), rect->axis(QCPAxis::atLeft));
    bars->setData(centres, counts, true);
    bars->setWidth(bin_ms);
    bars->setBrush(Colour(kTrainingColour).lighter(135));
    bars->setPen(QPen(Colour(kTrainingColour), 1));
    const double top = std::max(1.0, *std::max_element(counts.begin(), counts.end())) * 1.12;
    rect->axis(QCPAxis::atLeft)->setRange(0, top);
    rect->axis(QCPAxis::atLeft)->setLabel(QStringLiteral("count"));
    rect->axis(QCPAxis::atBottom)->setRange(first_edge - bin_ms, first_edge + (bins + 1) * bin_ms);
    rect->axis(QCPAxis::atBottom)->setLabel(Q(x_label));
    // Zero (A1 or the reference instant) as a thin black line.
    AddLine(plot, rect, 0, 0, 0, top, QPen(QColor(0, 0, 0), 1));
    if (std::isfinite(mean)) {
      AddLine(plot, rect, mean, 0, mean, top, QPen(QColor(30, 80, 220), 2));
      if (mean_entry == nullptr) {
        mean_entry = plot.addGraph(rect->axis(QCPAxis::atBottom), rect->axis(QCPAxis::atLeft));
        mean_entry->setPen(QPen(QColor(30, 80, 220), 2));
        mean_entry->setName(QStringLiteral("mean"));
      }
    }
    if (std::isfinite(p.reference_ms)) {
      any_reference = true;
      AddLine(plot, rect, p.reference_ms, 0, p.reference_ms, top, QPen(QColor(215, 40, 40), 2, Qt::DashLine));
      if (reference_entry == nullptr) {
        reference_entry = plot.addGraph(rect->axis(QCPAxis::atBottom), rect->axis(QCPAxis::atLeft));
        reference_entry->setPen(QPen(QColor(215, 40, 40), 2, Qt::DashLine));
        reference_name = p.reference_name.empty() ? "reference" : p.reference_name;
        reference_entry->setName(Q(reference_name));
      }
    }
  }
  if (mean_entry != nullptr || any_reference) {
    // Placed in the layout first: items join only a legend of their own plot.
    auto* legend = new QCPLegend;
    AddHeader(plot, title, legend);
    legend->setLayer(QStringLiteral("legend"));
    if (mean_entry) mean_entry->addToLegend(legend);
    if (reference_entry) reference_entry->addToLegend(legend);
  } else {
    AddHeader(plot, title, nullptr);
  }
  plot.Save(path);
}

void SaveConfusionMatrix(const std::string& path, const std::string& title, const std::vector<std::string>& labels,
                         const std::vector<std::vector<int>>& counts, const std::string& true_axis,
                         const std::string& recognised_axis) {
  FigureFormat(Q(path));
  const int n = static_cast<int>(labels.size());
  if (n == 0) throw InvalidInput(path + ": no classes");
  if (static_cast<int>(counts.size()) != n)
    throw InvalidInput(path + ": " + std::to_string(counts.size()) + " rows for " + std::to_string(n) + " classes");
  for (int i = 0; i < n; ++i) {
    if (static_cast<int>(counts[static_cast<size_t>(i)].size()) != n)
      throw InvalidInput(path + ": row " + labels[static_cast<size_t>(i)] + " has " +
                         std::to_string(counts[static_cast<size_t>(i)].size()) + " columns for " + std::to_string(n) +
                         " classes");
    for (int c : counts[static_cast<size_t>(i)])
      if (c < 0) throw InvalidInput(path + ": row " + labels[static_cast<size_t>(i)] + ": a negative count");
  }
  EnsureGuiApplication();

  const int side = std::clamp(60 * n, 300, 900);
  Canvas plot(side + 260, side + 170);
  QCPAxisRect* rect = plot.axisRect();
  StyleAxes(rect);
  auto* map = new QCPColorMap(plot.xAxis, plot.yAxis);
  map->data()->setSize(n, n);
  map->data()->setRange(QCPRange(0, n - 1), QCPRange(0, n - 1));
  auto ticks_x = QSharedPointer<QCPAxisTickerText>::create();
  auto ticks_y = QSharedPointer<QCPAxisTickerText>::create();
  auto ticks_acc = QSharedPointer<QCPAxisTickerText>::create();
  for (int i = 0; i < n; ++i) {
    const auto& row = counts[static_cast<size_t>(i)];
    const int total = std::accumulate(row.begin(), row.end(), 0);
    const int y = n - 1 - i;  // the first class on top
    for (int j = 0; j < n; ++j) {
      const double fraction = total > 0 ? static_cast<double>(row[static_cast<size_t>(j)]) / total : 0.0;
      map->data()->setCell(j, y, fraction);
      if (row[static_cast<size_t>(j)] > 0) {
        QCPItemText* t = AddText(plot, rect, j, y, QString::number(row[static_cast<size_t>(j)]), n > 10 ? 7 : 9);
        t->setColor(fraction > 0.55 ? QColor(255, 255, 255) : QColor(20, 20, 20));
      }
    }
    ticks_x->addTick(i, Q(labels[static_cast<size_t>(i)]));
    ticks_y->addTick(y, Q(labels[static_cast<size_t>(i)]));
    ticks_acc->addTick(
        y, total > 0
               ? QStringLiteral("%1 % of %2").arg(100.0 * row[static_cast<size_t>(i)] / total, 0, 'f', 1).arg(total)
               : QStringLiteral("none"));
  }
  QCPColorGradient gradient;
  gradient.setColorStopAt(0.0, QColor(255, 255, 255));
  gradient.setColorStopAt(1.0, QColor(20, 50, 140));
  gradient.setLevelCount(64);
  map->setGradient(gradient);
  map->setDataRange(QCPRange(0, 1));
  map->setInterpolate(false);
  plot.xAxis->setTicker(ticks_x);
  plot.yAxis->setTicker(ticks_y);
  plot.yAxis2->setVisible(true);
  plot.yAxis2->setTicker(ticks_acc);
  plot.yAxis2->setTickLabelFont(Font(8));
  plot.yAxis2->setLabel(QStringLiteral("correct (row)"));
  for (QCPAxis* a : {plot.xAxis, plot.yAxis, plot.yAxis2}) {
    a->setRange(-0.5, n - 0.5);
    a->setSubTicks(false);
    a->grid()->setVisible(false);
  }
  plot.xAxis->setLabel(Q(recognised_axis));
  plot.yAxis->setLabel(Q(true_axis));
  AddHeader(plot, title, nullptr);
  plot.Save(path);
}

void SavePlots(const std::string& path, const std::string& title, const std::vector<PlotPanel>& panels, int columns) {
  FigureFormat(Q(path));
  if (panels.empty()) throw InvalidInput(path + ": no panel to draw");
  for (const PlotPanel& p : panels) {
    bool any = false;
    for (const PlotSeries& s : p.series) {
      if (s.x.size() != s.y.size()) {
        throw InvalidInput(path + ": panel '" + p.title + "', series '" + s.name + "': x and y differ in length");
      }
      for (size_t i = 0; i < s.x.size(); ++i) {
        if (std::isinf(s.x[i]) || std::isinf(s.y[i])) {
          throw InvalidInput(path + ": panel '" + p.title + "', series '" + s.name + "': an infinite coordinate");
        }
        any = any || (std::isfinite(s.x[i]) && std::isfinite(s.y[i]));
      }
    }
    if (!any) throw InvalidInput(path + ": panel '" + p.title + "' has no point to draw");
    if (std::isfinite(p.y_min) && std::isfinite(p.y_max) && !(p.y_max > p.y_min)) {
      throw InvalidInput(path + ": panel '" + p.title + "': y_max must be above y_min");
    }
  }
  EnsureGuiApplication();
  const int n = static_cast<int>(panels.size());
  const int cols = columns > 0 ? std::min(columns, n) : std::min(2, n);
  const int rows = (n + cols - 1) / cols;
  Canvas plot(std::max(700, 580 * cols), 90 + 380 * rows);
  plot.plotLayout()->clear();
  auto* grid = new QCPLayoutGrid;
  plot.plotLayout()->addElement(0, 0, grid);
  auto* margins = new QCPMarginGroup(&plot);
  std::vector<std::pair<std::string, QCPGraph*>> legend_entries;
  for (int i = 0; i < n; ++i) {
    const PlotPanel& p = panels[static_cast<size_t>(i)];
    auto* cell = new QCPLayoutGrid;
    grid->addElement(i / cols, i % cols, cell);
    cell->addElement(0, 0, new QCPTextElement(&plot, Q(p.title), Font(9, true)));
    auto* rect = new QCPAxisRect(&plot);
    cell->addElement(1, 0, rect);
    cell->setRowStretchFactors({0.001, 1});
    rect->setMarginGroup(QCP::msLeft, margins);
    StyleAxes(rect);
    double x_lo = std::numeric_limits<double>::infinity(), x_hi = -x_lo, y_lo = x_lo, y_hi = -x_lo;
    for (size_t k = 0; k < p.series.size(); ++k) {
      const PlotSeries& s = p.series[k];
      QVector<double> xs, ys;
      for (size_t j = 0; j < s.x.size(); ++j) {
        xs.push_back(s.x[j]);
        ys.push_back(s.y[j]);
        if (std::isfinite(s.x[j]) && std::isfinite(s.y[j])) {
          x_lo = std::min(x_lo, s.x[j]);
          x_hi = std::max(x_hi, s.x[j]);
          y_lo = std::min(y_lo, s.y[j]);
          y_hi = std::max(y_hi, s.y[j]);
        }
      }
      QCPGraph* g = AddGraph(plot, rect);
      const QColor colour = ClassColour(s.colour >= 0 ? s.colour : static_cast<int>(k));
      if (s.style == PlotSeries::Style::kPoints) {
        g->setLineStyle(QCPGraph::lsNone);
        g->setScatterStyle(QCPScatterStyle(QCPScatterStyle::ssDisc, colour, colour, 5));
        g->setPen(QPen(colour));
      } else {
        g->setPen(QPen(colour, 2, s.style == PlotSeries::Style::kDashed ? Qt::DashLine : Qt::SolidLine));
      }
      g->setData(xs, ys, true);
      g->removeFromLegend();
      if (!s.name.empty() && std::none_of(legend_entries.begin(), legend_entries.end(),
                                          [&](const auto& e) { return e.first == s.name; })) {
        legend_entries.emplace_back(s.name, g);
      }
    }
    const double x_pad = x_hi > x_lo ? 0.03 * (x_hi - x_lo) : 1.0;
    double y_pad = y_hi > y_lo ? 0.08 * (y_hi - y_lo) : 1.0;
    if (std::isfinite(p.y_min) && std::isfinite(p.y_max)) {
      y_lo = p.y_min;
      y_hi = p.y_max;
      y_pad = 0;
    }
    rect->axis(QCPAxis::atBottom)->setRange(x_lo - x_pad, x_hi + x_pad);
    rect->axis(QCPAxis::atLeft)->setRange(y_lo - y_pad, y_hi + y_pad);
    rect->axis(QCPAxis::atBottom)->setLabel(Q(p.x_label));
    rect->axis(QCPAxis::atLeft)->setLabel(Q(p.y_label));
    for (double x : p.vertical_marks) {
      if (std::isfinite(x))
        AddLine(plot, rect, x, y_lo - y_pad, x, y_hi + y_pad, QPen(QColor(120, 120, 120), 1, Qt::DashLine));
    }
  }
  if (!legend_entries.empty()) {
    auto* legend = new QCPLegend;
    AddHeader(plot, title, legend);
    legend->setLayer(QStringLiteral("legend"));
    // More than five entries: rows of four, so that none is cut short.
    if (legend_entries.size() > 5) legend->setWrap(4);
    for (auto& [name, g] : legend_entries) {
      g->setName(Q(name));
      g->addToLegend(legend);
    }
  } else {
    AddHeader(plot, title, nullptr);
  }
  plot.Save(path);
}

}  // namespace csw::report
