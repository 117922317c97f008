#include "synth/marker_synthesis.h"

#include <cmath>
#include <limits>
#include <set>

#include "core/error.h"
#include "models/face_model.h"
#include "models/hand_model.h"

namespace csw {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Shape(const Eigen::MatrixXd& m) { return std::to_string(m.rows()) + "×" + std::to_string(m.cols()); }

void Store(const Eigen::Matrix3Xd& m, int64_t first_column, int64_t frame, MarkerArray* out) {
  for (Eigen::Index j = 0; j < m.cols(); ++j) {
    float* p = out->at(frame, first_column + j);
    for (int k = 0; k < 3; ++k) p[k] = static_cast<float>(m(k, j));
  }
}

}  // namespace

Eigen::Matrix<double, 6, 1> ComposePose(const Eigen::Matrix<double, 6, 1>& head,
                                        const Eigen::Matrix<double, 6, 1>& forearm_in_head) {
  if (!head.allFinite() || !forearm_in_head.allFinite()) return Eigen::Matrix<double, 6, 1>::Constant(kNaN);
  const RigidTransform h = RigidTransform::FromParameters(head);
  const RigidTransform r = RigidTransform::FromParameters(forearm_in_head);
  RigidTransform lab;
  lab.rotation = h.rotation * r.rotation;
  lab.translation = h.rotation * r.translation + h.translation;
  return lab.Parameters();
}

std::vector<std::string> SynthesisMarkerNames(const FaceModel& face, const HandModel& hand) {
  std::vector<std::string> names;
  for (const auto* group :
       {&face.layout.head, &face.layout.face, &face.layout.throat, &hand.layout.forearm, &hand.layout.hand}) {
    names.insert(names.end(), group->begin(), group->end());
  }
  return names;
}

Take MarkersFromParameters(const FaceModel& face, const HandModel& hand, const ParameterTracks& tracks,
                           const std::string& take_name) {
  const std::string where = "synthesised take '" + take_name + "'";
  if (!(tracks.rate_hz > 0) || !std::isfinite(tracks.rate_hz)) {
    throw InvalidInput(where + ": frame rate must be positive");
  }
  const int64_t n = tracks.frames();
  const int q = face.num_parameters(), p = hand.num_parameters();
  if (tracks.head_pose.cols() != 6 || tracks.forearm_in_head.cols() != 6 || tracks.face_params.rows() != n ||
      tracks.face_params.cols() != q || tracks.hand_params.rows() != n || tracks.hand_params.cols() != p ||
      tracks.forearm_in_head.rows() != n) {
    throw InvalidInput(where + ": parameter tracks disagree (head pose " + Shape(tracks.head_pose) +
                       ", face parameters " + Shape(tracks.face_params) + ", forearm in head " +
                       Shape(tracks.forearm_in_head) + ", hand parameters " + Shape(tracks.hand_params) +
                       "; poses need 6 columns, the face model has " + std::to_string(q) +
                       " parameters and the hand model " + std::to_string(p) + ", every track the same rows)");
  }
  Take take;
  take.name = take_name;
  take.rate_hz = tracks.rate_hz;
  take.first_frame = 1;
  take.marker_names = SynthesisMarkerNames(face, hand);
  std::set<std::string> seen;
  for (const std::string& m : take.marker_names) {
    if (!seen.insert(m).second) throw InvalidInput(where + ": the face and hand models both have marker '" + m + "'");
  }
  const int64_t face_markers = face.layout.num_markers();
  take.markers.Resize(n, static_cast<int64_t>(take.marker_names.size()));
  for (int64_t f = 0; f < n; ++f) {
    const Eigen::Matrix<double, 6, 1> head = tracks.head_pose.row(f).transpose();
    if (!head.allFinite()) continue;
    const RigidTransform head_pose = RigidTransform::FromParameters(head);
    const Eigen::VectorXd qf = tracks.face_params.row(f).transpose();
    if (qf.allFinite()) Store(face.MarkersInLab(head_pose, qf), 0, f, &take.markers);
    const Eigen::Matrix<double, 6, 1> rel = tracks.forearm_in_head.row(f).transpose();
    const Eigen::VectorXd pf = tracks.hand_params.row(f).transpose();
    if (rel.allFinite() && pf.allFinite()) {
      const RigidTransform r = RigidTransform::FromParameters(rel);
      RigidTransform forearm;  // head ∘ forearm_in_head, as ComposePose
      forearm.rotation = head_pose.rotation * r.rotation;
      forearm.translation = head_pose.rotation * r.translation + head_pose.translation;
      Store(hand.MarkersInLab(forearm, pf), face_markers, f, &take.markers);
    }
  }
  return take;
}

}  // namespace csw
