#pragma once
// A rigid cluster model (head or forearm): the cluster's reference shape and
// the PCA of its 6 motion parameters over the training frames — the seed's
// motion control parameters nmF (head) / nmH (forearm).
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/take.h"
#include "models/pca.h"
#include "models/rigid_motion.h"

namespace csw {

// Where a model came from; stored with it (docs/model-format.md).
struct ModelInfo {
  std::string corpus;                       // corpus path as given
  std::vector<std::string> training_takes;  // as given (take[@range])
  std::string config_json;                  // the configuration used, as JSON text
  std::string created_utc;                  // ISO 8601
  std::string csw_version;
  int64_t training_frames = 0;  // complete frames offered
  int64_t selected_frames = 0;  // kept by training-frame selection
  // RMS marker residual (3D distance) over the selected training frames of
  // the model's best fit to each frame: rigid = the cluster's fit; face = the
  // shape parameters' least-squares fit in the head frame; hand = the hand
  // inversion (InvertHand from a cold start, the forearm frame known) of every
  // selected frame, i.e. what inverting the training frames reaches.
  double training_rms_mm = 0;
};

struct RigidModel {
  std::string name;                  // "head" or "forearm"
  std::vector<std::string> markers;  // cluster markers, canonical names
  Eigen::Matrix3Xd reference;        // 3 × markers, cluster frame (centroid origin)
  Pca motion;                        // of the 6 pose parameters (rx ry rz rad, tx ty tz mm)
  ModelInfo info;
};

struct RigidModelOptions {
  RigidOptions rigid;
  double motion_variance = 0.99;  // motion PCA keeps the fewest components reaching this fraction
};

// Fits from takes whose columns are exactly the cluster markers (model order).
// Throws InvalidInput when no frame has every cluster marker visible.
RigidModel FitRigidModel(const std::string& name, const std::vector<std::string>& markers,
                         const std::vector<MarkerArray>& takes, const RigidModelOptions& options = {},
                         Progress* progress = nullptr);

}  // namespace csw
