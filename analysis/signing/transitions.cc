#include "analysis/signing/transitions.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <map>
#include <set>

#include "core/error.h"

namespace csw::signing {
namespace {

std::string Lower(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (!std::isspace(static_cast<unsigned char>(c)))
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

bool InList(const std::string& label, const std::vector<std::string>& list) {
  const std::string l = Lower(label);
  return std::any_of(list.begin(), list.end(), [&](const std::string& x) { return Lower(x) == l; });
}

int64_t NearestFrame(double t, double rate, int64_t frames) {
  const auto f = static_cast<int64_t>(std::llround(t * rate));
  return std::clamp<int64_t>(f, 0, frames - 1);
}

bool PositionKnown(const Take& take, int64_t frame, int joint) { return take.markers.Visible(frame, joint); }

Eigen::Vector3d Position(const Take& take, int64_t frame, int joint) {
  const float* p = take.markers.at(frame, joint);
  return {p[0], p[1], p[2]};
}

bool OrientationKnown(const Take& take, int64_t frame, int joint) {
  return !IsMissing(take.orientations.at(frame, joint)[0]);
}

Eigen::Quaterniond Orientation(const Take& take, int64_t frame, int joint) {
  const float* q = take.orientations.at(frame, joint);
  Eigen::Quaterniond out(q[0], q[1], q[2], q[3]);
  out.normalize();
  return out;
}

// Mean joint speed (units / s) and angular speed (rad / s) over frames [a, b].
void MeanSpeeds(const Take& take, int64_t a, int64_t b, const std::vector<int>& joints, double unit_mm, double* speed,
                double* angular) {
  double s = 0, w = 0;
  int64_t ns = 0, nw = 0;
  for (int64_t f = a; f < b; ++f) {
    for (int j : joints) {
      if (PositionKnown(take, f, j) && PositionKnown(take, f + 1, j)) {
        s += (Position(take, f + 1, j) - Position(take, f, j)).norm();
        ++ns;
      }
      if (OrientationKnown(take, f, j) && OrientationKnown(take, f + 1, j)) {
        w += GeodesicDistance(Orientation(take, f, j), Orientation(take, f + 1, j));
        ++nw;
      }
    }
  }
  const double nan = std::numeric_limits<double>::quiet_NaN();
  *speed = ns > 0 ? s / static_cast<double>(ns) * take.rate_hz / unit_mm : nan;
  *angular = nw > 0 ? w / static_cast<double>(nw) * take.rate_hz : nan;
}

}  // namespace

double GeodesicDistance(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b) {
  // a⁻¹ b for unit quaternions; its log is (0, θ/2 · axis), of norm θ/2.
  const Eigen::Quaterniond d = a.conjugate() * b;
  const double v = d.vec().norm();
  const double w = std::abs(d.w());  // q ≡ −q: the shorter way round
  return std::atan2(v, w);
}

std::vector<int> ArmJoints(const std::vector<SkeletonJoint>& skeleton, int wrist, int other_wrist) {
  const int n = static_cast<int>(skeleton.size());
  if (wrist < 0 || wrist >= n || other_wrist < 0 || other_wrist >= n) {
    throw InvalidInput("arm joints: wrist index outside the skeleton's " + std::to_string(n) + " joints");
  }
  if (wrist == other_wrist) throw InvalidInput("arm joints: both wrists are joint '" + skeleton[wrist].name + "'");
  for (int j = 0; j < n; ++j) {
    const int p = skeleton[static_cast<size_t>(j)].parent;
    if (p >= j || p < -1) {
      throw InvalidInput("arm joints: joint '" + skeleton[static_cast<size_t>(j)].name +
                         "' does not come after its parent (a skeleton lists parents first)");
    }
  }
  std::set<int> other_ancestors;
  for (int j = other_wrist; j >= 0; j = skeleton[static_cast<size_t>(j)].parent) other_ancestors.insert(j);
  std::vector<bool> in(static_cast<size_t>(n), false);
  for (int j = wrist; j >= 0 && other_ancestors.count(j) == 0; j = skeleton[static_cast<size_t>(j)].parent) {
    in[static_cast<size_t>(j)] = true;
  }
  // The wrist's descendants: every joint with the wrist among its ancestors.
  for (int j = 0; j < n; ++j) {
    for (int a = skeleton[static_cast<size_t>(j)].parent; a >= 0 && a < n;
         a = skeleton[static_cast<size_t>(a)].parent) {
      if (a == wrist) {
        in[static_cast<size_t>(j)] = true;
        break;
      }
    }
  }
  std::vector<int> out;
  for (int j = 0; j < n; ++j) {
    if (in[static_cast<size_t>(j)]) out.push_back(j);
  }
  return out;
}

std::string TransitionOptions::Check() const {
  if (!(max_transition_s > 0)) return "max_transition_s must be > 0";
  if (!(length_unit_mm > 0)) return "length_unit_mm must be > 0";
  return "";
}

std::string SignTypeCode(const std::string& label) {
  const std::string l = Lower(label);
  if (l == "00" || l == "10" || l == "11" || l == "20") return l;
  if (l == "one_hand" || l == "one-hand" || l == "onehand" || l == "1h" || l == "one") return "00";
  if (l == "two_hands" || l == "two-hands" || l == "two_hand" || l == "two-hand" || l == "2h" || l == "two")
    return "10";
  if (l == "symmetric" || l == "sym" || l == "two_hands_symmetric" || l == "2hs") return "11";
  if (l == "contextualised" || l == "contextualized" || l == "context" || l == "ctx") return "20";
  return "";
}

std::vector<Transition> ExtractTransitions(const Take& take, const LabelTier& tier, const LabelTier* types,
                                           const std::vector<int>& joints, const TransitionOptions& options) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput("transitions: " + why);
  const std::string where = "take '" + take.name + "', tier '" + tier.name + "'";
  if (tier.kind != LabelTier::Kind::kInterval) throw InvalidInput(where + ": not an interval tier");
  if (take.orientations.empty() || take.orientations.joints() != take.markers.markers() ||
      take.orientations.frames() != take.frames()) {
    throw InvalidInput("take '" + take.name + "' has no joint orientations (a skeleton capture, e.g. BVH, is needed)");
  }
  if (take.rate_hz <= 0 || take.frames() < 2) throw InvalidInput("take '" + take.name + "' has fewer than two frames");
  for (int j : joints) {
    if (j < 0 || j >= take.markers.markers()) throw InvalidInput(where + ": joint index outside the take");
  }
  // Signs in time order.
  std::vector<const Label*> sorted;
  for (const Label& l : tier.labels) sorted.push_back(&l);
  std::sort(sorted.begin(), sorted.end(), [](const Label* a, const Label* b) { return a->start_s < b->start_s; });
  auto is_sign = [&](const Label& l) {
    return !Lower(l.text).empty() && !InList(l.text, options.transition_labels) && !InList(l.text, options.rest_labels);
  };
  auto type_at = [&](double t) -> std::string {
    if (types == nullptr) return "";
    for (const Label& l : types->labels) {
      if (t >= l.start_s && t <= l.end_s) return SignTypeCode(l.text);
    }
    return "";
  };
  std::vector<Transition> out;
  const Label* previous = nullptr;
  bool rest_between = false;
  for (const Label* l : sorted) {
    if (!is_sign(*l)) {
      if (InList(l->text, options.rest_labels)) rest_between = true;
      continue;
    }
    if (previous != nullptr && !rest_between) {
      const double gap = l->start_s - previous->end_s;
      if (gap > 0 && gap <= options.max_transition_s) {
        Transition tr;
        tr.take = take.name;
        tr.hand = tier.name;
        tr.from_sign = previous->text;
        tr.to_sign = l->text;
        tr.from_type = type_at(0.5 * (previous->start_s + previous->end_s));
        tr.to_type = type_at(0.5 * (l->start_s + l->end_s));
        tr.start_s = previous->end_s;
        tr.end_s = l->start_s;
        tr.duration_s = gap;
        tr.start_frame = NearestFrame(tr.start_s, take.rate_hz, take.frames());
        tr.end_frame = NearestFrame(tr.end_s, take.rate_hz, take.frames());
        double g = 0, e = 0;
        int ng = 0, ne = 0;
        for (int j : joints) {
          if (PositionKnown(take, tr.start_frame, j) && PositionKnown(take, tr.end_frame, j)) {
            e += (Position(take, tr.end_frame, j) - Position(take, tr.start_frame, j)).norm();
            ++ne;
          }
          if (OrientationKnown(take, tr.start_frame, j) && OrientationKnown(take, tr.end_frame, j)) {
            g += GeodesicDistance(Orientation(take, tr.start_frame, j), Orientation(take, tr.end_frame, j));
            ++ng;
          }
        }
        if (ng > 0 && ne > 0) {
          tr.geodesic = g / ng;
          tr.euclidean = e / ne / options.length_unit_mm;
          tr.joints_used = std::min(ng, ne);
          MeanSpeeds(take, NearestFrame(previous->start_s, take.rate_hz, take.frames()), tr.start_frame, joints,
                     options.length_unit_mm, &tr.from_speed, &tr.from_angular_speed);
          MeanSpeeds(take, tr.end_frame, NearestFrame(l->end_s, take.rate_hz, take.frames()), joints,
                     options.length_unit_mm, &tr.to_speed, &tr.to_angular_speed);
          out.push_back(tr);
        }
      }
    }
    previous = l;
    rest_between = false;
  }
  return out;
}

double DistanceNormaliser::operator()(double geodesic, double euclidean) const {
  return 0.5 * ((geodesic - geodesic_mean) / geodesic_range + (euclidean - euclidean_mean) / euclidean_range);
}

DistanceNormaliser FitNormaliser(const std::vector<Transition>& transitions) {
  DistanceNormaliser n;
  if (transitions.empty()) return n;
  double g_min = transitions[0].geodesic, g_max = g_min, e_min = transitions[0].euclidean, e_max = e_min;
  double g_sum = 0, e_sum = 0;
  for (const Transition& t : transitions) {
    g_min = std::min(g_min, t.geodesic);
    g_max = std::max(g_max, t.geodesic);
    e_min = std::min(e_min, t.euclidean);
    e_max = std::max(e_max, t.euclidean);
    g_sum += t.geodesic;
    e_sum += t.euclidean;
  }
  const auto count = static_cast<double>(transitions.size());
  n.geodesic_mean = g_sum / count;
  n.euclidean_mean = e_sum / count;
  n.geodesic_range = g_max > g_min ? g_max - g_min : 1.0;
  n.euclidean_range = e_max > e_min ? e_max - e_min : 1.0;
  return n;
}

void NormaliseDistances(std::vector<Transition>& transitions) {
  const DistanceNormaliser n = FitNormaliser(transitions);
  for (Transition& t : transitions) t.normalised = n(t.geodesic, t.euclidean);
}

std::vector<TypeStatistics> StatisticsPerType(const std::vector<Transition>& transitions) {
  std::map<std::string, std::vector<double>> by_type;
  for (const Transition& t : transitions) by_type[t.type()].push_back(t.duration_s);
  std::vector<TypeStatistics> out;
  for (const auto& [type, d] : by_type) {
    TypeStatistics s;
    s.type = type;
    s.count = static_cast<int>(d.size());
    double sum = 0;
    for (double x : d) sum += x;
    s.mean_s = sum / s.count;
    double ss = 0;
    for (double x : d) ss += (x - s.mean_s) * (x - s.mean_s);
    s.sd_s = s.count > 1 ? std::sqrt(ss / (s.count - 1)) : 0.0;
    out.push_back(s);
  }
  return out;
}

}  // namespace csw::signing
