#pragma once
// The 3D view: markers of one frame, sticks and rigid-cluster frames from the
// marker set, orbit / zoom / pan with the mouse, click to identify a marker.
// Drawn with QPainter through an explicit camera (orthographic or perspective),
// so it renders identically on screen, offscreen and into SVG/PDF figures.
#include <QPointF>
#include <QWidget>
#include <array>
#include <memory>
#include <optional>
#include <vector>

#include "core/markerset.h"
#include "core/take.h"

namespace csw::gui {

// Orbit camera around a target point; the lab's vertical is +Z (or +Y).
struct Camera {
  std::array<double, 3> target{0, 0, 0};
  double distance_mm = 2000.0;
  double yaw_deg = -60.0;   // around the vertical axis
  double pitch_deg = 20.0;  // above the horizontal plane
  double fov_deg = 40.0;
  bool perspective = true;
  bool y_up = false;  // lab vertical: +Z (false) or +Y (true)
};

// A point of the lab projected into the widget.
struct Projected {
  QPointF pos;
  double depth = 0.0;  // distance along the viewing direction (mm)
};

// Projects a lab point for a viewport of the given size; nullopt behind the camera.
std::optional<Projected> Project(const Camera& camera, QSizeF viewport, const std::array<double, 3>& p);

// A rigid cluster's frame at one frame: origin at the centroid, x toward the
// second marker, z normal to the plane of the first three.
struct ClusterFrame {
  std::array<double, 3> origin{};
  std::array<std::array<double, 3>, 3> axes{};  // unit x, y, z
};
// nullopt when fewer than three of the cluster's markers are visible or they are collinear.
std::optional<ClusterFrame> ComputeClusterFrame(const MarkerArray& markers, int64_t frame,
                                                const std::vector<int>& columns);

class MarkerView : public QWidget {
  Q_OBJECT

 public:
  explicit MarkerView(QWidget* parent = nullptr);

  // Shows a take (nullptr clears). The marker set, when given, adds sticks and
  // cluster frames for the markers it binds in this take.
  void SetTake(std::shared_ptr<const Take> take, const MarkerSet* marker_set = nullptr);
  void SetFrame(int64_t frame);
  int64_t frame() const { return frame_; }

  // A model reconstruction of the shown take, in the take's column layout (NaN
  // where none; jobs::ModelReconstruction), drawn with the observed markers:
  // observed markers as filled discs, reconstructed ones as rings joined to
  // their observed marker by a line where it is seen (reconstructed-visible),
  // and as filled orange diamonds where it is missing (reconstructed-missing).
  // nullptr clears; cleared by SetTake; ignored when its size does not match.
  void SetReconstruction(std::shared_ptr<const MarkerArray> reconstruction);
  bool has_reconstruction() const { return reconstruction_ != nullptr; }
  // Reconstructed markers drawn at the current frame whose observed marker is
  // visible (observed_visible) or missing.
  int DrawnReconstructedCount(bool observed_visible) const;

  Camera& camera() { return camera_; }
  const Camera& camera() const { return camera_; }
  void SetPerspective(bool on);
  void SetYUp(bool on);
  // Frames the whole take (all frames' visible markers); with a marker set that
  // names head and face markers, the camera looks at the face from 30° to its side.
  void ResetView();
  void Orbit(double dyaw_deg, double dpitch_deg);
  void Zoom(double factor);  // > 1 moves closer
  void Pan(double dx_px, double dy_px);

  // Selection (click or programmatic); -1 = none.
  void SelectMarker(int marker);
  int selected_marker() const { return selected_; }
  // "name: x, y, z mm" of the selected marker at the current frame, or why not.
  QString SelectionText() const;

  // What the current frame shows, for tests and the status bar.
  int DrawnMarkerCount() const;
  int DrawnStickCount() const;
  int DrawnClusterFrameCount() const;
  std::optional<QPointF> MarkerScreenPos(int marker) const;
  // Marker nearest to a widget position within radius_px, or -1.
  int MarkerAt(QPointF pos, double radius_px = 8.0) const;

  // Renders the current frame into any paint device (screen, image, SVG, PDF).
  void Render(QPainter& painter, QSize size) const;

 signals:
  void MarkerPicked(int marker);

 protected:
  void paintEvent(QPaintEvent* event) override;
  void mousePressEvent(QMouseEvent* event) override;
  void mouseMoveEvent(QMouseEvent* event) override;
  void mouseReleaseEvent(QMouseEvent* event) override;
  void wheelEvent(QWheelEvent* event) override;

 private:
  std::array<double, 3> Point(int64_t marker) const;

  std::optional<Projected> ProjectReconstructed(int64_t marker, QSizeF viewport) const;

  std::shared_ptr<const Take> take_;
  std::shared_ptr<const MarkerArray> reconstruction_;
  int64_t frame_ = 0;
  Camera camera_;
  std::vector<std::pair<int, int>> sticks_;  // take columns
  std::vector<std::vector<int>> clusters_;   // take columns per rigid cluster
  std::vector<QString> cluster_names_;
  std::vector<int> head_columns_, face_columns_;  // for facing the talker on ResetView
  std::vector<char> in_marker_set_;               // per column: bound by the marker set
  int selected_ = -1;
  QPointF press_pos_;
  QPointF last_pos_;
  Qt::MouseButton drag_button_ = Qt::NoButton;
  bool dragged_ = false;
};

}  // namespace csw::gui
