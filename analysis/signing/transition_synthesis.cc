#include "analysis/signing/transition_synthesis.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "analysis/signing/transitions.h"
#include "core/error.h"

namespace csw::signing {
namespace {

void CheckCompatible(const Clip& a, const Clip& b, const char* what) {
  if (a.joints != b.joints) {
    throw InvalidInput(std::string(what) + ": the clips have " + std::to_string(a.joints) + " and " +
                       std::to_string(b.joints) + " joints");
  }
  if (std::abs(a.rate_hz - b.rate_hz) > 1e-9 * std::max(a.rate_hz, b.rate_hz)) {
    throw InvalidInput(std::string(what) + ": the clips' frame rates differ (" + std::to_string(a.rate_hz) + " and " +
                       std::to_string(b.rate_hz) + " Hz)");
  }
  if (a.frames < 1 || b.frames < 1) throw InvalidInput(std::string(what) + ": an empty clip");
}

Clip Empty(const Clip& like, int64_t frames) {
  Clip c;
  c.rate_hz = like.rate_hz;
  c.joints = like.joints;
  c.frames = frames;
  c.positions.resize(static_cast<size_t>(frames * like.joints));
  c.orientations.resize(static_cast<size_t>(frames * like.joints));
  return c;
}

}  // namespace

Clip ExtractClip(const Take& take, int64_t first, int64_t count) {
  const std::string where = "take '" + take.name + "'";
  if (take.orientations.empty() || take.orientations.frames() != take.frames() ||
      take.orientations.joints() != take.markers.markers()) {
    throw InvalidInput(where + " has no joint orientations (a skeleton capture is needed)");
  }
  if (first < 0 || count < 1 || first + count > take.frames()) {
    throw InvalidInput(where + ": frames [" + std::to_string(first) + ", " + std::to_string(first + count) +
                       ") are outside its " + std::to_string(take.frames()) + " frames");
  }
  Clip c;
  c.rate_hz = take.rate_hz;
  c.frames = count;
  c.joints = static_cast<int>(take.markers.markers());
  c.positions.reserve(static_cast<size_t>(count * c.joints));
  c.orientations.reserve(static_cast<size_t>(count * c.joints));
  for (int64_t f = first; f < first + count; ++f) {
    for (int j = 0; j < c.joints; ++j) {
      const float* p = take.markers.at(f, j);
      const float* q = take.orientations.at(f, j);
      if (IsMissing(p[0]) || IsMissing(q[0])) {
        throw InvalidInput(where + ": joint '" +
                           (static_cast<size_t>(j) < take.marker_names.size()
                                ? take.marker_names[static_cast<size_t>(j)]
                                : std::to_string(j)) +
                           "' is missing at frame " + std::to_string(f));
      }
      c.positions.emplace_back(p[0], p[1], p[2]);
      c.orientations.emplace_back(Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized());
    }
  }
  return c;
}

void PostureAt(const Clip& clip, double frame, std::vector<Eigen::Vector3d>* positions,
               std::vector<Eigen::Quaterniond>* orientations) {
  const double f = std::clamp(frame, 0.0, static_cast<double>(clip.frames - 1));
  const auto f0 = static_cast<int64_t>(std::floor(f));
  const int64_t f1 = std::min(f0 + 1, clip.frames - 1);
  const double u = f - static_cast<double>(f0);
  positions->resize(static_cast<size_t>(clip.joints));
  orientations->resize(static_cast<size_t>(clip.joints));
  for (int j = 0; j < clip.joints; ++j) {
    (*positions)[static_cast<size_t>(j)] = (1 - u) * clip.position(f0, j) + u * clip.position(f1, j);
    (*orientations)[static_cast<size_t>(j)] = clip.orientation(f0, j).slerp(u, clip.orientation(f1, j));
  }
}

Clip InterpolateTransition(const Clip& from, const Clip& to, int64_t frames) {
  CheckCompatible(from, to, "interpolation");
  if (frames < 0) throw InvalidInput("interpolation: a negative frame count");
  Clip c = Empty(from, frames);
  const int64_t last = from.frames - 1;
  for (int64_t i = 0; i < frames; ++i) {
    const double u = static_cast<double>(i + 1) / static_cast<double>(frames + 1);
    for (int j = 0; j < from.joints; ++j) {
      const size_t k = static_cast<size_t>(i * from.joints + j);
      c.positions[k] = (1 - u) * from.position(last, j) + u * to.position(0, j);
      c.orientations[k] = from.orientation(last, j).slerp(u, to.orientation(0, j));
    }
  }
  return c;
}

Clip BlendTransition(const Clip& retraction, const Clip& preparation, int64_t frames, bool smooth) {
  CheckCompatible(retraction, preparation, "blending");
  if (frames < 0) throw InvalidInput("blending: a negative frame count");
  Clip c = Empty(retraction, frames);
  std::vector<Eigen::Vector3d> pr, pp;
  std::vector<Eigen::Quaterniond> qr, qp;
  for (int64_t i = 0; i < frames; ++i) {
    const double u = frames == 1 ? 0.5 : static_cast<double>(i) / static_cast<double>(frames - 1);
    const double w = smooth ? u * u * (3 - 2 * u) : u;
    PostureAt(retraction, u * static_cast<double>(retraction.frames - 1), &pr, &qr);
    PostureAt(preparation, u * static_cast<double>(preparation.frames - 1), &pp, &qp);
    for (int j = 0; j < retraction.joints; ++j) {
      const size_t k = static_cast<size_t>(i * retraction.joints + j);
      c.positions[k] = (1 - w) * pr[static_cast<size_t>(j)] + w * pp[static_cast<size_t>(j)];
      c.orientations[k] = qr[static_cast<size_t>(j)].slerp(w, qp[static_cast<size_t>(j)]);
    }
  }
  return c;
}

int64_t TransitionFrames(double duration_s, double rate_hz) {
  if (!(duration_s > 0) || !(rate_hz > 0)) return 0;
  return std::max<int64_t>(0, static_cast<int64_t>(std::llround(duration_s * rate_hz)) - 1);
}

Clip Concatenate(const Clip& a, const Clip& b) {
  if (a.frames == 0) return b;
  if (b.frames == 0) return a;
  CheckCompatible(a, b, "concatenation");
  Clip c = a;
  c.frames += b.frames;
  c.positions.insert(c.positions.end(), b.positions.begin(), b.positions.end());
  c.orientations.insert(c.orientations.end(), b.orientations.begin(), b.orientations.end());
  return c;
}

double PostureDistance(const Clip& a, int64_t frame_a, const Clip& b, int64_t frame_b, double length_unit_mm) {
  CheckCompatible(a, b, "posture distance");
  double e = 0, g = 0;
  for (int j = 0; j < a.joints; ++j) {
    e += (a.position(frame_a, j) - b.position(frame_b, j)).norm();
    g += GeodesicDistance(a.orientation(frame_a, j), b.orientation(frame_b, j));
  }
  return (e / length_unit_mm + g) / std::max(1, a.joints);
}

size_t RetrieveOccurrence(const std::vector<Clip>& candidates, const Clip* previous, const Clip* next,
                          double length_unit_mm) {
  if (candidates.empty()) throw InvalidInput("motion retrieval: no candidate occurrence");
  size_t best = 0;
  double best_cost = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < candidates.size(); ++i) {
    const Clip& c = candidates[i];
    double cost = 0;
    if (previous != nullptr) cost += PostureDistance(*previous, previous->frames - 1, c, 0, length_unit_mm);
    if (next != nullptr) cost += PostureDistance(c, c.frames - 1, *next, 0, length_unit_mm);
    if (cost < best_cost) {
      best_cost = cost;
      best = i;
    }
  }
  return best;
}

std::vector<size_t> RetrieveSequence(const std::vector<std::vector<Clip>>& candidates, double length_unit_mm) {
  const size_t n = candidates.size();
  for (size_t i = 0; i < n; ++i) {
    if (candidates[i].empty())
      throw InvalidInput("motion retrieval: sign " + std::to_string(i + 1) + " has no occurrence");
  }
  if (n == 0) return {};
  // cost[i][k]: the least summed boundary distance of signs 0..i ending with occurrence k.
  std::vector<std::vector<double>> cost(n);
  std::vector<std::vector<size_t>> back(n);
  cost[0].assign(candidates[0].size(), 0.0);
  back[0].assign(candidates[0].size(), 0);
  for (size_t i = 1; i < n; ++i) {
    cost[i].assign(candidates[i].size(), std::numeric_limits<double>::infinity());
    back[i].assign(candidates[i].size(), 0);
    for (size_t k = 0; k < candidates[i].size(); ++k) {
      for (size_t p = 0; p < candidates[i - 1].size(); ++p) {
        const Clip& prev = candidates[i - 1][p];
        const double c = cost[i - 1][p] + PostureDistance(prev, prev.frames - 1, candidates[i][k], 0, length_unit_mm);
        if (c < cost[i][k]) {
          cost[i][k] = c;
          back[i][k] = p;
        }
      }
    }
  }
  std::vector<size_t> out(n);
  out[n - 1] = static_cast<size_t>(std::min_element(cost[n - 1].begin(), cost[n - 1].end()) - cost[n - 1].begin());
  for (size_t i = n - 1; i > 0; --i) out[i - 1] = back[i][out[i]];
  return out;
}

Transition MeasureBetween(const Clip& from, const Clip& to, const std::vector<int>& joints, double length_unit_mm) {
  CheckCompatible(from, to, "transition measure");
  std::vector<int> js = joints;
  if (js.empty()) {
    for (int j = 0; j < from.joints; ++j) js.push_back(j);
  }
  Transition t;
  double e = 0, g = 0;
  for (int j : js) {
    if (j < 0 || j >= from.joints) throw InvalidInput("transition measure: joint index outside the clips");
    e += (from.position(from.frames - 1, j) - to.position(0, j)).norm();
    g += GeodesicDistance(from.orientation(from.frames - 1, j), to.orientation(0, j));
  }
  const auto nj = static_cast<double>(js.size());
  t.euclidean = e / nj / length_unit_mm;
  t.geodesic = g / nj;
  t.joints_used = static_cast<int>(js.size());
  auto speeds = [&](const Clip& c, double* v, double* w) {
    double sv = 0, sw = 0;
    int64_t count = 0;
    for (int64_t f = 0; f + 1 < c.frames; ++f) {
      for (int j : js) {
        sv += (c.position(f + 1, j) - c.position(f, j)).norm();
        sw += GeodesicDistance(c.orientation(f, j), c.orientation(f + 1, j));
        ++count;
      }
    }
    const double nan = std::numeric_limits<double>::quiet_NaN();
    *v = count > 0 ? sv / static_cast<double>(count) * c.rate_hz / length_unit_mm : nan;
    *w = count > 0 ? sw / static_cast<double>(count) * c.rate_hz : nan;
  };
  speeds(from, &t.from_speed, &t.from_angular_speed);
  speeds(to, &t.to_speed, &t.to_angular_speed);
  return t;
}

void CompareClips(const Clip& a, const Clip& b, double* mean_position_error_mm, double* mean_geodesic_error) {
  if (a.frames != b.frames || a.joints != b.joints) {
    throw InvalidInput("comparing clips of " + std::to_string(a.frames) + " and " + std::to_string(b.frames) +
                       " frames (" + std::to_string(a.joints) + " and " + std::to_string(b.joints) + " joints)");
  }
  double e = 0, g = 0;
  for (size_t k = 0; k < a.positions.size(); ++k) {
    e += (a.positions[k] - b.positions[k]).norm();
    g += GeodesicDistance(a.orientations[k], b.orientations[k]);
  }
  const double n = std::max<double>(1.0, static_cast<double>(a.positions.size()));
  *mean_position_error_mm = e / n;
  *mean_geodesic_error = g / n;
}

}  // namespace csw::signing
