#include "models/rigid_model.h"

#include <cmath>
#include <string>

#include "core/error.h"

namespace csw {

RigidModel FitRigidModel(const std::string& name, const std::vector<std::string>& markers,
                         const std::vector<MarkerArray>& takes, const RigidModelOptions& options, Progress* progress) {
  const auto n = static_cast<int64_t>(markers.size());
  if (n < 3)
    throw InvalidInput(name + " model: a rigid cluster needs at least 3 markers (has " + std::to_string(n) + ")");
  if (takes.empty()) throw InvalidInput(name + " model: no training take");
  int64_t frames = 0;
  for (size_t i = 0; i < takes.size(); ++i) {
    if (takes[i].markers() != n) {
      throw InvalidInput(name + " model: training take " + std::to_string(i + 1) + " has " +
                         std::to_string(takes[i].markers()) + " cluster columns, the model has " + std::to_string(n));
    }
    frames += takes[i].frames();
  }
  // All takes end to end: one reference shape and one motion PCA for the set.
  MarkerArray all(frames, n);
  int64_t at = 0;
  for (const MarkerArray& t : takes) {
    std::copy(t.data().begin(), t.data().end(), all.data().begin() + static_cast<std::ptrdiff_t>(at * n * 3));
    at += t.frames();
  }
  std::vector<int> columns(static_cast<size_t>(n));
  for (int c = 0; c < static_cast<int>(n); ++c) columns[static_cast<size_t>(c)] = c;

  RigidModel model;
  model.name = name;
  model.markers = markers;
  try {
    model.reference = ClusterReference(all, columns);
  } catch (const InvalidInput&) {
    throw InvalidInput(name + " model: no training frame has every cluster marker visible (" + std::to_string(frames) +
                       " frames)");
  }
  const RigidSeries series = EstimateRigidSeries(all, columns, model.reference, options.rigid, progress);
  const Eigen::MatrixXd params = series.ValidParameters();
  if (params.rows() < 2) {
    throw InvalidInput(name + " model: fewer than 2 frames with at least 3 visible cluster markers");
  }
  model.motion = FitPcaVariance(params, options.motion_variance);
  model.info.training_frames = frames;
  model.info.selected_frames = params.rows();
  double sum = 0;
  int64_t count = 0;
  for (int64_t f = 0; f < series.frames(); ++f) {
    if (series.valid[static_cast<size_t>(f)] && std::isfinite(series.rms_mm(f))) {
      sum += series.rms_mm(f) * series.rms_mm(f);
      ++count;
    }
  }
  model.info.training_rms_mm = count > 0 ? std::sqrt(sum / static_cast<double>(count)) : 0.0;
  return model;
}

}  // namespace csw
