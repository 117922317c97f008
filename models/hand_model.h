#pragma once
// The hand model of the seed (Gibert-Bailly-Elisei §3.2): forearm motion from
// a rigid cluster (nmH); hand markers in the forearm frame; joint angles of
// every hand segment relative to its parent (the forearm for a root segment);
// PCA of the angles (naH parameters); regression from [1, cos, sin] of the
// PCA-predicted angles to the hand marker coordinates (hand_regression.h).
//
// Layout of a model-ordered marker array (see inversion.h): the forearm
// cluster markers, then the hand markers ("shape markers").
//
// Shape coordinates: the shape model (HandShapeModel) predicts, for naH
// parameters, the hand markers in the forearm frame as one vector of
// 3 × hand markers, marker by marker: (x0, y0, z0, x1, y1, z1, …).
//
// Segment frames (HandModel::Angles):
//  - 3 markers: FrameFromMarkers(m0, m1, m2) (joint_angles.h).
//  - more than 3: x from m0 to m1, z the normal of the least-squares plane of
//    all its markers (smallest principal axis), made orthogonal to x and
//    pointing to the side of x × Σ_{j≥2}(m_j − m0) (for 3 markers this is
//    exactly FrameFromMarkers); degenerate when the markers are (nearly)
//    collinear.
//  - 2 markers (a phalanx): only the direction x = m0→m1 is observed; see below.
// Joint angles are taken relative to each segment's REST orientation Q (its
// mean orientation relative to its parent over the training frames, stored in
// HandModel::rest), so that every joint works near zero, far from the Cardan
// gimbal lock at spread = ±90° (a phalanx whose markers run along the finger
// sits at ~90° from a palm frame whose x runs across the knuckles) and
// independent of the forearm cluster's arbitrary axes:
//    angles = JointAnglesFromRotation(Qᵀ · Rparentᵀ · Rsegment)
// (Rparent = identity for a root segment: hand markers are in the forearm frame).
// A 2-marker segment: its direction in Rparent·Q coordinates,
// u = Ry(flexion)·Rz(spread)·e_x, gives flexion and spread; twist is not
// observable and is reported as 0 (a constant column, which the regression
// drops with a warning); its frame is Rparent·Q·Ry(flexion)·Rz(spread), so its
// own children see a twist-free chain. Its rest Q is Ry(f̄)·Rz(s̄) of its mean
// direction. Angles: 3 per segment, in segment order: flexion, spread, twist (radians).
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/take.h"
#include "models/gaussian_fill.h"
#include "models/hand_regression.h"
#include "models/inversion.h"
#include "models/rigid_model.h"

namespace csw {

struct HandSegmentDef {
  std::string name;
  int parent = -1;           // index into HandLayout::segments, -1 = forearm; parents come first
  std::vector<int> markers;  // indices into HandLayout::hand, ≥ 2 (≥ 3 for a root segment)
};

struct HandLayout {
  std::vector<std::string> forearm;  // forearm cluster (≥ 3)
  std::vector<std::string> hand;     // hand markers (every segment marker, plus any others)
  std::vector<HandSegmentDef> segments;

  int num_shape_markers() const { return static_cast<int>(hand.size()); }
  int num_markers() const { return static_cast<int>(forearm.size() + hand.size()); }
};

struct HandModelOptions {
  // naH. The seed retains 12; on the virtual cuer 12 give 1.8/2.1 mm visible
  // error (training/held-out) and 20 give 1.0/1.3 mm (docs/models.md), hence 20.
  int angle_components = 20;
  // true: the angle PCA is weighted by each angle's effect on the markers
  // (w_i = RMS marker displacement per radian of angle i at its mean, from a
  // first regression on the measured angles): the naH directions are those
  // that move the markers most, not those of the largest raw angle variance
  // (a noisy twist of a short phalanx has a large angle variance and little
  // effect). Components are then orthonormalised in angle space and rotated
  // to uncorrelated parameters; variance_explained stays a fraction of the
  // total (unweighted) angle variance. false: the seed's plain angle PCA.
  bool weighted_angle_pca = true;
  double min_distance_mm = 2.0;  // training-frame selection
  // true: also fit HandModel::fill, the Gaussian gap filler of the hand
  // markers in the forearm frame (gaussian_fill.h), by EM on the training
  // frames where at least half the hand markers are seen (complete or not),
  // thinned per take: a frame is kept when a marker seen in it and in the
  // last kept frame has moved by min_distance_mm.
  bool gaussian_fill = true;
  GaussianFillOptions fill;
  HandRegressionOptions regression;  // ridge etc. (documented in hand_regression.h)
  RigidModelOptions forearm;         // forearm cluster fit and motion PCA (nmH)
};

struct HandModel {
  HandLayout layout;
  RigidModel forearm;
  std::vector<std::string> angle_names;  // "<segment>.flexion|spread|twist", 3 per segment
  // Per segment: rest orientation relative to its parent (see above), fitted
  // on the training frames. Empty = identity for every segment.
  std::vector<Eigen::Matrix3d> rest;
  HandShapeModel shape;  // naH params → hand coordinates (forearm frame, 3 × hand markers)
  // Scale of each PCA parameter (its training sd): inversion works on
  // params / scale so that InversionOptions::prior_mm is per unit sd.
  Eigen::VectorXd param_scale;
  // Gap filler for hidden hand markers (empty = none): InvertHand fills the
  // markers missing from a frame with their conditional mean given the seen
  // ones (in the solved forearm frame) instead of the shape model's
  // prediction, which is only weakly tied to a folded finger's hidden segments.
  GaussianFill fill;
  ModelInfo info;
  // Fit-time notes for the user (not stored in the model file), e.g. angle_components
  // beyond the rank of the training angles. The regression's own are in shape.regression.
  std::vector<std::string> warnings;

  int num_parameters() const { return shape.angle_pca.num_parameters(); }
  // Joint angles of one frame's hand markers (forearm frame, 3 × hand markers);
  // NaN angles where a segment's markers are missing or degenerate.
  Eigen::VectorXd Angles(const Eigen::Matrix3Xd& hand_in_forearm) const;
  // Hand markers in the lab for a forearm pose and shape parameters.
  Eigen::Matrix3Xd ShapeMarkersInLab(const RigidTransform& pose, const Eigen::VectorXd& params) const;
  // All model markers (forearm cluster then hand markers) in the lab.
  Eigen::Matrix3Xd MarkersInLab(const RigidTransform& pose, const Eigen::VectorXd& params) const;
};

// "" when the layout is usable, else the reason (parents first, indices in
// range, enough markers, no marker twice in a segment, names unique).
std::string CheckHandLayout(const HandLayout& layout);

// Fits from model-ordered takes: forearm cluster model (FitRigidModel on the
// forearm columns), hand markers in the forearm frame per take, frames with
// every hand marker visible and a valid forearm pose, training-frame
// selection over the hand markers (min_distance_mm), joint angles (frames
// with a degenerate segment dropped), FitHandShapeModel, param_scale; a warning
// when angle_components exceeds the rank of the training angles. Throws InvalidInput on a bad layout (parent
// after child, too few markers, index out of range), a column mismatch, or
// too few usable frames. Progress may cancel.
HandModel FitHandModel(const HandLayout& layout, const std::vector<MarkerArray>& takes,
                       const HandModelOptions& options = {}, Progress* progress = nullptr);

// Per-frame inversion of a model-ordered take (see inversion.h). pose is the
// forearm cluster pose; params the naH parameters (unscaled, as Predict takes them).
// The forearm cluster residuals are weighted by kHandForearmWeight: the
// cluster is rigid to within noise while the hand model misfits by
// millimetres, so unweighted hand residuals would tilt the forearm. (Before
// training_rms_mm meant the inversion's fit, the weight was
// clamp(training_rms_mm / forearm rms, 1, 10), which was 10 on the virtual cuer.)
// A warm start ending with an RMS above 3 · info.training_rms_mm + 1 mm is
// retried from a cold start (Kabsch on the cluster, angles measured on the seen
// hand markers with the missing ones from the gap filler when the model has
// one) and the better kept; a solve still above the threshold is tried again
// from two more starts (itself, continued; the mean posture at the Kabsch
// pose) and the best kept (InversionResult::cold_retry marks all of these).
inline constexpr double kHandForearmWeight = 10.0;
InversionResult InvertHand(const HandModel& model, const MarkerArray& take, const InversionOptions& options = {},
                           Progress* progress = nullptr);

// Temporal correction of the hand markers the Gaussian gap filler filled (the
// filler's counterpart of CorrectGapsWithEdgeResiduals, inversion.h). The
// filler's error for a marker depends on which markers are seen and on the
// posture, both of which change slowly, while the marker itself is seen just
// before and after its gap. For every filled sample (frame g, marker m), the
// filler's misfit is measured at up to 4 visible frames e on each side of m's
// gap WITH g's pattern of seen markers: observed m at e minus the filler's
// prediction of m from e's markers (e's own gaps filled) restricted to those
// seen at g, in the forearm frame. The mean misfit of each side is
// interpolated linearly across the gap (one edge only: fading to zero over
// fade_frames) and added. A marker hidden in one frame next to frames where
// the rest of its finger is hidden too (the filler's worst case, 20-50 mm on
// the virtual cuer) comes back within a few millimetres. Needs result from
// InvertHand(model, input) with the filler; returns the samples corrected.
// Throws InvalidInput on a shape mismatch or a model without a filler.
int64_t CorrectFilledGapsWithEdgeMisfits(const HandModel& model, const MarkerArray& input, InversionResult* result,
                                         int64_t fade_frames = 60);

}  // namespace csw
