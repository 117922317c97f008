#include "workbench/gui/score_lanes.h"

#include <qcustomplot.h>

#include <QVBoxLayout>
#include <algorithm>
#include <cmath>
#include <limits>

#include "workbench/gui/figure_export.h"

namespace csw::gui {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
const char* kCursorLayer = "cursor";

QColor ClassColor(int cls, int classes) {
  // Evenly spaced hues; class 0 (rest) in grey.
  if (cls == 0) return QColor(130, 130, 130);
  return QColor::fromHsv((cls - 1) * 330 / std::max(1, classes - 1), 210, 200);
}

const LabelTier* FindTier(const std::vector<LabelTier>& tiers, const std::string& name) {
  for (const LabelTier& t : tiers)
    if (t.name == name) return &t;
  return nullptr;
}
}  // namespace

ScoreLanes::ScoreLanes(QWidget* parent) : QWidget(parent) {
  setObjectName("scoreLanes");
  auto* layout = new QVBoxLayout(this);
  layout->setContentsMargins(0, 0, 0, 0);
  layout->setSpacing(0);
  const char* names[] = {"shapeLane", "placementLane", "keyTierLane"};
  const int heights[] = {72, 60, 44};
  for (int lane = 0; lane < kLaneCount; ++lane) {
    auto* plot = new QCustomPlot(this);
    plot->setObjectName(names[lane]);
    plot->setMinimumHeight(heights[lane]);
    plot->setMaximumHeight(heights[lane] * 2);
    plot->addLayer(kCursorLayer, nullptr, QCustomPlot::limAbove);
    plot->layer(kCursorLayer)->setMode(QCPLayer::lmBuffered);
    layout->addWidget(plot, lane == kTierLane ? 2 : 3);
    connect(plot, &QCustomPlot::mousePress, this, [this](QMouseEvent* e) { press_pos_ = e->position(); });
    connect(plot, &QCustomPlot::mouseRelease, this, [this, plot](QMouseEvent* e) {
      if ((e->position() - press_pos_).manhattanLength() > 3) return;
      emit TimeClicked(plot->xAxis->pixelToCoord(e->position().x()));
    });
    plots_.push_back(plot);
  }
  Rebuild();
}

void ScoreLanes::AlignWith(QCustomPlot* plot) {
  align_ = plot;
  if (align_ != nullptr) connect(align_, &QCustomPlot::afterReplot, this, &ScoreLanes::UpdateMargins);
}

void ScoreLanes::UpdateMargins() {
  if (align_ == nullptr || align_->axisRectCount() == 0) return;
  const QRect r = align_->axisRect(0)->rect();
  const int left = r.left();
  const int right = std::max(0, align_->width() - r.right() - 1);
  for (QCustomPlot* p : plots_) {
    QCPAxisRect* rect = p->axisRect();
    rect->setAutoMargins(QCP::msTop | QCP::msBottom);
    const QMargins m = rect->margins();
    if (m.left() == left && m.right() == right) continue;
    rect->setMargins(QMargins(left, m.top(), right, m.bottom()));
    p->replot(QCustomPlot::rpQueuedReplot);
  }
}

const ScoreMatrix* ScoreLanes::Matrix(const char* name) const {
  if (!scores_) return nullptr;
  for (const ScoreMatrix& m : scores_->matrices)
    if (m.name == name && m.rows > 0 && m.cols > 0) return &m;
  return nullptr;
}

void ScoreLanes::SetTake(std::optional<TakeScores> scores, const std::vector<LabelTier>& tiers, double duration_s) {
  scores_ = std::move(scores);
  if (scores_ && !(scores_->rate_hz > 0)) scores_.reset();
  duration_s_ = duration_s;
  if (scores_)
    for (const ScoreMatrix& m : scores_->matrices)
      duration_s_ = std::max(duration_s_, scores_->start_s + static_cast<double>(m.rows) / scores_->rate_hz);
  t0_ = 0.0;
  t1_ = duration_s_ > 0 ? duration_s_ : 1.0;
  cursor_t_ = 0.0;
  SetTiers(tiers);  // rebuilds
}

void ScoreLanes::SetTiers(const std::vector<LabelTier>& tiers) {
  decoded_ = LabelTier{};
  expected_ = LabelTier{};
  decoded_name_.clear();
  expected_name_.clear();
  if (const LabelTier* t = FindTier(tiers, kDecodedTier)) {
    decoded_ = *t;
    decoded_name_ = QString::fromStdString(t->name);
  }
  for (const std::string& name : ExpectedTierNames()) {
    if (const LabelTier* t = FindTier(tiers, name)) {
      expected_ = *t;
      expected_name_ = QString::fromStdString(t->name);
      break;
    }
  }
  Rebuild();
}

void ScoreLanes::Rebuild() {
  BuildPosteriorLane(kShapeLane, Matrix(kShapeMatrix), tr("shape"));
  BuildPosteriorLane(kPlacementLane, Matrix(kPlacementMatrix), tr("placement"));
  BuildTierLane();
  cursors_.clear();
  readouts_.clear();
  QFont small = font();
  small.setPointSizeF(std::max(6.0, small.pointSizeF() * 0.85));
  for (QCustomPlot* p : plots_) {
    auto* cursor = new QCPItemStraightLine(p);
    cursor->setLayer(kCursorLayer);
    cursor->setPen(QPen(QColor(220, 30, 30), 1.5));
    cursors_.push_back(cursor);
    auto* readout = new QCPItemText(p);
    readout->setLayer(kCursorLayer);
    readout->position->setType(QCPItemPosition::ptAxisRectRatio);
    readout->position->setCoords(0.005, 0.02);
    readout->setPositionAlignment(Qt::AlignLeft | Qt::AlignTop);
    readout->setFont(small);
    readout->setBrush(QColor(255, 255, 255, 200));
    readout->setPadding(QMargins(3, 1, 3, 1));
    readouts_.push_back(readout);
  }
  const bool posteriors = scores_.has_value();
  const bool tiers = !decoded_name_.isEmpty() || !expected_name_.isEmpty();
  plots_[kShapeLane]->setVisible(posteriors);
  plots_[kPlacementLane]->setVisible(posteriors);
  plots_[kTierLane]->setVisible(posteriors || tiers);
  setVisible(posteriors || tiers);
  UpdateMargins();
  SetTimeRange(t0_, t1_);
  UpdateCursor();
}

void ScoreLanes::BuildPosteriorLane(int lane, const ScoreMatrix* matrix, const QString& title) {
  QCustomPlot* p = plots_[static_cast<size_t>(lane)];
  p->clearItems();
  p->clearGraphs();
  QFont small = font();
  small.setPointSizeF(std::max(6.0, small.pointSizeF() * 0.8));
  p->xAxis->setTickLabels(false);
  p->xAxis->setLabel(QString());
  p->yAxis->setRange(0.0, 1.08);
  p->yAxis->setLabel(title);
  p->yAxis->setLabelFont(small);
  p->yAxis->setTickLabelFont(small);
  p->yAxis->ticker()->setTickCount(2);
  p->legend->clearItems();
  p->legend->setVisible(false);
  if (matrix != nullptr) {
    const auto rows = static_cast<int>(matrix->rows);
    const auto cols = static_cast<int>(matrix->cols);
    for (int c = 0; c < cols; ++c) {
      QCPGraph* g = p->addGraph();
      QVector<QCPGraphData> data(rows);
      for (int r = 0; r < rows; ++r) {
        data[r].key = scores_->start_s + r / scores_->rate_hz;
        data[r].value = matrix->values[static_cast<size_t>(r) * static_cast<size_t>(cols) + static_cast<size_t>(c)];
      }
      g->data()->set(data, /*alreadySorted=*/true);
      g->setPen(QPen(ClassColor(c, cols), 1.0));  // wider pens are stroked: slow on long takes
      const QString name = static_cast<size_t>(c) < matrix->column_names.size()
                               ? QString::fromStdString(matrix->column_names[static_cast<size_t>(c)])
                               : QString::number(c);
      g->setName(name);
    }
    p->legend->setVisible(true);
    p->legend->setFont(small);
    p->legend->setIconSize(12, 6);
    p->legend->setRowSpacing(0);
    p->legend->setColumnSpacing(4);
    p->legend->setFillOrder(QCPLayoutGrid::foColumnsFirst);
    p->legend->setWrap(cols);
    p->legend->setBrush(QColor(255, 255, 255, 190));
    p->axisRect()->insetLayout()->setInsetAlignment(0, Qt::AlignTop | Qt::AlignRight);
  }
  p->replot(QCustomPlot::rpQueuedReplot);
}

void ScoreLanes::BuildTierLane() {
  QCustomPlot* p = plots_[kTierLane];
  p->clearItems();
  p->clearGraphs();
  QFont small = font();
  small.setPointSizeF(std::max(6.0, small.pointSizeF() * 0.8));
  p->yAxis->setRange(0.0, 2.0);
  auto ticker = QSharedPointer<QCPAxisTickerText>::create();
  ticker->addTick(1.5, tr("decoded"));
  ticker->addTick(0.5, tr("expected"));
  p->yAxis->setTicker(ticker);
  p->yAxis->setTickLabelFont(small);
  p->yAxis->setSubTicks(false);
  p->yAxis->grid()->setVisible(false);
  p->xAxis->setTickLabels(true);
  p->xAxis->setTickLabelFont(small);
  p->xAxis->setLabel(QString());
  auto draw = [&](const LabelTier& tier, double y0, QColor fill) {
    for (const Label& l : tier.labels) {
      if (tier.kind == LabelTier::Kind::kInterval) {
        auto* box = new QCPItemRect(p);
        box->topLeft->setCoords(l.start_s, y0 + 0.9);
        box->bottomRight->setCoords(l.end_s, y0 + 0.1);
        box->setPen(QPen(fill.darker(170), 1));
        box->setBrush(l.text.empty() ? Qt::NoBrush : QBrush(fill));
        box->setClipToAxisRect(true);
      } else {
        auto* tick = new QCPItemLine(p);
        tick->start->setCoords(l.start_s, y0 + 0.05);
        tick->end->setCoords(l.start_s, y0 + 0.95);
        tick->setPen(QPen(fill.darker(170), 1.5));
      }
      if (l.text.empty()) continue;
      auto* text = new QCPItemText(p);
      text->position->setCoords(tier.kind == LabelTier::Kind::kInterval ? 0.5 * (l.start_s + l.end_s) : l.start_s,
                                y0 + 0.5);
      text->setPositionAlignment(tier.kind == LabelTier::Kind::kInterval ? Qt::AlignCenter
                                                                         : Qt::AlignLeft | Qt::AlignVCenter);
      text->setText(QString::fromStdString(l.text));
      text->setFont(small);
      text->setClipToAxisRect(true);
    }
  };
  p->setToolTip(tr("decoded: tier %1; expected: tier %2")
                    .arg(decoded_name_.isEmpty() ? tr("(none)") : decoded_name_,
                         expected_name_.isEmpty() ? tr("(none)") : expected_name_));
  draw(decoded_, 1.0, QColor(120, 170, 230, 110));
  draw(expected_, 0.0, QColor(240, 180, 90, 110));
  p->replot(QCustomPlot::rpQueuedReplot);
}

void ScoreLanes::SetTimeRange(double t0, double t1) {
  if (!(t1 > t0)) t1 = t0 + 1e-3;
  t0_ = t0;
  t1_ = t1;
  for (QCustomPlot* p : plots_) {
    p->xAxis->setRange(t0, t1);
    p->replot(QCustomPlot::rpQueuedReplot);
  }
}

void ScoreLanes::SetCursorTime(double t) {
  cursor_t_ = t;
  UpdateCursor();
  for (QCustomPlot* p : plots_) p->layer(kCursorLayer)->replot();
}

void ScoreLanes::UpdateCursor() {
  for (size_t k = 0; k < plots_.size() && k < cursors_.size(); ++k) {
    cursors_[k]->point1->setCoords(cursor_t_, 0);
    cursors_[k]->point2->setCoords(cursor_t_, 1);
    readouts_[k]->setText(Readout(static_cast<int>(k)));
    readouts_[k]->setVisible(!readouts_[k]->text().isEmpty());
  }
}

QString ScoreLanes::Readout(int lane) const {
  if (lane == kTierLane) return {};
  const ScoreMatrix* m = Matrix(lane == kShapeLane ? kShapeMatrix : kPlacementMatrix);
  if (m == nullptr) return {};
  const auto row = static_cast<int64_t>(std::llround((cursor_t_ - scores_->start_s) * scores_->rate_hz));
  const QString name = lane == kShapeLane ? tr("shape") : tr("placement");
  if (row < 0 || row >= m->rows) return QStringLiteral("%1: —").arg(name);
  int best = 0;
  const double* v = m->values.data() + row * m->cols;
  for (int c = 1; c < m->cols; ++c)
    if (v[c] > v[best]) best = c;
  return QStringLiteral("%1: %2 (p = %3)").arg(name).arg(best).arg(v[best], 0, 'f', 2);
}

int ScoreLanes::ClassCount(int lane) const {
  if (lane == kTierLane) return 0;
  return plots_[static_cast<size_t>(lane)]->graphCount();
}

double ScoreLanes::PlottedValue(int lane, int cls, int64_t row) const {
  if (lane == kTierLane || cls < 0 || cls >= ClassCount(lane)) return kNaN;
  QCPGraph* g = plots_[static_cast<size_t>(lane)]->graph(cls);
  if (row < 0 || row >= g->dataCount()) return kNaN;
  return g->data()->at(static_cast<int>(row))->value;
}

double ScoreLanes::PlottedTime(int lane, int64_t row) const {
  if (lane == kTierLane || ClassCount(lane) == 0) return kNaN;
  QCPGraph* g = plots_[static_cast<size_t>(lane)]->graph(0);
  if (row < 0 || row >= g->dataCount()) return kNaN;
  return g->data()->at(static_cast<int>(row))->key;
}

std::vector<Label> ScoreLanes::TierLabels(int row) const { return row == 0 ? decoded_.labels : expected_.labels; }

void ScoreLanes::ExportLane(int lane, const QString& path, int width, int height) {
  QCustomPlot* p = plots_.at(static_cast<size_t>(lane));
  // A lane saved alone carries its own time axis.
  const bool labels = p->xAxis->tickLabels();
  const QString label = p->xAxis->label();
  const bool hidden = p->isHidden();
  p->xAxis->setTickLabels(true);
  p->xAxis->setLabel(tr("time (s)"));
  if (hidden) p->resize(std::max(p->width(), 640), std::max(p->height(), p->minimumHeight()));
  const int w = width > 0 ? width : std::max(p->width(), 640);
  const int h = height > 0 ? height : std::max(p->height() + 40, 160);
  try {
    ExportFigure(p, path, w, h);
  } catch (...) {
    p->xAxis->setTickLabels(labels);
    p->xAxis->setLabel(label);
    p->replot(QCustomPlot::rpQueuedReplot);
    throw;
  }
  p->xAxis->setTickLabels(labels);
  p->xAxis->setLabel(label);
  p->replot(QCustomPlot::rpQueuedReplot);
}

}  // namespace csw::gui
