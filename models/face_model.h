#pragma once
// The face model of the seed (Gibert-Bailly-Elisei §3.1) and MOTHER (§2.2):
// head motion from a rigid cluster, then a guided PCA of the face and throat
// markers expressed in the head frame, with throat markers that follow the head
// only partly.
//
// Layout of a model-ordered marker array (see inversion.h): the head cluster
// markers, then the face markers, then the throat markers. The shape model
// (GuidedPcaModel) works on the face+throat markers ("shape markers"), in that
// order, in the head frame.
//
// Throat markers: a throat marker sits on skin between the head and the
// torso, so it follows the head motion only in part. Its lab position is the
// blend
//     lab = w · (R x + t) + (1 − w) · (R̄ x + t̄)
// of the head motion (R, t) and the head's rest pose (R̄, t̄) (the pose whose
// parameters are the motion PCA mean), where x is the marker's head-frame
// position predicted by the shape model and w in [0, 1] its head weight (w = 1
// for face markers). For small head motions this equals applying the fraction
// w of the motion. The weights not fixed by the marker set are fitted jointly
// with the shape directions (Ceres; FitFaceModel).
//
// A blend moves a throat marker by the same fraction w of the head's rotation
// and of its translation. Skin that hangs from the torso can follow the
// head's translation fully and its rotation only partly (about a pivot other
// than the head frame's origin), which no w reproduces. So a throat marker
// whose weight is fitted also gets a rotation offset k (mm, lab axes at the
// rest pose), fitted with it:
//     lab = w · (R x + t) + (1 − w) · (R̄ x + t̄) + (R R̄ᵀ − I) k.
// To first order the marker moves by w (δ × R̄x + τ) + δ × k for a head
// rotation δ and translation τ from rest: w sets how much of the
// translation it follows, and k shifts the lever arm of the rotation (a
// marker following all of τ and a fraction a of the rotation about a pivot c
// has w = 1, k = (a − 1)(R̄x + t̄ − c)). k = 0 is the blend. The offsets are
// kept only when they cut the throat markers' training residual by more than
// five times what fitting noise would (FitFaceModel): on the default virtual
// cuer (a true blend) they are all zero, on its lab2 layout 85-91 mm.

#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/take.h"
#include "models/guided_pca.h"
#include "models/inversion.h"
#include "models/rigid_model.h"

namespace csw {

struct FaceLayout {
  std::vector<std::string> head;    // head cluster (≥ 3)
  std::vector<std::string> face;    // face markers
  std::vector<std::string> throat;  // throat markers
  // One per throat marker: a fixed head weight in [0, 1), or NaN = fitted.
  std::vector<double> throat_weights;

  int num_shape_markers() const { return static_cast<int>(face.size() + throat.size()); }
  int num_markers() const { return static_cast<int>(head.size()) + num_shape_markers(); }
};

struct FaceModelOptions {
  // Guided PCA steps; marker indices refer to the shape markers (face then
  // throat). Empty: one step over all shape markers with default_components.
  std::vector<GuidedPcaStep> steps;
  int default_components = 6;
  double min_distance_mm = 2.0;        // training-frame selection (frame_selection.h)
  RigidModelOptions head;              // head cluster fit and motion PCA
  int throat_weight_rounds = 4;        // alternations PCA ↔ weight fit (0: weights stay at their start)
  double initial_throat_weight = 0.5;  // start for fitted weights
};

struct FaceModel {
  FaceLayout layout;
  RigidModel head;               // cluster reference and motion PCA (nmF)
  Eigen::VectorXd head_weights;  // one per shape marker: 1 for face, w for throat (fixed or fitted)
  RigidTransform rest_pose;      // (R̄, t̄) above
  // k above, one row per shape marker (shape markers × 3, zero rows for the
  // face and for throat markers with a fixed weight); empty = all zero (model
  // files written before it existed).
  Eigen::MatrixXd rotation_offsets;
  GuidedPcaModel shape;  // over the shape markers, head frame
  ModelInfo info;

  int num_parameters() const { return shape.num_parameters(); }
  // Shape markers in the lab for a head pose and shape parameters (3 × shape markers).
  Eigen::Matrix3Xd ShapeMarkersInLab(const RigidTransform& pose, const Eigen::VectorXd& params) const;
  // All model markers (head cluster then shape markers) in the lab.
  Eigen::Matrix3Xd MarkersInLab(const RigidTransform& pose, const Eigen::VectorXd& params) const;
};

// Fits from model-ordered takes: head cluster model, head-frame coordinates,
// training-frame selection over the shape markers (frames with a missing
// shape or too few head markers are excluded), guided PCA, and the throat
// weights. Throws InvalidInput on a layout/column mismatch, no usable frame,
// or fewer selected frames than parameters + 1. Progress is reported and may
// cancel (Cancelled).
FaceModel FitFaceModel(const FaceLayout& layout, const std::vector<MarkerArray>& takes,
                       const FaceModelOptions& options = {}, Progress* progress = nullptr);

// Per-frame inversion of a model-ordered take (see inversion.h). pose is the
// head cluster pose; params the shape parameters.
InversionResult InvertFace(const FaceModel& model, const MarkerArray& take, const InversionOptions& options = {},
                           Progress* progress = nullptr);

}  // namespace csw
