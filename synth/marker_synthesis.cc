#include "synth/marker_synthesis.h"

#include <algorithm>
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

namespace {

// Largest jump of any marker visible in frames f - 1 and f (0 when none).
double MaxJump(const MarkerArray& m, int64_t f) {
  double best = 0.0;
  for (int64_t j = 0; j < m.markers(); ++j) {
    if (!m.Visible(f - 1, j) || !m.Visible(f, j)) continue;
    const float* a = m.at(f - 1, j);
    const float* b = m.at(f, j);
    const double dx = double(b[0]) - a[0], dy = double(b[1]) - a[1], dz = double(b[2]) - a[2];
    best = std::max(best, std::sqrt(dx * dx + dy * dy + dz * dz));
  }
  return best;
}

bool RowsFinite(const ParameterTracks& t, int64_t f) {
  return t.face_params.row(f).allFinite() && t.head_pose.row(f).allFinite() && t.hand_params.row(f).allFinite() &&
         t.forearm_in_head.row(f).allFinite();
}

}  // namespace

SpeedLimitResult LimitMarkerSpeed(const FaceModel& face, const HandModel& hand, double limit_mm, int max_passes,
                                  ParameterTracks* tracks, Take* take) {
  if (!(limit_mm > 0) || !std::isfinite(limit_mm))
    throw InvalidInput("synthesised take '" + take->name + "': the speed limit must be a positive number of mm");
  SpeedLimitResult r;
  const int64_t n = tracks->frames();
  if (take->markers.frames() != n)
    throw InvalidInput("synthesised take '" + take->name + "': " + std::to_string(take->markers.frames()) +
                       " marker frames for " + std::to_string(n) + " track rows");
  std::vector<double> jump(static_cast<size_t>(std::max<int64_t>(n, 1)), 0.0);
  for (int64_t f = 1; f < n; ++f) jump[static_cast<size_t>(f)] = MaxJump(take->markers, f);
  r.max_jump_before_mm = r.max_jump_after_mm = *std::max_element(jump.begin(), jump.end());
  // How many frames beyond each violating transition are smoothed too:
  // grows by one whenever a pass takes less than 1 % off the total excess
  // over the limit (a stretch already moving at one speed above the limit,
  // between frames that do not, is a fixed point of the kernel; only
  // widening it slows it down).
  auto excess = [&] {
    double e = 0;
    for (double j : jump) e += std::max(0.0, j - limit_mm);
    return e;
  };
  int64_t widen = 0;
  double previous_excess = excess();
  for (int pass = 0; pass < max_passes; ++pass) {
    // Frames to smooth: both ends of every transition above the limit (and
    // `widen` more on each side), when they and their neighbours have finite
    // tracks.
    std::vector<char> smooth(static_cast<size_t>(n), 0);
    bool any = false;
    for (int64_t f = 1; f < n; ++f) {
      if (jump[static_cast<size_t>(f)] <= limit_mm) continue;
      for (int64_t g = std::max<int64_t>(f - 1 - widen, 0); g <= std::min(f + widen, n - 1); ++g)
        if (RowsFinite(*tracks, std::max<int64_t>(g - 1, 0)) && RowsFinite(*tracks, g) &&
            RowsFinite(*tracks, std::min(g + 1, n - 1))) {
          smooth[static_cast<size_t>(g)] = 1;
          any = true;
        }
    }
    if (!any) break;
    const ParameterTracks before = *tracks;
    int64_t lo = n, hi = -1;
    for (int64_t g = 0; g < n; ++g) {
      if (!smooth[static_cast<size_t>(g)]) continue;
      // The ends are held: their missing neighbour is themselves.
      const int64_t prev = std::max<int64_t>(g - 1, 0), next = std::min(g + 1, n - 1);
      auto blend = [&](const Eigen::MatrixXd& from, Eigen::MatrixXd& to) {
        to.row(g) = 0.25 * from.row(prev) + 0.5 * from.row(g) + 0.25 * from.row(next);
      };
      blend(before.face_params, tracks->face_params);
      blend(before.head_pose, tracks->head_pose);
      blend(before.hand_params, tracks->hand_params);
      blend(before.forearm_in_head, tracks->forearm_in_head);
      ++r.smoothings;
      lo = std::min(lo, g);
      hi = std::max(hi, g);
    }
    ++r.passes;
    // Recompute the markers of the smoothed frames (rows lo..hi), then the
    // jumps next to them.
    ParameterTracks part;
    part.rate_hz = tracks->rate_hz;
    const Eigen::Index rows = static_cast<Eigen::Index>(hi - lo + 1);
    part.face_params = tracks->face_params.middleRows(lo, rows);
    part.head_pose = tracks->head_pose.middleRows(lo, rows);
    part.hand_params = tracks->hand_params.middleRows(lo, rows);
    part.forearm_in_head = tracks->forearm_in_head.middleRows(lo, rows);
    const Take redone = MarkersFromParameters(face, hand, part, take->name);
    for (int64_t g = lo; g <= hi; ++g) {
      if (!smooth[static_cast<size_t>(g)]) continue;
      for (int64_t j = 0; j < take->markers.markers(); ++j) {
        const float* src = redone.markers.at(g - lo, j);
        float* dst = take->markers.at(g, j);
        for (int k = 0; k < 3; ++k) dst[k] = src[k];
      }
    }
    for (int64_t g = std::max<int64_t>(1, lo); g <= std::min(n - 1, hi + 1); ++g)
      jump[static_cast<size_t>(g)] = MaxJump(take->markers, g);
    r.max_jump_after_mm = *std::max_element(jump.begin(), jump.end());
    const double now = excess();
    if (!(now < 0.99 * previous_excess)) ++widen;
    previous_excess = now;
  }
  return r;
}

}  // namespace csw
