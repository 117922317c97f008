#include "analysis/keys/key_decoding.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "core/error.h"

namespace csw::keys {
namespace {

constexpr double kNegInf = -std::numeric_limits<double>::infinity();
constexpr int kKeys = kNumPlacements * kNumShapes;

int Frames(double ms, double rate_hz) { return std::max(1, static_cast<int>(std::lround(ms * 1e-3 * rate_hz))); }

// Log emissions, frames × (placement, shape) and per component.
struct Emissions {
  Eigen::MatrixXd log_shape;      // frames × 9
  Eigen::MatrixXd log_placement;  // frames × 6
  double Key(int64_t t, int p, int s) const { return log_shape(t, s) + log_placement(t, p); }
};

Emissions MakeEmissions(const KeyPosteriors& post, double floor) {
  if (post.shape.cols() != kNumShapes || post.placement.cols() != kNumPlacements ||
      post.shape.rows() != post.placement.rows())
    throw InvalidInput("key decoding: posteriors must be frames × 9 (shape) and frames × 6 (placement)");
  Emissions e;
  e.log_shape = post.shape.array().max(floor).log().matrix();
  e.log_placement = post.placement.array().max(floor).log().matrix();
  return e;
}

// Target frame in [start, end) of a per-frame log score: the best frame, or
// the middle of the frames within `plateau` of the best.
int64_t TargetFrame(int64_t start, int64_t end, double plateau, const std::function<double(int64_t)>& score) {
  double best = kNegInf;
  for (int64_t t = start; t < end; ++t) best = std::max(best, score(t));
  std::vector<int64_t> near;
  for (int64_t t = start; t < end; ++t)
    if (score(t) >= best - plateau) near.push_back(t);
  return near.empty() ? start : near[near.size() / 2];
}

// Arrival: the first frame of [start, end) whose score comes within
// `tolerance` of the segment's best.
int64_t ArrivalFrame(int64_t start, int64_t end, double tolerance, const std::function<double(int64_t)>& score) {
  double best = kNegInf, worst = std::numeric_limits<double>::infinity();
  for (int64_t t = start; t < end; ++t) {
    const double v = score(t);
    best = std::max(best, v);
    if (v > kNegInf) worst = std::min(worst, v);
  }
  const double threshold = best - tolerance * (best - worst);
  for (int64_t t = start; t < end; ++t)
    if (score(t) >= threshold) return t;
  return start;
}

void SetTargets(const KeyPosteriors& post, const Emissions& e, double plateau, double arrival, DecodedKey* k) {
  const int p = k->placement, s = k->shape;
  const bool close = post.shape_closeness.rows() == post.frames() && post.placement_closeness.rows() == post.frames();
  if (close) {
    // Closeness to the class means peaks where the posture is reached; NaN
    // (nothing observed) never wins.
    auto value = [](double v) { return std::isnan(v) ? kNegInf : v; };
    auto joint = [&](int64_t t) { return value(post.shape_closeness(t, s)) + value(post.placement_closeness(t, p)); };
    k->target_frame = ArrivalFrame(k->start_frame, k->end_frame, arrival, joint);
    k->shape_target_frame = ArrivalFrame(k->start_frame, k->end_frame, arrival,
                                         [&](int64_t t) { return value(post.shape_closeness(t, s)); });
    k->placement_target_frame = ArrivalFrame(k->start_frame, k->end_frame, arrival,
                                             [&](int64_t t) { return value(post.placement_closeness(t, p)); });
    return;
  }
  k->target_frame = TargetFrame(k->start_frame, k->end_frame, plateau, [&](int64_t t) { return e.Key(t, p, s); });
  k->shape_target_frame =
      TargetFrame(k->start_frame, k->end_frame, plateau, [&](int64_t t) { return e.log_shape(t, s); });
  k->placement_target_frame =
      TargetFrame(k->start_frame, k->end_frame, plateau, [&](int64_t t) { return e.log_placement(t, p); });
}

// Splits frames [0, n) into m contiguous segments, in order, each at least
// min_len frames (clipped to n / m), maximising the sum of emission(t, j) over
// the frames t of segment j (dynamic programming, O(m × n)). Returns the start
// frame of every segment.
std::vector<int64_t> AlignSegments(int64_t n, int64_t m, int64_t min_len,
                                   const std::function<double(int64_t, int64_t)>& emission) {
  const int64_t lmin = std::max<int64_t>(1, std::min<int64_t>(min_len, n / m));
  // prev[t]: best score with segments 0..j-1 covering [0, t], segment j-1 ending at t.
  std::vector<double> prev(static_cast<size_t>(n), kNegInf), cur(static_cast<size_t>(n), kNegInf);
  std::vector<int32_t> start(static_cast<size_t>(m * n), -1);  // start of segment j when it ends at t
  std::vector<double> cum(static_cast<size_t>(n + 1));
  for (int64_t j = 0; j < m; ++j) {
    cum[0] = 0;
    for (int64_t t = 0; t < n; ++t) cum[t + 1] = cum[t] + emission(t, j);
    std::fill(cur.begin(), cur.end(), kNegInf);
    if (j == 0) {
      for (int64_t t = lmin - 1; t < n; ++t) {
        cur[t] = cum[t + 1];
        start[static_cast<size_t>(t)] = 0;
      }
    } else {
      // cur[t] = cum[t+1] + max_{u <= t - lmin} (prev[u] - cum[u+1]); segment starts at u + 1.
      double run = kNegInf;
      int64_t arg = -1;
      for (int64_t t = 0; t < n; ++t) {
        const int64_t u = t - lmin;
        if (u >= 0 && prev[u] > kNegInf && prev[u] - cum[u + 1] > run) {
          run = prev[u] - cum[u + 1];
          arg = u;
        }
        if (arg >= 0) {
          cur[t] = cum[t + 1] + run;
          start[static_cast<size_t>(j * n + t)] = static_cast<int32_t>(arg + 1);
        }
      }
    }
    prev.swap(cur);
  }
  if (!(prev[n - 1] > kNegInf)) throw InvalidInput("aligned decoding: no alignment (take too short)");
  std::vector<int64_t> starts(static_cast<size_t>(m));
  int64_t end = n;
  for (int64_t j = m - 1; j >= 0; --j) {
    starts[j] = start[static_cast<size_t>(j * n + end - 1)];
    end = starts[j];
  }
  return starts;
}

}  // namespace

std::string DecodeOptions::Check() const {
  if (!(min_key_ms > 0)) return "min_key_ms must be > 0";
  if (!(switch_penalty >= 0)) return "switch_penalty must be >= 0";
  if (!(aligned_min_key_ms > 0)) return "aligned_min_key_ms must be > 0";
  if (!(floor > 0 && floor < 1)) return "floor must be in (0, 1)";
  if (!(aligned_floor > 0 && aligned_floor < 1)) return "aligned_floor must be in (0, 1)";
  if (!(plateau_log >= 0)) return "plateau_log must be >= 0";
  if (!(arrival_tolerance >= 0)) return "arrival_tolerance must be >= 0";
  return "";
}

int ArgMax(const Eigen::MatrixXd& posteriors, int64_t frame) {
  Eigen::Index best = 0;
  posteriors.row(frame).maxCoeff(&best);
  return static_cast<int>(best);
}

std::vector<DecodedKey> DecodeFree(const KeyPosteriors& posteriors, double rate_hz, const DecodeOptions& options) {
  const std::string reason = options.Check();
  if (!reason.empty()) throw InvalidInput("key decoding: " + reason);
  const Emissions e = MakeEmissions(posteriors, options.floor);
  const int64_t n = posteriors.frames();
  if (n == 0) return {};
  const int d = Frames(options.min_key_ms, rate_hz);
  // State (k, c): key k, c = frames spent so far - 1, capped at d - 1.
  const int states = kKeys * d;
  std::vector<double> v(static_cast<size_t>(states), kNegInf), next(static_cast<size_t>(states));
  // Back pointer per frame and state: for c = 0 the previous key; for c = d - 1
  // whether it came from c = d - 1 (1) or d - 2 (0); otherwise implicit.
  std::vector<int16_t> back(static_cast<size_t>(n * states), -1);
  auto at = [&](int k, int c) { return static_cast<size_t>(k * d + c); };
  for (int k = 0; k < kKeys; ++k) v[at(k, 0)] = e.Key(0, k / kNumShapes, k % kNumShapes);
  for (int64_t t = 1; t < n; ++t) {
    // Best two "may leave" scores.
    int b1 = -1, b2 = -1;
    for (int k = 0; k < kKeys; ++k) {
      const double s = v[at(k, d - 1)];
      if (b1 < 0 || s > v[at(b1, d - 1)]) {
        b2 = b1;
        b1 = k;
      } else if (b2 < 0 || s > v[at(b2, d - 1)]) {
        b2 = k;
      }
    }
    int16_t* bp = &back[static_cast<size_t>(t * states)];
    for (int k = 0; k < kKeys; ++k) {
      const double em = e.Key(t, k / kNumShapes, k % kNumShapes);
      const int from = (k == b1) ? b2 : b1;
      next[at(k, 0)] = v[at(from, d - 1)] - options.switch_penalty + em;
      bp[at(k, 0)] = static_cast<int16_t>(from);
      for (int c = 1; c < d; ++c) next[at(k, c)] = v[at(k, c - 1)] + em;
      if (d > 1 && v[at(k, d - 1)] > v[at(k, d - 2)]) {
        next[at(k, d - 1)] = v[at(k, d - 1)] + em;
        bp[at(k, d - 1)] = 1;
      } else if (d > 1) {
        bp[at(k, d - 1)] = 0;
      } else {
        // d == 1: staying is (k, 0) -> (k, 0); compare with switching.
        const double stay = v[at(k, 0)] + em;
        if (stay >= next[at(k, 0)]) {
          next[at(k, 0)] = stay;
          bp[at(k, 0)] = static_cast<int16_t>(k);
        }
      }
    }
    v.swap(next);
  }
  // Best end state, back-trace the key of every frame.
  size_t best = 0;
  for (size_t i = 1; i < v.size(); ++i)
    if (v[i] > v[best]) best = i;
  std::vector<int> key_of(static_cast<size_t>(n));
  int k = static_cast<int>(best) / d, c = static_cast<int>(best) % d;
  for (int64_t t = n - 1; t >= 0; --t) {
    key_of[static_cast<size_t>(t)] = k;
    if (t == 0) break;
    const int16_t bp = back[static_cast<size_t>(t * states) + at(k, c)];
    if (c == 0) {
      k = bp;
      c = d - 1;
    } else if (c == d - 1) {
      c = bp == 1 ? d - 1 : d - 2;
    } else {
      --c;
    }
  }
  std::vector<DecodedKey> keys;
  for (int64_t t = 0; t < n; ++t) {
    const int kk = key_of[static_cast<size_t>(t)];
    if (keys.empty() || t == 0 || kk != key_of[static_cast<size_t>(t - 1)]) {
      DecodedKey key;
      key.placement = kk / kNumShapes;
      key.shape = kk % kNumShapes;
      key.start_frame = t;
      keys.push_back(key);
    }
    keys.back().end_frame = t + 1;
  }
  for (auto& key : keys) SetTargets(posteriors, e, options.plateau_log, options.arrival_tolerance, &key);
  return keys;
}

std::vector<DecodedKey> DecodeAligned(const KeyPosteriors& posteriors, const std::vector<ExpectedKey>& expected,
                                      double rate_hz, const DecodeOptions& options) {
  const std::string reason = options.Check();
  if (!reason.empty()) throw InvalidInput("key decoding: " + reason);
  if (expected.empty()) throw InvalidInput("aligned decoding: the expected key sequence is empty");
  for (const auto& x : expected)
    if (x.placement < 0 || x.placement >= kNumPlacements || x.shape < 0 || x.shape >= kNumShapes)
      throw InvalidInput("aligned decoding: expected key " + KeyCode(x.placement, x.shape) + " out of range");
  const Emissions e = MakeEmissions(posteriors, options.aligned_floor);
  const int64_t n = posteriors.frames();
  const auto m = static_cast<int64_t>(expected.size());
  if (n < m) throw InvalidInput("aligned decoding: fewer frames than expected keys");
  const std::vector<int64_t> starts =
      AlignSegments(n, m, Frames(options.aligned_min_key_ms, rate_hz),
                    [&](int64_t t, int64_t j) { return e.Key(t, expected[j].placement, expected[j].shape); });
  std::vector<DecodedKey> keys(static_cast<size_t>(m));
  for (int64_t j = 0; j < m; ++j) {
    keys[j].placement = expected[j].placement;
    keys[j].shape = expected[j].shape;
    keys[j].start_frame = starts[j];
    keys[j].end_frame = j + 1 < m ? starts[j + 1] : n;
  }
  for (auto& key : keys) SetTargets(posteriors, e, options.plateau_log, options.arrival_tolerance, &key);
  return keys;
}

std::vector<ComponentSegment> AlignComponent(const Eigen::MatrixXd& posteriors, const std::vector<int>& labels,
                                             double rate_hz, const DecodeOptions& options,
                                             const std::vector<std::pair<int64_t, int64_t>>& windows) {
  const std::string reason = options.Check();
  if (!reason.empty()) throw InvalidInput("key decoding: " + reason);
  if (labels.empty()) throw InvalidInput("aligned decoding: the expected label sequence is empty");
  for (int x : labels)
    if (x < 0 || x >= posteriors.cols())
      throw InvalidInput("aligned decoding: label " + std::to_string(x) + " out of range");
  const int64_t n = posteriors.rows();
  const auto m = static_cast<int64_t>(labels.size());
  if (n < m) throw InvalidInput("aligned decoding: fewer frames than expected labels");
  if (!windows.empty() && windows.size() != labels.size())
    throw InvalidInput("aligned decoding: " + std::to_string(windows.size()) + " windows for " +
                       std::to_string(labels.size()) + " labels");
  const Eigen::MatrixXd log_post = posteriors.array().max(options.floor).log().matrix();
  const double outside = std::log(options.floor) - 1.0;  // below any frame inside
  const std::vector<int64_t> starts =
      AlignSegments(n, m, Frames(options.aligned_min_key_ms, rate_hz), [&](int64_t t, int64_t j) {
        if (!windows.empty() && (t < windows[j].first || t >= windows[j].second)) return outside;
        return log_post(t, labels[j]);
      });
  std::vector<ComponentSegment> out(static_cast<size_t>(m));
  for (int64_t j = 0; j < m; ++j) out[j] = {labels[j], starts[j], j + 1 < m ? starts[j + 1] : n};
  return out;
}

std::vector<GestureExtent> GestureExtents(const Eigen::MatrixXd& posteriors) {
  std::vector<GestureExtent> out;
  for (int64_t t = 0; t < posteriors.rows(); ++t) {
    const int k = ArgMax(posteriors, t);
    const double v = posteriors(t, k);
    if (out.empty() || out.back().label != k) {
      out.push_back({k, t, t + 1, t, v});
    } else {
      out.back().end_frame = t + 1;
      if (v > out.back().peak) {
        out.back().peak = v;
        out.back().peak_frame = t;
      }
    }
  }
  return out;
}

std::vector<std::optional<GestureExtent>> KeyExtents(const std::vector<GestureExtent>& extents,
                                                     const std::vector<DecodedKey>& keys, Component component) {
  std::vector<std::optional<GestureExtent>> out(keys.size());
  auto label = [&](const DecodedKey& k) { return component == Component::kShape ? k.shape : k.placement; };
  for (size_t i = 0; i < keys.size(); ++i) {
    if (i > 0 && label(keys[i]) == label(keys[i - 1])) continue;
    const auto& k = keys[i];
    const int64_t target = component == Component::kShape ? k.shape_target_frame : k.placement_target_frame;
    int64_t best_dist = std::numeric_limits<int64_t>::max();
    for (const auto& x : extents) {
      if (x.label != label(k) || x.end_frame <= k.start_frame || x.start_frame >= k.end_frame) continue;
      const int64_t dist =
          target < x.start_frame ? x.start_frame - target : (target >= x.end_frame ? target - x.end_frame + 1 : 0);
      if (dist < best_dist) {
        best_dist = dist;
        out[i] = x;
      }
    }
  }
  return out;
}

EditAlignment AlignSequences(const std::vector<std::string>& decoded, const std::vector<std::string>& expected) {
  const size_t a = decoded.size(), b = expected.size();
  std::vector<std::vector<int>> cost(a + 1, std::vector<int>(b + 1, 0));
  for (size_t i = 0; i <= a; ++i) cost[i][0] = static_cast<int>(i);
  for (size_t j = 0; j <= b; ++j) cost[0][j] = static_cast<int>(j);
  for (size_t i = 1; i <= a; ++i)
    for (size_t j = 1; j <= b; ++j)
      cost[i][j] = std::min(
          {cost[i - 1][j - 1] + (decoded[i - 1] == expected[j - 1] ? 0 : 1), cost[i - 1][j] + 1, cost[i][j - 1] + 1});
  EditAlignment out;
  size_t i = a, j = b;
  while (i > 0 || j > 0) {
    if (i > 0 && j > 0 && cost[i][j] == cost[i - 1][j - 1] + (decoded[i - 1] == expected[j - 1] ? 0 : 1)) {
      if (decoded[i - 1] == expected[j - 1])
        ++out.matches;
      else
        ++out.substitutions;
      out.pairs.push_back({static_cast<int>(i - 1), static_cast<int>(j - 1)});
      --i;
      --j;
    } else if (i > 0 && cost[i][j] == cost[i - 1][j] + 1) {
      ++out.insertions;
      out.pairs.push_back({static_cast<int>(i - 1), -1});
      --i;
    } else {
      ++out.deletions;
      out.pairs.push_back({-1, static_cast<int>(j - 1)});
      --j;
    }
  }
  std::reverse(out.pairs.begin(), out.pairs.end());
  return out;
}

}  // namespace csw::keys
