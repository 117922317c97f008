#include "workbench/gui/marker_view.h"

#include <QMouseEvent>
#include <QPainter>
#include <QPainterPath>
#include <QWheelEvent>
#include <algorithm>
#include <cmath>
#include <numbers>

namespace csw::gui {

namespace {

using Vec = std::array<double, 3>;

Vec Sub(const Vec& a, const Vec& b) { return {a[0] - b[0], a[1] - b[1], a[2] - b[2]}; }
Vec Add(const Vec& a, const Vec& b) { return {a[0] + b[0], a[1] + b[1], a[2] + b[2]}; }
Vec Scale(const Vec& a, double s) { return {a[0] * s, a[1] * s, a[2] * s}; }
double Dot(const Vec& a, const Vec& b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
Vec Cross(const Vec& a, const Vec& b) {
  return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
double Norm(const Vec& a) { return std::sqrt(Dot(a, a)); }
Vec Unit(const Vec& a) {
  double n = Norm(a);
  return n > 0 ? Scale(a, 1.0 / n) : Vec{0, 0, 0};
}
double Rad(double deg) { return deg * std::numbers::pi / 180.0; }

// The camera's basis: eye position, right, up and forward unit vectors.
struct Basis {
  Vec eye, right, up, forward;
};

Basis CameraBasis(const Camera& c) {
  Vec up = c.y_up ? Vec{0, 1, 0} : Vec{0, 0, 1};
  double yaw = Rad(c.yaw_deg), pitch = Rad(c.pitch_deg);
  Vec horizontal = c.y_up ? Vec{std::cos(yaw), 0, -std::sin(yaw)} : Vec{std::cos(yaw), std::sin(yaw), 0};
  Vec offset = Add(Scale(horizontal, std::cos(pitch)), Scale(up, std::sin(pitch)));
  Basis b;
  b.eye = Add(c.target, Scale(offset, c.distance_mm));
  b.forward = Scale(offset, -1.0);
  b.right = Unit(Cross(b.forward, up));
  b.up = Cross(b.right, b.forward);
  return b;
}

double PixelsPerMmAtTarget(const Camera& c, QSizeF viewport) {
  return 0.5 * viewport.height() / (c.distance_mm * std::tan(Rad(c.fov_deg) / 2));
}

QColor MarkerColor(bool in_set) { return in_set ? QColor(110, 190, 255) : QColor(210, 210, 210); }

}  // namespace

std::optional<Projected> Project(const Camera& camera, QSizeF viewport, const Vec& p) {
  Basis b = CameraBasis(camera);
  Vec d = Sub(p, b.eye);
  double x = Dot(d, b.right), y = Dot(d, b.up), z = Dot(d, b.forward);
  double scale;
  if (camera.perspective) {
    if (z <= camera.distance_mm * 1e-3) return std::nullopt;
    scale = PixelsPerMmAtTarget(camera, viewport) * camera.distance_mm / z;
  } else {
    scale = PixelsPerMmAtTarget(camera, viewport);
  }
  Projected out;
  out.pos = QPointF(viewport.width() / 2 + x * scale, viewport.height() / 2 - y * scale);
  out.depth = z;
  return out;
}

std::optional<ClusterFrame> ComputeClusterFrame(const MarkerArray& markers, int64_t frame,
                                                const std::vector<int>& columns) {
  std::vector<Vec> pts;
  for (int c : columns) {
    if (c < 0 || c >= markers.markers() || frame < 0 || frame >= markers.frames()) continue;
    if (!markers.Visible(frame, c)) continue;
    const float* p = markers.at(frame, c);
    pts.push_back({p[0], p[1], p[2]});
  }
  if (pts.size() < 3) return std::nullopt;
  ClusterFrame f;
  Vec sum{0, 0, 0};
  for (const Vec& p : pts) sum = Add(sum, p);
  f.origin = Scale(sum, 1.0 / static_cast<double>(pts.size()));
  Vec x = Sub(pts[1], pts[0]);
  Vec z = Cross(x, Sub(pts[2], pts[0]));
  if (Norm(x) < 1e-9 || Norm(z) < 1e-9 * Norm(x) * Norm(x)) return std::nullopt;
  x = Unit(x);
  z = Unit(z);
  f.axes = {x, Cross(z, x), z};
  return f;
}

MarkerView::MarkerView(QWidget* parent) : QWidget(parent) {
  setMinimumSize(200, 150);
  setFocusPolicy(Qt::ClickFocus);
  setAttribute(Qt::WA_OpaquePaintEvent);
  setToolTip(tr("Left-drag: orbit · right/middle-drag or Shift+left: pan · wheel: zoom · click: identify a marker"));
}

void MarkerView::SetTake(std::shared_ptr<const Take> take, const MarkerSet* marker_set) {
  take_ = std::move(take);
  reconstruction_.reset();
  sticks_.clear();
  clusters_.clear();
  cluster_names_.clear();
  in_marker_set_.clear();
  head_columns_.clear();
  face_columns_.clear();
  selected_ = -1;
  frame_ = 0;
  if (take_ && marker_set != nullptr) {
    MarkerBinding binding = BindMarkerSet(*marker_set, take_->marker_names, /*require_all=*/false, take_->name);
    in_marker_set_.assign(take_->marker_names.size(), 0);
    for (const auto& [name, col] : binding.index) in_marker_set_[static_cast<size_t>(col)] = 1;
    for (const auto& [a, b] : marker_set->sticks) {
      auto ia = binding.index.find(a), ib = binding.index.find(b);
      if (ia != binding.index.end() && ib != binding.index.end()) sticks_.emplace_back(ia->second, ib->second);
    }
    auto add_cluster = [&](const std::vector<std::string>& names, const QString& label) {
      std::vector<int> cols;
      for (const auto& n : names) {
        auto it = binding.index.find(n);
        if (it != binding.index.end()) cols.push_back(it->second);
      }
      if (cols.size() >= 3) {
        clusters_.push_back(cols);
        cluster_names_.push_back(label);
      }
    };
    for (const auto& n : marker_set->head_cluster)
      if (auto it = binding.index.find(n); it != binding.index.end()) head_columns_.push_back(it->second);
    for (const auto& n : marker_set->face)
      if (auto it = binding.index.find(n); it != binding.index.end()) face_columns_.push_back(it->second);
    add_cluster(marker_set->head_cluster, tr("head"));
    add_cluster(marker_set->forearm_cluster, tr("forearm"));
  }
  ResetView();
}

void MarkerView::SetFrame(int64_t frame) {
  if (take_ && take_->frames() > 0) frame = std::clamp<int64_t>(frame, 0, take_->frames() - 1);
  if (frame == frame_) return;
  frame_ = frame;
  update();
}

void MarkerView::SetPerspective(bool on) {
  camera_.perspective = on;
  update();
}

void MarkerView::SetYUp(bool on) {
  camera_.y_up = on;
  update();
}

void MarkerView::ResetView() {
  Camera fresh;
  fresh.perspective = camera_.perspective;
  fresh.y_up = camera_.y_up;
  if (take_ && !take_->markers.empty()) {
    const MarkerArray& m = take_->markers;
    Vec lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
    int64_t step = std::max<int64_t>(1, m.frames() / 2000);
    bool any = false;
    for (int64_t f = 0; f < m.frames(); f += step) {
      for (int64_t k = 0; k < m.markers(); ++k) {
        if (!m.Visible(f, k)) continue;
        const float* p = m.at(f, k);
        for (int i = 0; i < 3; ++i) {
          lo[i] = std::min(lo[i], static_cast<double>(p[i]));
          hi[i] = std::max(hi[i], static_cast<double>(p[i]));
        }
        any = true;
      }
    }
    if (any) {
      fresh.target = Scale(Add(lo, hi), 0.5);
      double radius = std::max(10.0, 0.5 * Norm(Sub(hi, lo)));
      fresh.distance_mm = 1.15 * radius / std::sin(Rad(fresh.fov_deg) / 2);
    }
    // Face the talker: the horizontal direction from the head markers' centroid to the face's.
    auto centroid = [&](int64_t f, const std::vector<int>& cols) -> std::optional<Vec> {
      Vec sum{0, 0, 0};
      int n = 0;
      for (int c : cols) {
        if (!m.Visible(f, c)) continue;
        const float* p = m.at(f, c);
        sum = Add(sum, Vec{p[0], p[1], p[2]});
        ++n;
      }
      if (n == 0) return std::nullopt;
      return Scale(sum, 1.0 / n);
    };
    if (!head_columns_.empty() && !face_columns_.empty()) {
      for (int64_t f = 0; f < m.frames(); f += step) {
        auto head = centroid(f, head_columns_), face = centroid(f, face_columns_);
        if (!head || !face) continue;
        Vec d = Sub(*face, *head);
        double yaw = fresh.y_up ? std::atan2(-d[2], d[0]) : std::atan2(d[1], d[0]);
        fresh.yaw_deg = yaw * 180.0 / std::numbers::pi + 30.0;
        fresh.pitch_deg = 10.0;
        break;
      }
    }
  }
  camera_ = fresh;
  update();
}

void MarkerView::Orbit(double dyaw_deg, double dpitch_deg) {
  camera_.yaw_deg = std::fmod(camera_.yaw_deg + dyaw_deg, 360.0);
  camera_.pitch_deg = std::clamp(camera_.pitch_deg + dpitch_deg, -89.0, 89.0);
  update();
}

void MarkerView::Zoom(double factor) {
  if (factor <= 0) return;
  camera_.distance_mm = std::clamp(camera_.distance_mm / factor, 1.0, 1e7);
  update();
}

void MarkerView::Pan(double dx_px, double dy_px) {
  Basis b = CameraBasis(camera_);
  double mm_per_px = 1.0 / PixelsPerMmAtTarget(camera_, QSizeF(size()));
  camera_.target = Add(camera_.target, Add(Scale(b.right, -dx_px * mm_per_px), Scale(b.up, dy_px * mm_per_px)));
  update();
}

void MarkerView::SelectMarker(int marker) {
  if (!take_ || marker < 0 || marker >= take_->markers.markers()) marker = -1;
  selected_ = marker;
  update();
}

void MarkerView::SetReconstruction(std::shared_ptr<const MarkerArray> reconstruction) {
  if (reconstruction && (!take_ || reconstruction->frames() != take_->frames() ||
                         reconstruction->markers() != take_->markers.markers())) {
    reconstruction.reset();
  }
  reconstruction_ = std::move(reconstruction);
  update();
}

std::optional<Projected> MarkerView::ProjectReconstructed(int64_t marker, QSizeF viewport) const {
  if (!reconstruction_ || frame_ >= reconstruction_->frames()) return std::nullopt;
  const float* p = reconstruction_->at(frame_, marker);
  if (IsMissing(p[0])) return std::nullopt;
  return Project(camera_, viewport, {p[0], p[1], p[2]});
}

int MarkerView::DrawnReconstructedCount(bool observed_visible) const {
  if (!take_ || !reconstruction_ || frame_ >= take_->frames()) return 0;
  int n = 0;
  for (int64_t k = 0; k < take_->markers.markers(); ++k) {
    if (take_->markers.Visible(frame_, k) != observed_visible) continue;
    n += ProjectReconstructed(k, QSizeF(size())).has_value();
  }
  return n;
}

std::array<double, 3> MarkerView::Point(int64_t marker) const {
  const float* p = take_->markers.at(frame_, marker);
  return {p[0], p[1], p[2]};
}

QString MarkerView::SelectionText() const {
  if (!take_ || selected_ < 0) return {};
  QString name = QString::fromStdString(take_->marker_names[static_cast<size_t>(selected_)]);
  if (frame_ >= take_->frames() || !take_->markers.Visible(frame_, selected_))
    return tr("%1: missing at frame %2").arg(name).arg(frame_ + take_->first_frame);
  Vec p = Point(selected_);
  return tr("%1: %2, %3, %4 mm").arg(name).arg(p[0], 0, 'f', 2).arg(p[1], 0, 'f', 2).arg(p[2], 0, 'f', 2);
}

int MarkerView::DrawnMarkerCount() const {
  if (!take_ || frame_ >= take_->frames()) return 0;
  int n = 0;
  for (int64_t k = 0; k < take_->markers.markers(); ++k) n += MarkerScreenPos(static_cast<int>(k)).has_value();
  return n;
}

int MarkerView::DrawnStickCount() const {
  if (!take_ || frame_ >= take_->frames()) return 0;
  int n = 0;
  for (const auto& [a, b] : sticks_) n += MarkerScreenPos(a).has_value() && MarkerScreenPos(b).has_value();
  return n;
}

int MarkerView::DrawnClusterFrameCount() const {
  if (!take_ || frame_ >= take_->frames()) return 0;
  int n = 0;
  for (const auto& c : clusters_) n += ComputeClusterFrame(take_->markers, frame_, c).has_value();
  return n;
}

std::optional<QPointF> MarkerView::MarkerScreenPos(int marker) const {
  if (!take_ || marker < 0 || marker >= take_->markers.markers() || frame_ >= take_->frames()) return std::nullopt;
  if (!take_->markers.Visible(frame_, marker)) return std::nullopt;
  auto p = Project(camera_, QSizeF(size()), Point(marker));
  if (!p) return std::nullopt;
  return p->pos;
}

int MarkerView::MarkerAt(QPointF pos, double radius_px) const {
  int best = -1;
  double best_d = radius_px;
  if (!take_) return best;
  for (int64_t k = 0; k < take_->markers.markers(); ++k) {
    auto p = MarkerScreenPos(static_cast<int>(k));
    if (!p) continue;
    double d = std::hypot(p->x() - pos.x(), p->y() - pos.y());
    if (d <= best_d) {
      best_d = d;
      best = static_cast<int>(k);
    }
  }
  return best;
}

void MarkerView::Render(QPainter& painter, QSize size) const {
  QSizeF vp(size);
  painter.fillRect(QRect(QPoint(0, 0), size), QColor(30, 31, 36));
  painter.setRenderHint(QPainter::Antialiasing, true);

  // Lab axes triad in the lower left corner (directions only).
  {
    Camera axes_cam = camera_;
    axes_cam.perspective = false;
    Basis b = CameraBasis(axes_cam);
    QPointF origin(36, size.height() - 36);
    const char* names[3] = {"X", "Y", "Z"};
    const QColor colors[3] = {QColor(230, 80, 80), QColor(90, 200, 90), QColor(90, 140, 255)};
    for (int i = 0; i < 3; ++i) {
      Vec axis{0, 0, 0};
      axis[i] = 1;
      QPointF tip = origin + QPointF(Dot(axis, b.right), -Dot(axis, b.up)) * 24;
      painter.setPen(QPen(colors[i], 2));
      painter.drawLine(origin, tip);
      painter.drawText(tip + QPointF(2, -2), names[i]);
    }
  }

  if (!take_ || take_->frames() == 0) {
    painter.setPen(QColor(180, 180, 180));
    painter.drawText(QRect(QPoint(0, 0), size), Qt::AlignCenter, tr("No take selected"));
    return;
  }
  const MarkerArray& m = take_->markers;
  auto project = [&](int64_t k) -> std::optional<Projected> {
    if (!m.Visible(frame_, k)) return std::nullopt;
    return Project(camera_, vp, Point(k));
  };

  // Sticks.
  painter.setPen(QPen(QColor(150, 150, 160), 1.6));
  for (const auto& [a, b] : sticks_) {
    auto pa = project(a), pb = project(b);
    if (pa && pb) painter.drawLine(pa->pos, pb->pos);
  }

  // Rigid-cluster frames.
  double axis_len = std::max(5.0, 0.06 * camera_.distance_mm);
  for (size_t c = 0; c < clusters_.size(); ++c) {
    auto f = ComputeClusterFrame(m, frame_, clusters_[c]);
    if (!f) continue;
    auto o = Project(camera_, vp, f->origin);
    if (!o) continue;
    const QColor colors[3] = {QColor(230, 80, 80), QColor(90, 200, 90), QColor(90, 140, 255)};
    for (int i = 0; i < 3; ++i) {
      auto tip = Project(camera_, vp, Add(f->origin, Scale(f->axes[static_cast<size_t>(i)], axis_len)));
      if (!tip) continue;
      painter.setPen(QPen(colors[i], 2.2));
      painter.drawLine(o->pos, tip->pos);
    }
    painter.setPen(QColor(220, 220, 220));
    painter.drawText(o->pos + QPointF(4, 12), cluster_names_[c]);
  }

  // Markers, far to near.
  struct Dot2 {
    int64_t k;
    Projected p;
  };
  std::vector<Dot2> dots;
  dots.reserve(static_cast<size_t>(m.markers()));
  for (int64_t k = 0; k < m.markers(); ++k) {
    if (auto p = project(k)) dots.push_back({k, *p});
  }
  std::sort(dots.begin(), dots.end(), [](const Dot2& a, const Dot2& b) { return a.p.depth > b.p.depth; });
  for (const Dot2& d : dots) {
    bool in_set = !in_marker_set_.empty() && in_marker_set_[static_cast<size_t>(d.k)];
    bool selected = d.k == selected_;
    painter.setPen(QPen(QColor(10, 10, 10), 1));
    painter.setBrush(selected ? QColor(255, 220, 60) : MarkerColor(in_set));
    double r = selected ? 6.0 : 4.0;
    painter.drawEllipse(d.p.pos, r, r);
  }
  painter.setBrush(Qt::NoBrush);

  // The model reconstruction: a ring joined to the observed marker where it is
  // seen, a filled diamond where it is missing.
  int reconstructed_visible = 0, reconstructed_missing = 0;
  if (reconstruction_) {
    const QColor ring(80, 230, 140), filled(255, 150, 40);
    for (int64_t k = 0; k < m.markers(); ++k) {
      auto r = ProjectReconstructed(k, vp);
      if (!r) continue;
      if (auto o = project(k)) {
        painter.setPen(QPen(ring, 1.0));
        painter.drawLine(o->pos, r->pos);
        painter.setPen(QPen(ring, 1.6));
        painter.setBrush(Qt::NoBrush);
        painter.drawEllipse(r->pos, 5.5, 5.5);
        ++reconstructed_visible;
      } else {
        const QPointF c = r->pos;
        const double h = 5.5;
        const QPointF diamond[4] = {c + QPointF(0, -h), c + QPointF(h, 0), c + QPointF(0, h), c + QPointF(-h, 0)};
        painter.setPen(QPen(QColor(10, 10, 10), 1));
        painter.setBrush(filled);
        painter.drawPolygon(diamond, 4);
        painter.setBrush(Qt::NoBrush);
        ++reconstructed_missing;
      }
    }
    // Legend, lower right above the projection name.
    const double x = size.width() - 250, y = size.height() - 66;
    painter.setPen(QPen(QColor(10, 10, 10), 1));
    painter.setBrush(MarkerColor(true));
    painter.drawEllipse(QPointF(x, y), 4, 4);
    painter.setBrush(Qt::NoBrush);
    painter.setPen(QPen(ring, 1.6));
    painter.drawEllipse(QPointF(x, y + 16), 5.5, 5.5);
    const QPointF d(x, y + 32);
    const QPointF diamond[4] = {d + QPointF(0, -5.5), d + QPointF(5.5, 0), d + QPointF(0, 5.5), d + QPointF(-5.5, 0)};
    painter.setPen(QPen(QColor(10, 10, 10), 1));
    painter.setBrush(filled);
    painter.drawPolygon(diamond, 4);
    painter.setBrush(Qt::NoBrush);
    painter.setPen(QColor(235, 235, 235));
    painter.drawText(QPointF(x + 12, y + 4), tr("observed"));
    painter.drawText(QPointF(x + 12, y + 20), tr("reconstructed, marker seen (%1)").arg(reconstructed_visible));
    painter.drawText(QPointF(x + 12, y + 36), tr("reconstructed, marker missing (%1)").arg(reconstructed_missing));
  }

  // Heads-up text: take, frame, time, visibility, selection.
  painter.setPen(QColor(235, 235, 235));
  QString hud = tr("%1   frame %2 / %3   t = %4 s   %5 of %6 markers visible")
                    .arg(QString::fromStdString(take_->name))
                    .arg(frame_ + take_->first_frame)
                    .arg(take_->frames() + take_->first_frame - 1)
                    .arg(static_cast<double>(frame_) / take_->rate_hz, 0, 'f', 3)
                    .arg(dots.size())
                    .arg(m.markers());
  painter.drawText(QPointF(8, 18), hud);
  if (selected_ >= 0) {
    painter.setPen(QColor(255, 220, 60));
    painter.drawText(QPointF(8, 36), SelectionText());
    if (auto p = project(selected_)) {
      painter.drawText(p->pos + QPointF(8, -8),
                       QString::fromStdString(take_->marker_names[static_cast<size_t>(selected_)]));
    }
  }
  painter.setPen(QColor(150, 150, 150));
  painter.drawText(QPointF(size.width() - 110, size.height() - 10),
                   camera_.perspective ? tr("perspective") : tr("orthographic"));
}

void MarkerView::paintEvent(QPaintEvent*) {
  QPainter painter(this);
  Render(painter, size());
}

void MarkerView::mousePressEvent(QMouseEvent* event) {
  press_pos_ = last_pos_ = event->position();
  drag_button_ = event->button();
  dragged_ = false;
  event->accept();
}

void MarkerView::mouseMoveEvent(QMouseEvent* event) {
  if (drag_button_ == Qt::NoButton) return;
  QPointF d = event->position() - last_pos_;
  last_pos_ = event->position();
  if ((event->position() - press_pos_).manhattanLength() > 3) dragged_ = true;
  if (!dragged_) return;
  bool pan =
      drag_button_ == Qt::RightButton || drag_button_ == Qt::MiddleButton || (event->modifiers() & Qt::ShiftModifier);
  if (pan) {
    Pan(d.x(), d.y());
  } else {
    Orbit(-0.4 * d.x(), 0.4 * d.y());
  }
}

void MarkerView::mouseReleaseEvent(QMouseEvent* event) {
  if (!dragged_ && drag_button_ == Qt::LeftButton) {
    int k = MarkerAt(event->position());
    SelectMarker(k);
    emit MarkerPicked(k);
  }
  drag_button_ = Qt::NoButton;
  dragged_ = false;
}

void MarkerView::wheelEvent(QWheelEvent* event) {
  Zoom(std::pow(1.0015, event->angleDelta().y()));
  event->accept();
}

}  // namespace csw::gui
