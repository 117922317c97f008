#include "workbench/gui/timeseries_panel.h"

#include <qcustomplot.h>

#include <QVBoxLayout>
#include <algorithm>
#include <cmath>
#include <limits>

namespace csw::gui {

namespace {
constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
const char* kCursorLayer = "cursor";
}  // namespace

QString QuantityName(MarkerQuantity q) {
  switch (q) {
    case MarkerQuantity::kX:
      return QStringLiteral("x");
    case MarkerQuantity::kY:
      return QStringLiteral("y");
    case MarkerQuantity::kZ:
      return QStringLiteral("z");
    case MarkerQuantity::kSpeed:
      return QStringLiteral("speed");
  }
  return {};
}

std::vector<float> MarkerSeries(const Take& take, int marker, MarkerQuantity q) {
  const MarkerArray& m = take.markers;
  std::vector<float> out(static_cast<size_t>(m.frames()), kNaN);
  if (marker < 0 || marker >= m.markers()) return out;
  if (q != MarkerQuantity::kSpeed) {
    int axis = q == MarkerQuantity::kX ? 0 : q == MarkerQuantity::kY ? 1 : 2;
    for (int64_t f = 0; f < m.frames(); ++f) out[static_cast<size_t>(f)] = m.at(f, marker)[axis];
    return out;
  }
  auto distance = [&](int64_t a, int64_t b) -> double {
    if (a < 0 || b >= m.frames() || !m.Visible(a, marker) || !m.Visible(b, marker)) return std::nan("");
    const float* p = m.at(a, marker);
    const float* r = m.at(b, marker);
    return std::sqrt(double(r[0] - p[0]) * (r[0] - p[0]) + double(r[1] - p[1]) * (r[1] - p[1]) +
                     double(r[2] - p[2]) * (r[2] - p[2]));
  };
  for (int64_t f = 0; f < m.frames(); ++f) {
    if (!m.Visible(f, marker)) continue;
    double d = distance(f - 1, f + 1);
    double span = 2.0;
    if (std::isnan(d)) {  // one-sided difference at an end or next to a gap
      d = distance(f, f + 1);
      span = 1.0;
      if (std::isnan(d)) d = distance(f - 1, f);
    }
    if (!std::isnan(d)) out[static_cast<size_t>(f)] = static_cast<float>(d * take.rate_hz / span);
  }
  return out;
}

// Draws a label tier (intervals as boxes with their text, points as ticks)
// clipped to the visible time range; cost grows with the visible labels only.
class TierPlottable : public QCPAbstractPlottable {
 public:
  TierPlottable(QCPAxis* key_axis, QCPAxis* value_axis, LabelTier tier)
      : QCPAbstractPlottable(key_axis, value_axis), tier_(std::move(tier)) {
    std::stable_sort(tier_.labels.begin(), tier_.labels.end(),
                     [](const Label& a, const Label& b) { return a.start_s < b.start_s; });
    // Longest label, so that a visible-window search can start early enough.
    for (const Label& l : tier_.labels) longest_s_ = std::max(longest_s_, l.end_s - l.start_s);
    setSelectable(QCP::stNone);
    setAntialiased(false);  // pixel-aligned boxes and lines: antialiasing only costs time
  }

  const LabelTier& tier() const { return tier_; }

  // The label covering t (intervals) or the last point at or before t.
  const Label* LabelAt(double t) const {
    auto it = std::upper_bound(tier_.labels.begin(), tier_.labels.end(), t,
                               [](double v, const Label& l) { return v < l.start_s; });
    if (it == tier_.labels.begin()) return nullptr;
    const Label& l = *(it - 1);
    if (tier_.kind == LabelTier::Kind::kPoint) return &l;
    return t < l.end_s || (t == l.end_s && it == tier_.labels.end()) ? &l : nullptr;
  }

  double selectTest(const QPointF&, bool, QVariant*) const override { return -1; }
  QCPRange getKeyRange(bool& found, QCP::SignDomain) const override {
    found = !tier_.labels.empty() || tier_.end_s > tier_.start_s;
    return QCPRange(tier_.start_s, std::max(tier_.end_s, tier_.start_s));
  }
  QCPRange getValueRange(bool& found, QCP::SignDomain, const QCPRange&) const override {
    found = true;
    return QCPRange(0, 1);
  }

 protected:
  // Many labels share a pixel when a long take is seen whole: boundary lines
  // closer than a pixel to the last one drawn are skipped, and the boxes of
  // labelled intervals that touch (within a pixel) are filled as one, so the
  // cost grows with the plot's width, not with the labels in view.
  void draw(QCPPainter* painter) override {
    QCPAxis* x = keyAxis();
    if (x == nullptr) return;
    QRect area = clipRect();
    QCPRange range = x->range();
    auto first = std::lower_bound(tier_.labels.begin(), tier_.labels.end(), range.lower - longest_s_,
                                  [](const Label& l, double v) { return l.start_s < v; });
    QFontMetrics metrics(painter->font());
    const bool interval = tier_.kind == LabelTier::Kind::kInterval;
    const QPen boundary_pen(QColor(40, 80, 150), 1);
    const QPen point_pen(QColor(170, 60, 40), 1.5);
    const QColor fill(120, 170, 230, 60);
    double text_right = -1e300;
    double last_line = -1e300;
    double run_x0 = 0, run_x1 = -1e300;  // the filled run not drawn yet (run_x1 < run_x0: none)
    bool have_run = false;
    auto flush_run = [&] {
      if (!have_run) return;
      painter->setPen(Qt::NoPen);
      painter->setBrush(fill);
      painter->drawRect(QRectF(QPointF(run_x0, area.top() + 2), QPointF(run_x1, area.bottom() - 2)));
      have_run = false;
    };
    auto line = [&](double px, const QPen& pen) {
      if (std::abs(px - last_line) < 1.0) return;
      painter->setPen(pen);
      painter->drawLine(QPointF(px, area.top()), QPointF(px, area.bottom()));
      last_line = px;
    };
    // Boxes first (under the lines and texts), then lines and texts.
    if (interval) {
      for (auto it = first; it != tier_.labels.end() && it->start_s <= range.upper; ++it) {
        if (it->end_s < range.lower || it->text.empty()) continue;
        const double x0 = x->coordToPixel(it->start_s), x1 = x->coordToPixel(it->end_s);
        if (have_run && x0 <= run_x1 + 1.0) {
          run_x1 = std::max(run_x1, x1);
          continue;
        }
        flush_run();
        run_x0 = x0;
        run_x1 = x1;
        have_run = true;
      }
      flush_run();
    }
    for (auto it = first; it != tier_.labels.end() && it->start_s <= range.upper; ++it) {
      if (interval && it->end_s < range.lower) continue;
      const double x0 = x->coordToPixel(it->start_s);
      if (interval) {
        const double x1 = x->coordToPixel(it->end_s);
        line(x0, boundary_pen);
        line(x1, boundary_pen);
        QRectF box(QPointF(x0, area.top() + 2), QPointF(x1, area.bottom() - 2));
        if (box.width() > 14 && !it->text.empty()) {
          QString text =
              metrics.elidedText(QString::fromStdString(it->text), Qt::ElideRight, static_cast<int>(box.width()) - 4);
          painter->setPen(QColor(20, 20, 20));
          painter->drawText(box, Qt::AlignCenter, text);
        }
      } else {
        line(x0, point_pen);
        // A point's text only where it does not run into the previous one.
        if (x0 + 3 >= text_right) {
          QString text = QString::fromStdString(it->text);
          const double width = metrics.horizontalAdvance(text);
          painter->setPen(QColor(20, 20, 20));
          painter->drawText(QPointF(x0 + 3, area.center().y() + metrics.ascent() / 2.0), text);
          text_right = x0 + 3 + width + 4;
        }
      }
    }
    painter->setBrush(Qt::NoBrush);
  }
  void drawLegendIcon(QCPPainter*, const QRectF&) const override {}

 private:
  LabelTier tier_;
  double longest_s_ = 0.0;
};

TimeSeriesPanel::TimeSeriesPanel(QWidget* parent) : QWidget(parent) {
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  plot_ = new QCustomPlot(this);
  plot_->setObjectName("timeSeriesPlot");
  plot_->setInteractions(QCP::iRangeDrag | QCP::iRangeZoom);
  plot_->setMinimumHeight(120);
  plot_->addLayer(kCursorLayer, nullptr, QCustomPlot::limAbove);
  plot_->layer(kCursorLayer)->setMode(QCPLayer::lmBuffered);
  plot_->setNoAntialiasingOnDrag(true);
  layout->addWidget(plot_);
  connect(plot_, &QCustomPlot::mousePress, this, [this](QMouseEvent* e) { press_pos_ = e->position(); });
  connect(plot_, &QCustomPlot::mouseRelease, this, [this](QMouseEvent* e) {
    if ((e->position() - press_pos_).manhattanLength() > 3 || lanes_.empty()) return;
    QCPAxis* x = lanes_.front()->rect->axis(QCPAxis::atBottom);
    emit TimeClicked(x->pixelToCoord(e->position().x()));
  });
  Rebuild();
}

TimeSeriesPanel::~TimeSeriesPanel() = default;

std::shared_ptr<const MinMaxPyramid> TimeSeriesPanel::AudioSeries(const Take& take) {
  if (take.audio.samples.empty() || take.audio.channels <= 0) return nullptr;
  // Built once per take (a 10-minute take at 16 kHz has ~10 M samples), shared by rebuilds.
  const Audio& a = take.audio;
  std::vector<float> mono(static_cast<size_t>(a.frames()));
  for (int64_t i = 0; i < a.frames(); ++i) {
    float s = 0;
    for (int c = 0; c < a.channels; ++c) s += a.samples[static_cast<size_t>(i * a.channels + c)];
    mono[static_cast<size_t>(i)] = s / static_cast<float>(a.channels);
  }
  return std::make_shared<const MinMaxPyramid>(std::move(mono), a.rate_hz);
}

std::shared_ptr<const MinMaxPyramid> TimeSeriesPanel::MarkerLaneSeries(const Take& take, int marker, MarkerQuantity q) {
  return std::make_shared<const MinMaxPyramid>(MarkerSeries(take, marker, q), take.rate_hz);
}

TimeSeriesPanel::Prepared TimeSeriesPanel::Shown() const {
  Prepared shown;
  shown.audio = audio_;
  for (const auto& lane : lanes_) {
    if (lane->kind != LaneKind::kMarker || !lane->series) continue;
    shown.marker = marker_;
    shown.quantity = quantity_;
    shown.series = lane->series;
  }
  return shown;
}

void TimeSeriesPanel::SetTake(std::shared_ptr<const Take> take) {
  Prepared prepared;
  if (take) prepared.audio = AudioSeries(*take);
  SetTake(std::move(take), std::move(prepared));
}

void TimeSeriesPanel::SetTake(std::shared_ptr<const Take> take, Prepared prepared) {
  take_ = std::move(take);
  audio_ = take_ ? std::move(prepared.audio) : nullptr;
  prepared_ = take_ ? std::move(prepared) : Prepared();
  prepared_.audio.reset();
  // A prepared marker series is shown at once (one rebuild, not two).
  marker_ = prepared_.series && prepared_.marker < (take_ ? take_->markers.markers() : 0) ? prepared_.marker : -1;
  if (marker_ >= 0) quantity_ = prepared_.quantity;
  cursor_t_ = 0.0;
  Rebuild();
}

void TimeSeriesPanel::SetMarkerSeries(int marker, MarkerQuantity quantity) {
  if (take_ && (marker < 0 || marker >= take_->markers.markers())) marker = -1;
  marker_ = take_ ? marker : -1;
  quantity_ = quantity;
  double t0 = view_start(), t1 = view_end();
  Rebuild();
  SetTimeRange(t0, t1);
}

void TimeSeriesPanel::SetHiddenTier(const QString& name) {
  if (name == hidden_tier_) return;
  hidden_tier_ = name;
  if (!take_) return;
  double t0 = view_start(), t1 = view_end(), cursor = cursor_t_;
  Rebuild();
  SetTimeRange(t0, t1);
  SetCursorTime(cursor);
}

TimeSeriesPanel::Lane& TimeSeriesPanel::AddLane(LaneKind kind, const QString& name, double stretch) {
  auto lane = std::make_unique<Lane>();
  lane->kind = kind;
  lane->name = name;
  int row = static_cast<int>(lanes_.size());
  lane->rect = new QCPAxisRect(plot_, true);
  plot_->plotLayout()->addElement(row, 0, lane->rect);
  plot_->plotLayout()->setRowStretchFactor(row, stretch);
  lane->rect->setMarginGroup(QCP::msLeft | QCP::msRight, margins_);
  lane->rect->setRangeDrag(Qt::Horizontal);
  lane->rect->setRangeZoom(Qt::Horizontal);
  lane->rect->setRangeZoomFactor(0.85);
  lane->rect->setMinimumMargins(QMargins(4, 2, 8, 2));
  lane->rect->setMinimumSize(0, kind == LaneKind::kAudio || kind == LaneKind::kMarker ? 48 : 18);
  lane->rect->axis(QCPAxis::atBottom)->setTickLabels(false);
  QCPAxis* y = lane->rect->axis(QCPAxis::atLeft);
  QFont small = font();
  small.setPointSizeF(std::max(6.0, small.pointSizeF() * 0.85));
  y->setTickLabelFont(small);
  y->ticker()->setTickCount(3);
  y->setLabelFont(small);
  connect(lane->rect->axis(QCPAxis::atBottom), qOverload<const QCPRange&>(&QCPAxis::rangeChanged), this,
          &TimeSeriesPanel::OnRangeChanged);

  lane->cursor = new QCPItemStraightLine(plot_);
  lane->cursor->setLayer(kCursorLayer);
  lane->cursor->setClipAxisRect(lane->rect);
  lane->cursor->setPen(QPen(QColor(220, 30, 30), 1.5));
  for (QCPItemPosition* p : {lane->cursor->point1, lane->cursor->point2}) {
    p->setAxes(lane->rect->axis(QCPAxis::atBottom), lane->rect->axis(QCPAxis::atLeft));
  }
  lane->readout = new QCPItemText(plot_);
  lane->readout->setLayer(kCursorLayer);
  lane->readout->setClipAxisRect(lane->rect);
  lane->readout->position->setType(QCPItemPosition::ptAxisRectRatio);
  lane->readout->position->setAxisRect(lane->rect);
  lane->readout->position->setCoords(0.005, 0.02);
  lane->readout->setPositionAlignment(Qt::AlignLeft | Qt::AlignTop);
  lane->readout->setFont(small);
  lane->readout->setBrush(QColor(255, 255, 255, 200));
  lane->readout->setPadding(QMargins(3, 1, 3, 1));
  lanes_.push_back(std::move(lane));
  return *lanes_.back();
}

void TimeSeriesPanel::Rebuild() {
  syncing_ = true;
  plot_->clearItems();
  plot_->clearPlottables();
  plot_->plotLayout()->clear();
  lanes_.clear();
  delete margins_;
  margins_ = new QCPMarginGroup(plot_);
  duration_s_ = 0.0;

  if (!take_) {
    auto* empty = new QCPTextElement(plot_, tr("Open a corpus and select a take"));
    plot_->plotLayout()->addElement(0, 0, empty);
    syncing_ = false;
    plot_->replot();
    return;
  }
  duration_s_ = std::max(take_->duration_s(), take_->audio.duration_s());
  for (const LabelTier& t : take_->tiers) duration_s_ = std::max(duration_s_, t.end_s);

  if (audio_) {
    Lane& lane = AddLane(LaneKind::kAudio, tr("audio"), 1.2);
    lane.series = audio_;
    lane.graph = plot_->addGraph(lane.rect->axis(QCPAxis::atBottom), lane.rect->axis(QCPAxis::atLeft));
    lane.graph->setPen(QPen(QColor(40, 90, 160), 1));
    lane.graph->setAdaptiveSampling(false);
    lane.graph->setAntialiased(false);  // a min/max envelope per pixel column: antialiasing only costs time
    lane.rect->axis(QCPAxis::atLeft)->setRange(-1.05, 1.05);
    auto ticker = QSharedPointer<QCPAxisTickerFixed>::create();
    ticker->setTickStep(1.0);
    lane.rect->axis(QCPAxis::atLeft)->setTicker(ticker);
  }
  for (const LabelTier& t : take_->tiers) {
    if (!hidden_tier_.isEmpty() && QString::fromStdString(t.name) == hidden_tier_) continue;
    Lane& lane = AddLane(LaneKind::kTier, QString::fromStdString(t.name), 0.5);
    lane.tier = new TierPlottable(lane.rect->axis(QCPAxis::atBottom), lane.rect->axis(QCPAxis::atLeft), t);
    QCPAxis* y = lane.rect->axis(QCPAxis::atLeft);
    y->setRange(0, 1);
    y->setTicks(false);
    y->setTickLabels(false);
  }
  if (!take_->events.empty()) {
    LabelTier events;
    events.name = "events";
    events.kind = LabelTier::Kind::kPoint;
    events.end_s = duration_s_;
    for (const Event& e : take_->events) {
      std::string text = e.context.empty() ? e.label : e.context + " " + e.label;
      events.labels.push_back({e.time_s, e.time_s, text});
    }
    Lane& lane = AddLane(LaneKind::kEvents, tr("events"), 0.45);
    lane.tier = new TierPlottable(lane.rect->axis(QCPAxis::atBottom), lane.rect->axis(QCPAxis::atLeft), events);
    QCPAxis* y = lane.rect->axis(QCPAxis::atLeft);
    y->setRange(0, 1);
    y->setTicks(false);
    y->setTickLabels(false);
  }
  if (marker_ >= 0) {
    QString name = QString::fromStdString(take_->marker_names[static_cast<size_t>(marker_)]);
    Lane& lane = AddLane(LaneKind::kMarker, name + " " + QuantityName(quantity_), 1.4);
    lane.unit = quantity_ == MarkerQuantity::kSpeed ? "mm/s" : "mm";
    lane.series = prepared_.series && prepared_.marker == marker_ && prepared_.quantity == quantity_
                      ? prepared_.series
                      : MarkerLaneSeries(*take_, marker_, quantity_);
    lane.graph = plot_->addGraph(lane.rect->axis(QCPAxis::atBottom), lane.rect->axis(QCPAxis::atLeft));
    // Width 1: a wider pen goes through the raster engine's stroker, ~100x slower on a
    // whole-take min/max envelope (250 ms for one 10-minute lane).
    lane.graph->setPen(QPen(QColor(30, 130, 60), 1));
    lane.graph->setAdaptiveSampling(false);
    lane.graph->setAntialiased(false);  // a min/max envelope per pixel column: antialiasing only costs time
    float lo = kNaN, hi = kNaN;
    for (float v : lane.series->samples()) {
      if (std::isnan(v)) continue;
      lo = std::isnan(lo) ? v : std::min(lo, v);
      hi = std::isnan(hi) ? v : std::max(hi, v);
    }
    if (std::isnan(lo)) lo = 0, hi = 1;
    double pad = std::max(1e-3, 0.06 * (hi - lo));
    lane.rect->axis(QCPAxis::atLeft)->setRange(lo - pad, hi + pad);
    lane.rect->axis(QCPAxis::atLeft)->setLabel(lane.unit);
  }
  if (lanes_.empty()) {
    // A take with neither audio nor tiers still gets a time axis (the capture's span).
    Lane& lane = AddLane(LaneKind::kEvents, tr("events"), 0.45);
    LabelTier none;
    none.kind = LabelTier::Kind::kPoint;
    none.end_s = duration_s_;
    lane.tier = new TierPlottable(lane.rect->axis(QCPAxis::atBottom), lane.rect->axis(QCPAxis::atLeft), none);
    lane.rect->axis(QCPAxis::atLeft)->setTicks(false);
    lane.rect->axis(QCPAxis::atLeft)->setTickLabels(false);
  }
  QCPAxis* bottom = lanes_.back()->rect->axis(QCPAxis::atBottom);
  bottom->setTickLabels(true);
  bottom->setLabel(tr("time (s)"));
  syncing_ = false;
  ShowAll();
}

void TimeSeriesPanel::ShowAll() {
  double end = duration_s_ > 0 ? duration_s_ : 1.0;
  SetTimeRange(0.0, end);
}

double TimeSeriesPanel::view_start() const {
  return lanes_.empty() ? 0.0 : lanes_.front()->rect->axis(QCPAxis::atBottom)->range().lower;
}
double TimeSeriesPanel::view_end() const {
  return lanes_.empty() ? 0.0 : lanes_.front()->rect->axis(QCPAxis::atBottom)->range().upper;
}

void TimeSeriesPanel::SetTimeRange(double t0, double t1) {
  if (lanes_.empty()) return;
  if (!(t1 > t0)) t1 = t0 + 1e-3;
  lanes_.front()->rect->axis(QCPAxis::atBottom)->setRange(t0, t1);  // OnRangeChanged syncs the rest
}

void TimeSeriesPanel::ZoomTime(double factor, double center_t) {
  if (lanes_.empty() || factor <= 0) return;
  double t0 = view_start(), t1 = view_end();
  SetTimeRange(center_t + (t0 - center_t) * factor, center_t + (t1 - center_t) * factor);
}

void TimeSeriesPanel::OnRangeChanged(const QCPRange& range) {
  if (syncing_) return;
  syncing_ = true;
  QCPRange r = range;
  // Never zoom below a few samples of the capture rate, nor beyond ten times the take.
  double min_width = take_ && take_->rate_hz > 0 ? 4.0 / take_->rate_hz : 1e-3;
  if (r.size() < min_width) r = QCPRange(r.center() - min_width / 2, r.center() + min_width / 2);
  double max_width = std::max(1.0, duration_s_ * 10);
  if (r.size() > max_width) r = QCPRange(r.center() - max_width / 2, r.center() + max_width / 2);
  for (auto& lane : lanes_) lane->rect->axis(QCPAxis::atBottom)->setRange(r);
  syncing_ = false;
  Redecimate();
  UpdateCursor();
  plot_->replot(QCustomPlot::rpQueuedReplot);
  emit TimeRangeChanged(r.lower, r.upper);
}

void TimeSeriesPanel::Redecimate() {
  for (auto& lane : lanes_) {
    if (lane->graph == nullptr) continue;
    QCPRange r = lane->rect->axis(QCPAxis::atBottom)->range();
    int columns = std::max(100, lane->rect->width() > 0 ? lane->rect->width() : plot_->width());
    std::vector<MinMaxBin> bins = lane->series->Decimate(r.lower, r.upper, columns);
    QVector<QCPGraphData> data;
    data.reserve(static_cast<int>(bins.size() * 2));
    for (const MinMaxBin& b : bins) {
      data.push_back(QCPGraphData(b.time_s, b.min));
      if (b.max != b.min) data.push_back(QCPGraphData(b.time_s, b.max));
    }
    lane->graph->data()->set(data, /*alreadySorted=*/true);
  }
}

QString TimeSeriesPanel::ReadoutText(const Lane& lane) const {
  switch (lane.kind) {
    case LaneKind::kAudio:
    case LaneKind::kMarker: {
      float v = lane.series->ValueAt(cursor_t_);
      QString value = std::isnan(v) ? tr("missing") : QString::number(v, 'f', lane.kind == LaneKind::kAudio ? 3 : 2);
      return QStringLiteral("%1: %2 %3").arg(lane.name, value, std::isnan(v) ? QString() : lane.unit).trimmed();
    }
    case LaneKind::kTier:
    case LaneKind::kEvents: {
      const Label* l = lane.tier != nullptr ? lane.tier->LabelAt(cursor_t_) : nullptr;
      return QStringLiteral("%1: %2").arg(lane.name, l != nullptr ? QString::fromStdString(l->text) : QString("—"));
    }
  }
  return {};
}

void TimeSeriesPanel::UpdateCursor() {
  for (auto& lane : lanes_) {
    lane->cursor->point1->setCoords(cursor_t_, 0);
    lane->cursor->point2->setCoords(cursor_t_, 1);
    lane->readout->setText(ReadoutText(*lane));
  }
}

void TimeSeriesPanel::SetCursorTime(double t) {
  cursor_t_ = t;
  if (lanes_.empty()) return;
  double t0 = view_start(), t1 = view_end();
  if (t < t0 || t > t1) {
    double w = t1 - t0;
    SetTimeRange(t - 0.1 * w, t + 0.9 * w);  // page so the cursor stays in view
    return;
  }
  UpdateCursor();
  plot_->layer(kCursorLayer)->replot();
}

void TimeSeriesPanel::resizeEvent(QResizeEvent* event) {
  QWidget::resizeEvent(event);
  Redecimate();
}

TimeSeriesPanel::LaneKind TimeSeriesPanel::lane_kind(int lane) const {
  return lanes_.at(static_cast<size_t>(lane))->kind;
}
QString TimeSeriesPanel::lane_name(int lane) const { return lanes_.at(static_cast<size_t>(lane))->name; }
double TimeSeriesPanel::LaneViewStart(int lane) const {
  return lanes_.at(static_cast<size_t>(lane))->rect->axis(QCPAxis::atBottom)->range().lower;
}
double TimeSeriesPanel::LaneViewEnd(int lane) const {
  return lanes_.at(static_cast<size_t>(lane))->rect->axis(QCPAxis::atBottom)->range().upper;
}
double TimeSeriesPanel::LaneCursorTime(int lane) const {
  return lanes_.at(static_cast<size_t>(lane))->cursor->point1->coords().x();
}
QString TimeSeriesPanel::LaneReadout(int lane) const { return lanes_.at(static_cast<size_t>(lane))->readout->text(); }
int TimeSeriesPanel::LanePointCount(int lane) const {
  const Lane& l = *lanes_.at(static_cast<size_t>(lane));
  return l.graph != nullptr ? l.graph->dataCount() : 0;
}

}  // namespace csw::gui
