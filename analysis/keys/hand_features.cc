#include "analysis/keys/hand_features.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <set>

#include "core/error.h"

namespace csw::keys {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string Prefix(const std::string& take_name) { return take_name.empty() ? "" : take_name + ": "; }

// Lab position of a canonical marker at a frame, or false when unbound / missing.
bool Position(const MarkerArray& markers, const MarkerBinding& binding, const std::string& name, int64_t frame,
              Eigen::Vector3d* p) {
  const auto it = binding.index.find(name);
  if (it == binding.index.end()) return false;
  const float* v = markers.at(frame, it->second);
  if (!std::isfinite(v[0]) || !std::isfinite(v[1]) || !std::isfinite(v[2])) return false;
  *p = Eigen::Vector3d(v[0], v[1], v[2]);
  return true;
}

int ColumnOf(const MarkerBinding& binding, const std::string& name) {
  const auto it = binding.index.find(name);
  return it == binding.index.end() ? -1 : it->second;
}

// Up to `count` frames spread evenly over the take.
std::vector<int64_t> SampleFrames(int64_t frames, int64_t count) {
  std::vector<int64_t> out;
  if (frames <= 0) return out;
  const int64_t n = std::min(frames, count);
  for (int64_t i = 0; i < n; ++i) out.push_back(i * frames / n);
  return out;
}

// Centroid of the markers visible at a frame; false when fewer than `min_count`.
bool Centroid(const MarkerArray& markers, const MarkerBinding& binding, const std::vector<std::string>& names,
              int64_t frame, size_t min_count, Eigen::Vector3d* c) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  size_t n = 0;
  for (const auto& name : names) {
    Eigen::Vector3d p;
    if (Position(markers, binding, name, frame, &p)) {
      sum += p;
      ++n;
    }
  }
  if (n < std::max<size_t>(min_count, 1)) return false;
  *c = sum / static_cast<double>(n);
  return true;
}

}  // namespace

const std::array<std::string, kNumFingers>& FingerNames() {
  static const std::array<std::string, kNumFingers> names = {"thumb", "index", "middle", "ring", "little"};
  return names;
}

const std::vector<std::string>& DistanceNames() {
  static const std::vector<std::string> names = {"thumb_extension", "index_extension",  "middle_extension",
                                                 "ring_extension",  "little_extension", "index_middle_tips",
                                                 "thumb_palm"};
  return names;
}

std::string HandLayout::Check() const {
  for (int f = 0; f < kNumFingers; ++f) {
    if (proximal[f].empty() || distal[f].empty()) return "hand layout: finger " + FingerNames()[f] + " has no markers";
    if (proximal[f] == distal[f]) return "hand layout: finger " + FingerNames()[f] + " uses one marker twice";
  }
  if (palm.size() < 3)
    return "hand layout: the palm needs at least 3 markers (has " + std::to_string(palm.size()) + ")";
  if (!thumb_palm.empty() && std::find(palm.begin(), palm.end(), thumb_palm) == palm.end())
    return "hand layout: thumb_palm " + thumb_palm + " is not one of the palm markers";
  if (head.size() < 3)
    return "hand layout: the head needs at least 3 markers (has " + std::to_string(head.size()) + ")";
  return "";
}

bool operator==(const HandLayout& a, const HandLayout& b) {
  return a.proximal == b.proximal && a.distal == b.distal && a.palm == b.palm && a.thumb_palm == b.thumb_palm &&
         a.head == b.head;
}

HandLayout ParseHandLayout(const nlohmann::json& section, const MarkerSet& set, const std::string& where) {
  auto fail = [&](const std::string& what) { throw InvalidInput(where + ": " + what); };
  if (!section.is_object()) fail("hand_layout must be an object");
  auto names = [&](const nlohmann::json& v, const std::string& key) {
    if (!v.is_array()) fail(key + " must be an array of marker names");
    std::vector<std::string> out;
    for (const auto& e : v) {
      if (!e.is_string()) fail(key + " must be an array of marker names");
      out.push_back(e.get<std::string>());
    }
    return out;
  };
  HandLayout layout;
  layout.head = set.head_cluster;
  bool have_fingers = false;
  for (const auto& [key, value] : section.items()) {
    if (key == "fingers") {
      if (!value.is_object()) fail("fingers must be an object");
      for (const auto& [finger, markers] : value.items()) {
        const auto& fn = FingerNames();
        const auto it = std::find(fn.begin(), fn.end(), finger);
        if (it == fn.end()) fail("unknown finger \"" + finger + "\" (thumb, index, middle, ring, little)");
        const auto pair = names(markers, "fingers." + finger);
        if (pair.size() != 2) fail("fingers." + finger + " must name 2 markers (proximal, distal)");
        const auto f = static_cast<size_t>(it - fn.begin());
        layout.proximal[f] = pair[0];
        layout.distal[f] = pair[1];
      }
      have_fingers = true;
    } else if (key == "palm") {
      layout.palm = names(value, "palm");
    } else if (key == "thumb_palm") {
      if (!value.is_string()) fail("thumb_palm must be a marker name");
      layout.thumb_palm = value.get<std::string>();
    } else if (key == "head") {
      layout.head = names(value, "head");
    } else {
      fail("unknown key \"" + key + "\" in hand_layout");
    }
  }
  if (!have_fingers) fail("hand_layout needs \"fingers\"");
  const std::string reason = layout.Check();
  if (!reason.empty()) fail(reason);
  return layout;
}

nlohmann::json HandLayoutToJson(const HandLayout& layout) {
  nlohmann::json fingers = nlohmann::json::object();
  for (int f = 0; f < kNumFingers; ++f) fingers[FingerNames()[f]] = {layout.proximal[f], layout.distal[f]};
  return {{"fingers", fingers}, {"palm", layout.palm}, {"thumb_palm", layout.thumb_palm}, {"head", layout.head}};
}

HandLayout DeriveHandLayout(const MarkerSet& set, const MarkerArray& markers, const MarkerBinding& binding,
                            const std::string& take_name) {
  const std::string pre = Prefix(take_name);
  const auto& segs = set.hand_segments;
  std::map<std::string, int> by_name;
  for (size_t i = 0; i < segs.size(); ++i) by_name[segs[i].name] = static_cast<int>(i);
  std::vector<std::vector<int>> children(segs.size());
  for (size_t i = 0; i < segs.size(); ++i) {
    const auto it = by_name.find(segs[i].parent);
    if (it != by_name.end()) children[it->second].push_back(static_cast<int>(i));
  }
  // Longest descending chain from a segment (first segment included).
  std::function<std::vector<int>(int)> chain = [&](int s) {
    std::vector<int> best;
    for (int c : children[s]) {
      auto sub = chain(c);
      if (sub.size() > best.size()) best = std::move(sub);
    }
    best.insert(best.begin(), s);
    return best;
  };
  // The palm: the segment with the most child chains (a hand's root).
  int palm_seg = -1;
  for (size_t i = 0; i < segs.size(); ++i)
    if (palm_seg < 0 || children[i].size() > children[palm_seg].size()) palm_seg = static_cast<int>(i);
  if (palm_seg < 0 || children[palm_seg].size() != kNumFingers) {
    throw InvalidInput(pre + "marker set \"" + set.name + "\": the hand segments must form a palm with " +
                       std::to_string(kNumFingers) + " finger chains (found " +
                       std::to_string(palm_seg < 0 ? 0 : children[palm_seg].size()) +
                       "); name the markers in a hand_layout section");
  }
  std::vector<std::vector<int>> chains;
  for (int c : children[palm_seg]) chains.push_back(chain(c));

  HandLayout layout;
  layout.palm = set.palm.size() >= 3 ? set.palm : segs[palm_seg].markers;
  layout.head = set.head_cluster;

  // Fingers: vote over frames where all five first segments are visible.
  const auto frames = SampleFrames(markers.frames(), 400);
  std::map<std::array<int, kNumFingers>, int> votes;  // finger -> chain
  for (int64_t t : frames) {
    std::array<Eigen::Vector3d, kNumFingers> c;
    bool ok = true;
    for (int i = 0; i < kNumFingers && ok; ++i)
      ok =
          Centroid(markers, binding, segs[chains[i].front()].markers, t, segs[chains[i].front()].markers.size(), &c[i]);
    if (!ok) continue;
    int thumb = 0;
    double best = std::numeric_limits<double>::infinity();
    Eigen::Vector3d best_dir = Eigen::Vector3d::UnitX(), best_mean = Eigen::Vector3d::Zero();
    for (int j = 0; j < kNumFingers; ++j) {
      Eigen::Matrix<double, 3, 4> pts;
      int k = 0;
      for (int i = 0; i < kNumFingers; ++i)
        if (i != j) pts.col(k++) = c[i];
      const Eigen::Vector3d mean = pts.rowwise().mean();
      const Eigen::Matrix<double, 3, 4> centred = pts.colwise() - mean;
      Eigen::JacobiSVD<Eigen::Matrix<double, 3, 4>> svd(centred, Eigen::ComputeFullU);
      const double residual =
          svd.singularValues()(1) * svd.singularValues()(1) + svd.singularValues()(2) * svd.singularValues()(2);
      // Relative to the spread of the thumb candidate from the line.
      const Eigen::Vector3d dir = svd.matrixU().col(0);
      const Eigen::Vector3d off = (c[j] - mean) - dir * dir.dot(c[j] - mean);
      const double score = residual / std::max(off.squaredNorm(), 1e-9);
      if (score < best) {
        best = score;
        thumb = j;
        best_dir = dir;
        best_mean = mean;
      }
    }
    std::vector<std::pair<double, int>> order;
    for (int i = 0; i < kNumFingers; ++i)
      if (i != thumb) order.push_back({best_dir.dot(c[i] - best_mean), i});
    std::sort(order.begin(), order.end());
    // Canonical direction for the vote (the end with the lower chain index
    // first); which end is the index is decided below from finger lengths.
    if (order.front().second > order.back().second) std::reverse(order.begin(), order.end());
    std::array<int, kNumFingers> assign{};
    assign[0] = thumb;
    for (int i = 0; i < 4; ++i) assign[i + 1] = order[i].second;
    ++votes[assign];
  }
  if (votes.empty()) {
    throw InvalidInput(pre +
                       "no frame shows the first segment of all five fingers; cannot tell the fingers apart "
                       "(name the markers in a hand_layout section)");
  }
  auto winner = std::max_element(votes.begin(), votes.end(), [](const auto& a, const auto& b) {
                  return a.second < b.second;
                })->first;
  // The index is the longer of the two outer fingers (the little finger is the
  // shortest): 95th percentile over frames of the distance from the first to
  // the last segment of the chain (its extended length).
  auto extended_length = [&](int chain_index) {
    const auto& ch = chains[chain_index];
    std::vector<double> d;
    for (int64_t t : frames) {
      Eigen::Vector3d a, b;
      if (Centroid(markers, binding, segs[ch.front()].markers, t, 1, &a) &&
          Centroid(markers, binding, segs[ch.back()].markers, t, 1, &b))
        d.push_back((a - b).norm());
    }
    if (d.empty()) return 0.0;
    std::sort(d.begin(), d.end());
    return d[std::min(d.size() - 1, static_cast<size_t>(0.95 * static_cast<double>(d.size())))];
  };
  if (extended_length(winner[4]) > extended_length(winner[1])) std::reverse(winner.begin() + 1, winner.end());

  std::set<std::string> tips(set.fingertips.begin(), set.fingertips.end());
  for (int f = 0; f < kNumFingers; ++f) {
    const auto& ch = chains[winner[f]];
    const auto& first = segs[ch.front()].markers;
    const auto& last = segs[ch.back()].markers;
    // Mean distance of each candidate marker to the palm centre.
    auto mean_distance = [&](const std::string& name) {
      double sum = 0;
      int n = 0;
      for (int64_t t : frames) {
        Eigen::Vector3d p, c;
        if (!Position(markers, binding, name, t, &p)) continue;
        if (!Centroid(markers, binding, layout.palm, t, 3, &c)) continue;
        sum += (p - c).norm();
        ++n;
      }
      return n > 0 ? sum / n : std::numeric_limits<double>::quiet_NaN();
    };
    std::string prox;
    double prox_d = std::numeric_limits<double>::infinity();
    for (const auto& m : first) {
      const double d = mean_distance(m);
      if (std::isfinite(d) && d < prox_d) {
        prox_d = d;
        prox = m;
      }
    }
    std::string dist;
    for (int s : ch)
      for (const auto& m : segs[s].markers)
        if (tips.count(m)) dist = m;
    if (dist.empty()) {
      double dist_d = -1;
      for (const auto& m : last) {
        const double d = mean_distance(m);
        if (std::isfinite(d) && d > dist_d) {
          dist_d = d;
          dist = m;
        }
      }
    }
    if (prox.empty() || dist.empty())
      throw InvalidInput(pre + "finger " + FingerNames()[f] + ": its markers are never visible with the palm");
    layout.proximal[f] = prox;
    layout.distal[f] = dist;
  }
  // The palm marker nearest the little finger's base (see the header).
  double best_d = std::numeric_limits<double>::infinity();
  for (const auto& m : layout.palm) {
    double sum = 0;
    int n = 0;
    for (int64_t t : frames) {
      Eigen::Vector3d a, b;
      if (Position(markers, binding, m, t, &a) && Position(markers, binding, layout.proximal[4], t, &b)) {
        sum += (a - b).norm();
        ++n;
      }
    }
    if (n > 0 && sum / n < best_d) {
      best_d = sum / n;
      layout.thumb_palm = m;
    }
  }
  const std::string reason = layout.Check();
  if (!reason.empty()) throw InvalidInput(pre + reason);
  return layout;
}

Eigen::Matrix3Xd HeadReference(const MarkerArray& markers, const MarkerBinding& binding, const HandLayout& layout) {
  std::vector<int> cols;
  for (const auto& m : layout.head) {
    const int c = ColumnOf(binding, m);
    if (c < 0) throw InvalidInput("head marker " + m + " is not in the take");
    cols.push_back(c);
  }
  return ClusterReference(markers, cols);
}

HandFeatures ComputeHandFeatures(const MarkerArray& markers, const MarkerBinding& binding, const HandLayout& layout,
                                 const Eigen::Matrix3Xd& head_reference, const HandFeatureOptions& options,
                                 Progress* progress) {
  const std::string reason = layout.Check();
  if (!reason.empty()) throw InvalidInput(reason);
  if (head_reference.cols() != static_cast<Eigen::Index>(layout.head.size()))
    throw InvalidInput("head reference has " + std::to_string(head_reference.cols()) + " markers, the layout " +
                       std::to_string(layout.head.size()));
  const int64_t n = markers.frames();
  HandFeatures out;
  out.distances.setConstant(n, kNumDistances, kNaN);
  out.index_tip.setConstant(n, 3, kNaN);
  out.middle_tip.setConstant(n, 3, kNaN);

  // Palm centre: rigid fit of the palm markers to their reference shape (from
  // this take) when >= 3 are visible, so one hidden palm marker does not move it.
  std::vector<int> palm_cols;
  for (const auto& m : layout.palm) palm_cols.push_back(ColumnOf(binding, m));
  Eigen::Matrix3Xd palm_reference;
  bool palm_rigid = std::find(palm_cols.begin(), palm_cols.end(), -1) == palm_cols.end();
  if (palm_rigid) {
    try {
      palm_reference = ClusterReference(markers, palm_cols);
    } catch (const InvalidInput&) {
      palm_rigid = false;
    }
  }
  Eigen::Vector3d palm_centre_local = Eigen::Vector3d::Zero();
  std::vector<std::string> palm_point_markers = layout.palm;
  if (!layout.thumb_palm.empty()) palm_point_markers = {layout.thumb_palm};
  if (palm_rigid) {
    palm_centre_local = palm_reference.rowwise().mean();
    for (size_t i = 0; i < layout.palm.size(); ++i)
      if (layout.palm[i] == layout.thumb_palm) palm_centre_local = palm_reference.col(static_cast<Eigen::Index>(i));
  }

  // Head frame.
  std::vector<int> head_cols;
  for (const auto& m : layout.head) head_cols.push_back(ColumnOf(binding, m));
  const bool head_bound = std::find(head_cols.begin(), head_cols.end(), -1) == head_cols.end();
  RigidSeries head;
  if (head_bound) head = EstimateRigidSeries(markers, head_cols, head_reference, options.head_fit, nullptr);

  if (palm_rigid) out.tips_in_palm.setConstant(n, 3 * kNumFingers, kNaN);
  Eigen::Matrix3Xd palm_obs(3, static_cast<Eigen::Index>(palm_cols.size()));
  for (int64_t t = 0; t < n; ++t) {
    if (progress != nullptr && t % 4096 == 0) progress->Update("hand features", static_cast<double>(t) / n);
    std::array<Eigen::Vector3d, kNumFingers> prox, dist;
    std::array<bool, kNumFingers> have_prox{}, have_dist{};
    for (int f = 0; f < kNumFingers; ++f) {
      have_prox[f] = Position(markers, binding, layout.proximal[f], t, &prox[f]);
      have_dist[f] = Position(markers, binding, layout.distal[f], t, &dist[f]);
      if (have_prox[f] && have_dist[f]) out.distances(t, f) = (dist[f] - prox[f]).norm();
    }
    if (have_dist[1] && have_dist[2]) out.distances(t, 5) = (dist[1] - dist[2]).norm();
    // The palm's pose this frame (rigid fit of its visible markers).
    RigidFit palm_fit;
    if (palm_rigid) {
      int visible = 0;
      for (size_t i = 0; i < palm_cols.size(); ++i) {
        const float* v = markers.at(t, palm_cols[i]);
        if (std::isfinite(v[0])) {
          palm_obs.col(static_cast<Eigen::Index>(i)) = Eigen::Vector3d(v[0], v[1], v[2]);
          ++visible;
        } else {
          palm_obs.col(static_cast<Eigen::Index>(i)).setConstant(kNaN);
        }
      }
      if (visible >= 3) palm_fit = EstimateRigidKabsch(palm_reference, palm_obs);
      if (palm_fit.valid) {
        const RigidTransform to_palm = palm_fit.transform.Inverse();
        for (int f = 0; f < kNumFingers; ++f)
          if (have_dist[f]) out.tips_in_palm.block<1, 3>(t, 3 * f) = to_palm.Apply(dist[f]).transpose();
      }
    }
    if (have_dist[0]) {
      Eigen::Vector3d centre;
      bool have_centre = false;
      if (palm_rigid) {
        if (palm_fit.valid) {
          centre = palm_fit.transform.Apply(palm_centre_local);
          have_centre = true;
        }
      } else {
        have_centre = Centroid(markers, binding, palm_point_markers, t, palm_point_markers.size(), &centre);
      }
      if (have_centre) out.distances(t, 6) = (dist[0] - centre).norm();
    }
    if (head_bound && head.valid[t]) {
      const RigidTransform inv = head.Transform(t).Inverse();
      if (have_dist[1]) out.index_tip.row(t) = inv.Apply(dist[1]).transpose();
      if (have_dist[2]) out.middle_tip.row(t) = inv.Apply(dist[2]).transpose();
    }
  }
  if (progress != nullptr) progress->Update("hand features", 1.0);
  return out;
}

}  // namespace csw::keys
