#include "synth/concatenation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <numeric>

#include "core/error.h"

namespace csw::dict {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

std::string Num(double v, int digits = 3) {
  char buf[48];
  std::snprintf(buf, sizeof(buf), "%.*f", digits, v);
  return buf;
}

// Linear interpolation of matrix rows at a fractional row (clamped).
Eigen::RowVectorXd SampleRow(const Eigen::MatrixXd& m, double row) {
  const double last = static_cast<double>(m.rows() - 1);
  row = std::clamp(row, 0.0, last);
  const auto r0 = static_cast<Eigen::Index>(std::floor(row));
  const Eigen::Index r1 = std::min<Eigen::Index>(r0 + 1, m.rows() - 1);
  const double frac = row - static_cast<double>(r0);
  if (frac == 0.0) return m.row(r0);
  return (1.0 - frac) * m.row(r0) + frac * m.row(r1);
}

// Column standard deviations of row blocks, accumulated (shifted by the
// first row seen, against cancellation).
struct ColumnSpread {
  Eigen::ArrayXd shift, sum, sum_sq;
  void Add(const Eigen::MatrixXd& block, Eigen::Index col) {
    const Eigen::Index c = block.cols();
    if (sum.size() < col + c) {
      shift.conservativeResize(col + c);
      sum.conservativeResize(col + c);
      sum_sq.conservativeResize(col + c);
      shift.segment(col, c) = block.row(0).transpose().array();
      sum.segment(col, c).setZero();
      sum_sq.segment(col, c).setZero();
    }
    for (Eigen::Index r = 0; r < block.rows(); ++r) {
      const Eigen::ArrayXd x = block.row(r).transpose().array() - shift.segment(col, c);
      sum.segment(col, c) += x;
      sum_sq.segment(col, c) += x.square();
    }
  }
};

// Standard deviations of the first c columns over `rows` frames (1 where
// not above 1e-12 of the largest, or for every column when there is one row).
Eigen::VectorXd ColumnSigma(const ColumnSpread& spread, double rows, Eigen::Index c) {
  Eigen::VectorXd sigma = Eigen::VectorXd::Ones(c);
  if (rows > 1) {
    const Eigen::ArrayXd mean = spread.sum.head(c) / rows;
    sigma = ((spread.sum_sq.head(c) - rows * mean.square()).max(0.0) / (rows - 1)).sqrt().matrix();
    const double big = sigma.maxCoeff();
    for (Eigen::Index j = 0; j < c; ++j)
      if (!(sigma(j) > 1e-12 * big) || !(sigma(j) > 0)) sigma(j) = 1.0;
  }
  return sigma;
}

// Per-column factors a_c = sqrt(w_c / Σw) / σ_c, so that the weighted RMS
// jump of Δ is ‖a ∘ Δ‖. σ_c = ColumnSigma.
Eigen::VectorXd JumpFactors(const ColumnSpread& spread, double rows, const Eigen::VectorXd& weights) {
  const Eigen::Index c = weights.size();
  const Eigen::VectorXd sigma = ColumnSigma(spread, rows, c);
  const double total = weights.sum();
  Eigen::VectorXd a(c);
  for (Eigen::Index j = 0; j < c; ++j) a(j) = total > 0 ? std::sqrt(weights(j) / total) / sigma(j) : 0.0;
  return a;
}

Eigen::VectorXd Weights(const Eigen::VectorXd& given, Eigen::Index n, const std::string& what) {
  if (given.size() == 0) return Eigen::VectorXd::Ones(n);
  if (given.size() != n) {
    throw InvalidInput(what + " has " + std::to_string(given.size()) + " values, the dictionary " + std::to_string(n) +
                       " parameters");
  }
  return given;
}

// A running mean of row vectors.
struct Mean {
  Eigen::RowVectorXd sum;
  int count = 0;
  void Add(const Eigen::RowVectorXd& v) {
    if (count == 0) sum = Eigen::RowVectorXd::Zero(v.size());
    sum += v;
    ++count;
  }
  Eigen::RowVectorXd Value() const { return sum / static_cast<double>(count); }
};

// Viterbi over slots: local[i][c] and join(i, c_prev, c) costs; returns the
// best path and its total.
template <typename JoinFn>
std::vector<int> Viterbi(const std::vector<std::vector<double>>& local, JoinFn join, double* total) {
  const size_t n = local.size();
  std::vector<std::vector<double>> cost(n);
  std::vector<std::vector<int>> back(n);
  cost[0] = local[0];
  back[0].assign(local[0].size(), -1);
  for (size_t i = 1; i < n; ++i) {
    cost[i].assign(local[i].size(), kInf);
    back[i].assign(local[i].size(), -1);
    for (size_t c = 0; c < local[i].size(); ++c) {
      for (size_t p = 0; p < local[i - 1].size(); ++p) {
        const double v = cost[i - 1][p] + join(i, static_cast<int>(p), static_cast<int>(c));
        if (v < cost[i][c]) {
          cost[i][c] = v;
          back[i][c] = static_cast<int>(p);
        }
      }
      cost[i][c] += local[i][c];
    }
  }
  std::vector<int> path(n);
  const auto best = std::min_element(cost[n - 1].begin(), cost[n - 1].end());
  *total = *best;
  path[n - 1] = static_cast<int>(best - cost[n - 1].begin());
  for (size_t i = n - 1; i > 0; --i) path[i - 1] = back[i][static_cast<size_t>(path[i])];
  return path;
}

// The indices of `units` with the `keep` smallest duration mismatches
// (stable: ties keep dictionary order).
std::vector<int> ClosestInDuration(std::vector<int> units, const std::vector<double>& mismatch, int keep) {
  std::stable_sort(units.begin(), units.end(),
                   [&](int a, int b) { return mismatch[static_cast<size_t>(a)] < mismatch[static_cast<size_t>(b)]; });
  if (static_cast<int>(units.size()) > keep) units.resize(static_cast<size_t>(keep));
  return units;
}

// Output frames of the key times, checked.
std::vector<int64_t> KeyFrames(const std::vector<double>& times, double duration_s, double rate,
                               const std::string& what) {
  if (!std::isfinite(duration_s) || duration_s < 0)
    throw InvalidInput("duration " + Num(duration_s) + " s is not valid");
  const auto last_frame = static_cast<int64_t>(std::llround(duration_s * rate));
  std::vector<int64_t> frames;
  for (size_t i = 0; i < times.size(); ++i) {
    const double t = times[i];
    if (!std::isfinite(t)) throw InvalidInput(what + " " + std::to_string(i + 1) + ": time is not finite");
    if (t < 0 || t > duration_s + 0.5 / rate) {
      throw InvalidInput(what + " " + std::to_string(i + 1) + ": time " + Num(t) + " s is outside [0, " +
                         Num(duration_s) + "] s");
    }
    if (i > 0 && !(t > times[i - 1])) {
      throw InvalidInput(what + " " + std::to_string(i + 1) + ": time " + Num(t) + " s is not after the previous (" +
                         Num(times[i - 1]) + " s)");
    }
    // A time up to half a frame past the end lands on the last frame.
    frames.push_back(std::min(static_cast<int64_t>(std::llround(t * rate)), last_frame));
  }
  return frames;
}

// Writes the slots' frames into `out` (frames × C). sample(i, u) gives slot
// i's value at u in [0, 1] (u = 0 at its first key frame, 1 at the next);
// first(i)/last(i) its values at u = 0 and 1. With smoothing, the jump from
// last(i) to the first value of the next slot that has frames (for the last
// slot: to end_value(i), the intended end value) is added as u · jump over slot i.
// Frames before the first key and after the last hold.
template <typename SampleFn, typename FirstFn, typename LastFn, typename EndFn>
void Render(const std::vector<int64_t>& key_frames, bool smoothing, SampleFn sample, FirstFn first, LastFn last,
            EndFn end_value, Eigen::MatrixXd* out) {
  const size_t slots = key_frames.size() - 1;
  const int64_t frames = out->rows();
  std::vector<size_t> written;
  for (size_t i = 0; i < slots; ++i)
    if (key_frames[i + 1] > key_frames[i]) written.push_back(i);
  if (written.empty()) {  // every key on one frame: the first slot's start value
    const Eigen::RowVectorXd v = first(0);
    for (Eigen::Index f = 0; f < out->rows(); ++f) out->row(f) = v;
    return;
  }
  for (size_t w = 0; w < written.size(); ++w) {
    const size_t i = written[w];
    Eigen::RowVectorXd jump = Eigen::RowVectorXd::Zero(out->cols());
    if (smoothing) jump = (w + 1 < written.size() ? first(written[w + 1]) : end_value(i)) - last(i);
    const int64_t f0 = key_frames[i], f1 = key_frames[i + 1];
    const double n = static_cast<double>(f1 - f0);
    for (int64_t f = (w == 0 ? f0 : f0 + 1); f <= f1; ++f) {
      if (f < 0 || f >= frames) continue;
      const double u = static_cast<double>(f - f0) / n;
      out->row(f) = sample(i, u) + u * jump;
    }
  }
  const int64_t start = std::clamp<int64_t>(key_frames[written.front()], 0, frames - 1);
  const int64_t end = std::clamp<int64_t>(key_frames[written.back() + 1], 0, frames - 1);
  for (int64_t f = 0; f < start; ++f) out->row(f) = out->row(start);
  for (int64_t f = end + 1; f < frames; ++f) out->row(f) = out->row(end);
}

// ---------------------------------------------------------------------------
// Dikeys.

// A dikey unit's row r as one vector [hand P | forearm_in_head 6 | head 6].
Eigen::RowVectorXd DikeyRow(const DikeyUnit& u, double row) {
  const Eigen::RowVectorXd h = SampleRow(u.hand_params, row), f = SampleRow(u.forearm_in_head, row),
                           p = SampleRow(u.head_pose, row);
  Eigen::RowVectorXd v(h.size() + 12);
  v << h, f, p;
  return v;
}

// How a slot's fraction u in [0, 1] maps onto one stream of its unit (unit
// fractions: row / (frames − 1)): piecewise linear through knots (slot,
// unit), both increasing; two knots at one slot fraction are a cut (the
// unit's rows between them are skipped: a stretch of hold). The unit's rows
// before the first knot's are trimmed away.
struct StreamWarp {
  std::vector<std::pair<double, double>> knots = {{0.0, 0.0}, {1.0, 1.0}};
  double UnitFraction(double u) const {
    if (u <= knots.front().first) return knots.front().second;
    for (size_t k = 1; k < knots.size(); ++k) {
      const auto& [s0, f0] = knots[k - 1];
      const auto& [s1, f1] = knots[k];
      if (u < s1) return s1 > s0 ? f0 + (u - s0) / (s1 - s0) * (f1 - f0) : f1;
    }
    return knots.back().second;
  }
  // The inverse (clamped to [0, 1]): where a unit fraction lands in the slot.
  double SlotFraction(double f) const {
    if (f <= knots.front().second) return 0.0;
    for (size_t k = 1; k < knots.size(); ++k) {
      const auto& [s0, f0] = knots[k - 1];
      const auto& [s1, f1] = knots[k];
      if (f < f1) return f1 > f0 ? std::max(s0, s0 + (f - f0) / (f1 - f0) * (s1 - s0)) : s0;
    }
    return 1.0;
  }
  // ConcatOptions::movement_onsets (planned): the knots map only the
  // arrival and hold (unit fractions 0 to movement_from, held there once
  // reached); the movement, unit fractions movement_from to 1, is laid
  // linearly from slot fraction movement_start (negative: before the slot)
  // to 1 and added as a displacement from the row at movement_from.
  bool planned = false;
  double movement_from = 1, movement_start = 0;
  // The movement's unit fraction at slot fraction u (any u; NaN before it
  // starts or without a planned movement).
  double MovementFraction(double u) const {
    if (!planned || u < movement_start) return std::numeric_limits<double>::quiet_NaN();
    return std::min(1.0, movement_from + (u - movement_start) / (1.0 - movement_start) * (1.0 - movement_from));
  }
  bool trimmed() const { return !planned && knots.front().second > 1e-12; }
};

// The unit's last `shown` seconds of `unit_s`, warped linearly onto the slot.
StreamWarp LastPart(double unit_s, double shown) {
  StreamWarp w;
  w.knots = {{0.0, std::clamp((unit_s - shown) / unit_s, 0.0, 1.0)}, {1.0, 1.0}};
  return w;
}

// The fraction of a unit's rows trimmed from its start so that it is
// compressed at most max_compression times onto a slot of slot_s seconds.
double TrimFraction(double unit_s, double slot_s, double max_compression) {
  if (max_compression <= 0 || !(unit_s > max_compression * slot_s)) return 0.0;
  return 1.0 - max_compression * slot_s / unit_s;
}

// ConcatOptions::keep_movement_duration. A stream of a unit of unit_s
// seconds arrives at its leaving key until arrival_s (0: it starts there),
// holds it until onset_s and then moves to the arriving key (onset_s =
// unit_s: it only holds).
StreamWarp MakeWarp(double unit_s, double slot_s, double arrival_s, double onset_s, const ConcatOptions& o) {
  if (!(unit_s > 0) || !(slot_s > 0)) return StreamWarp{};
  if (!o.keep_movement_duration)
    return LastPart(unit_s, (1.0 - TrimFraction(unit_s, slot_s, o.max_compression)) * unit_s);
  const double cmax = o.max_compression > 0 ? o.max_compression : std::numeric_limits<double>::infinity();
  const double m = std::clamp(onset_s, 0.0, unit_s), l = std::clamp(arrival_s, 0.0, m);
  const double arrival = l, hold = m - l, movement = unit_s - m;
  auto f = [&](double t) { return t / unit_s; };
  auto s = [&](double t) { return t / slot_s; };
  StreamWarp w;
  if (slot_s >= arrival + movement) {
    // Arrival and movement at their own speed; the hold fills the rest of
    // the slot, stretched, or compressed at most cmax times with its middle
    // cut beyond.
    const double room = slot_s - arrival - movement;
    w.knots = {{0.0, 0.0}, {s(arrival), f(l)}};
    if (hold <= cmax * room) {
      w.knots.push_back({s(arrival + room), f(m)});
    } else {
      const double half = 0.5 * cmax * room;
      w.knots.push_back({s(arrival + 0.5 * room), f(l + half)});
      w.knots.push_back({s(arrival + 0.5 * room), f(m - half)});
      w.knots.push_back({s(arrival + room), f(m)});
    }
    w.knots.push_back({1.0, 1.0});
    return w;
  }
  // Too short: the hold is cut and arrival and movement compressed together,
  // at most cmax times (the start trimmed beyond).
  const double shown = std::min(arrival + movement, cmax * slot_s);
  if (shown <= movement) return LastPart(unit_s, shown);
  const double c = shown / slot_s, kept_arrival = shown - movement;
  w.knots = {{0.0, f(l - kept_arrival)}, {s(kept_arrival / c), f(l)}, {s(kept_arrival / c), f(m)}, {1.0, 1.0}};
  return w;
}

// ConcatOptions::movement_onsets. A stream of a unit of unit_s seconds
// arrives at its leaving key until arrival_s, holds it until onset_s and
// moves to the arriving key; the movement is laid linearly from start_s
// (re the slot's start; negative: before it) to the slot's end, superposed
// on the arrival (at its own speed) and the hold (stretched until the
// movement starts, or shown within a tenth of the slot after the arrival
// when the movement starts earlier).
StreamWarp OnsetWarp(double unit_s, double slot_s, double arrival_s, double onset_s, double start_s) {
  StreamWarp w;
  if (!(unit_s > 0) || !(slot_s > 0) || !(start_s < slot_s)) return w;
  const double m = std::clamp(onset_s, 0.0, unit_s), l = std::clamp(arrival_s, 0.0, m);
  const double a = std::min(l, slot_s);
  const double hold_end = start_s > a ? start_s : std::min(slot_s, a + std::min(m - l, 0.1 * slot_s));
  w.knots = {{0.0, 0.0}};
  if (a > 0 && a < hold_end) w.knots.push_back({a / slot_s, l / unit_s});
  if (hold_end > 0) w.knots.push_back({hold_end / slot_s, m / unit_s});
  w.knots.push_back({1.0, m / unit_s});
  w.planned = true;
  w.movement_from = m / unit_s;
  w.movement_start = start_s / slot_s;
  return w;
}

// When a stream's movement starts in a unit (s after its first row): the
// last frame before the stream's fastest after `from_s` where its speed (the
// RMS change of its columns per frame, each in units of `inv_sigma`⁻¹,
// averaged over 5 frames) is at most a tenth of that peak speed; from_s
// when no frame between is that slow.
double MovementOnset(const Eigen::MatrixXd& x, const Eigen::VectorXd& inv_sigma, double rate_hz, double from_s) {
  const Eigen::Index n = x.rows();
  if (n < 3 || !(rate_hz > 0)) return 0.0;
  Eigen::VectorXd speed(n - 1);
  for (Eigen::Index r = 0; r + 1 < n; ++r)
    speed(r) = ((x.row(r + 1) - x.row(r)).transpose().array() * inv_sigma.array()).matrix().norm();
  Eigen::VectorXd smooth(n - 1);
  for (Eigen::Index r = 0; r + 1 < n; ++r) {
    const Eigen::Index lo = std::max<Eigen::Index>(0, r - 2), hi = std::min<Eigen::Index>(n - 2, r + 2);
    smooth(r) = speed.segment(lo, hi - lo + 1).mean();
  }
  const Eigen::Index first = std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::ceil(from_s * rate_hz)), 0, n - 2);
  Eigen::Index peak = 0;
  smooth.tail(n - 1 - first).maxCoeff(&peak);
  peak += first;
  const double limit = 0.1 * smooth(peak);
  for (Eigen::Index r = peak; r >= first; --r)
    if (smooth(r) <= limit) return static_cast<double>(r) / rate_hz;
  return static_cast<double>(first) / rate_hz;
}

struct DikeyCandidate {
  FallbackLevel level = FallbackLevel::kWhole;
  int shape_unit = -1, pose_unit = -1;  // the same unit for levels 0 and 1
  // Each stream's warp onto the slot (ConcatOptions::max_compression,
  // keep_movement_duration).
  StreamWarp shape_warp, pose_warp;
  // With ConcatOptions::trim_keeps_key_posture: the untrimmed first row minus
  // the trimmed one, added as (1 − u) · offset over the slot, so the key
  // posture is held at its frame and the trimmed movement catches up.
  Eigen::RowVectorXd key_offset;
  KeyCode used_to;
  double selection = 0;  // RMS duration mismatch (s)
  // Values at u = 0 and 1, and the intended value at the arriving key (= last
  // but at level 1, whose forearm-in-head is the intended placement's mean):
  // the smoothing's target after the last slot.
  Eigen::RowVectorXd first, last, end;
};

// Learned from the dictionary: per shape the mean hand parameters, per
// placement the mean forearm-in-head and head pose, at every key instant
// (units' first and last rows); per whole key code every instance's hand
// parameters and forearm-in-head pose (the posture pull).
struct KeyClasses {
  std::map<int, Mean> shape, placement;
  std::map<std::string, std::vector<Eigen::RowVectorXd>> postures;
  bool keep_postures = false;  // fill `postures` (only the pull needs them)
  void Add(const KeyCode& code, const DikeyUnit& u, Eigen::Index row) {
    shape[code.shape].Add(u.hand_params.row(row));
    Eigen::RowVectorXd pose(12);
    pose << u.forearm_in_head.row(row), u.head_pose.row(row);
    placement[code.placement].Add(pose);
    if (!keep_postures) return;
    Eigen::RowVectorXd posture(u.hand_params.cols() + 6);
    posture << u.hand_params.row(row), u.forearm_in_head.row(row);
    postures[code.Text()].push_back(std::move(posture));
  }
  bool Has(const KeyCode& k) const { return shape.count(k.shape) && placement.count(k.placement); }
  Eigen::RowVectorXd Of(const KeyCode& k) const {
    const Eigen::RowVectorXd h = shape.at(k.shape).Value(), p = placement.at(k.placement).Value();
    Eigen::RowVectorXd v(h.size() + p.size());
    v << h, p;
    return v;
  }
  // Mean forearm-in-head translation (mm) of a placement.
  Eigen::Vector3d Translation(int placement_class) const {
    return placement.at(placement_class).Value().segment(3, 3).transpose();
  }
};

// A key code's postures: their mean, per-column standard deviation (at
// least `floor`) and exemplar (the instance nearest the mean in those
// deviations).
struct PostureClass {
  Eigen::RowVectorXd mean, sd, exemplar;
};
PostureClass MakePostureClass(const std::vector<Eigen::RowVectorXd>& rows, const Eigen::RowVectorXd& floor) {
  Mean m, sq;
  for (const Eigen::RowVectorXd& r : rows) {
    m.Add(r);
    sq.Add(r.array().square().matrix());
  }
  PostureClass c;
  c.mean = m.Value();
  c.sd = (sq.Value().array() - c.mean.array().square()).max(0.0).sqrt().matrix().cwiseMax(floor);
  double best = kInf;
  for (const Eigen::RowVectorXd& r : rows) {
    const double d = (r - c.mean).cwiseQuotient(c.sd).squaredNorm();
    if (d < best) {
      best = d;
      c.exemplar = r;
    }
  }
  return c;
}

// Adds to `m` (frames × c) the corrections `corr` (one row per point, at
// strictly increasing frames `at`), blended by minimum-jerk ramps between
// points and held before the first and after the last.
void AddRamped(const std::vector<int64_t>& at, const std::vector<Eigen::RowVectorXd>& corr, Eigen::MatrixXd* m) {
  size_t k = 0;
  for (int64_t f = 0; f < m->rows(); ++f) {
    while (k < at.size() && at[k] <= f) ++k;  // at[k-1] <= f < at[k]
    if (k == 0) {
      m->row(f) += corr.front();
    } else if (k == at.size()) {
      m->row(f) += corr.back();
    } else {
      const double u = static_cast<double>(f - at[k - 1]) / static_cast<double>(at[k] - at[k - 1]);
      m->row(f) += corr[k - 1] + MinimumJerk(u) * (corr[k] - corr[k - 1]);
    }
  }
}

void CheckDikeys(const Dictionary& d) {
  if (d.dikeys.empty()) throw InvalidInput("the dictionary has no dikey units");
  const Eigen::Index p = d.dikeys.front().hand_params.cols();
  for (size_t i = 0; i < d.dikeys.size(); ++i) {
    const DikeyUnit& u = d.dikeys[i];
    const std::string where =
        "dikey unit " + std::to_string(i) + " (take '" + u.take + "', " + SuccessionCode(u.from, u.to) + ")";
    if (u.frames() < 1 || u.hand_params.cols() != p || u.forearm_in_head.rows() != u.frames() ||
        u.head_pose.rows() != u.frames() || u.forearm_in_head.cols() != 6 || u.head_pose.cols() != 6) {
      throw InvalidInput(where + ": its series have inconsistent sizes");
    }
    if (!u.hand_params.allFinite() || !u.forearm_in_head.allFinite() || !u.head_pose.allFinite()) {
      throw InvalidInput(where + ": a value is not finite");
    }
    if (!std::isfinite(u.duration_s())) throw InvalidInput(where + ": its times are not finite");
  }
}

}  // namespace

std::string ConcatOptions::Check() const {
  if (!(rate_hz > 0) || !std::isfinite(rate_hz)) return "rate_hz must be positive";
  if (!(selection_weight >= 0) || !std::isfinite(selection_weight)) return "selection_weight must be >= 0";
  if (!(concatenation_weight >= 0) || !std::isfinite(concatenation_weight)) return "concatenation_weight must be >= 0";
  if (!(target_weight >= 0) || !std::isfinite(target_weight)) return "target_weight must be >= 0";
  if (hand_weights.size() && !(hand_weights.allFinite() && hand_weights.minCoeff() >= 0))
    return "hand_weights must be finite and >= 0";
  if (face_weights.size() && !(face_weights.allFinite() && face_weights.minCoeff() >= 0))
    return "face_weights must be finite and >= 0";
  if (max_fallback_level < 0 || max_fallback_level > 3) return "max_fallback_level must be in 0-3";
  if (max_stream_candidates < 1) return "max_stream_candidates must be >= 1";
  if (!(posture_radius >= 0) || !std::isfinite(posture_radius)) return "posture_radius must be >= 0";
  if (posture_min_instances < 1) return "posture_min_instances must be >= 1";
  if (!(max_compression == 0 || (max_compression >= 1 && max_compression < 1e6)))
    return "max_compression must be 0 or >= 1";
  if (keep_movement_duration && movement_onsets) return "keep_movement_duration and movement_onsets exclude each other";
  if (!(max_onset_overlap >= 0 && max_onset_overlap <= 1)) return "max_onset_overlap must be in [0, 1]";
  return "";
}

const char* FallbackLevelName(FallbackLevel level) {
  switch (level) {
    case FallbackLevel::kWhole:
      return "whole";
    case FallbackLevel::kClosestPlacement:
      return "closest placement";
    case FallbackLevel::kTwoStreams:
      return "two streams";
    case FallbackLevel::kInterpolated:
      return "interpolated";
  }
  return "?";
}

double MinimumJerk(double u) {
  u = std::clamp(u, 0.0, 1.0);
  return u * u * u * (10.0 + u * (-15.0 + 6.0 * u));
}

namespace {

// ConcatOptions::posture_radius on a rendered track.
void PullKeyPostures(const KeyClasses& classes, const ColumnSpread& spread, double rows,
                     const std::vector<KeyTarget>& keys, const std::vector<int64_t>& key_frames, const ConcatOptions& o,
                     HandTrack* out) {
  const Eigen::Index P = out->hand_params.cols();
  // Each column's spread over every frame, the floor of the classes' own.
  const Eigen::RowVectorXd all_sd = ColumnSigma(spread, rows, P + 6).transpose();
  std::map<std::string, PostureClass> made;
  const double n = std::sqrt(static_cast<double>(P + 6));
  const int64_t last = out->frames() - 1;
  std::vector<int64_t> at;
  std::vector<Eigen::RowVectorXd> corr;
  out->postures.assign(keys.size(), KeyPosture{});
  for (size_t i = 0; i < keys.size(); ++i) {
    const int64_t f = std::clamp<int64_t>(key_frames[i], 0, last);
    if (!at.empty() && f <= at.back()) continue;  // a key on the previous key's frame
    Eigen::RowVectorXd c = Eigen::RowVectorXd::Zero(P + 6);
    const std::string code = keys[i].code.Text();
    const auto instances = classes.postures.find(code);
    if (instances != classes.postures.end() && static_cast<int>(instances->second.size()) >= o.posture_min_instances) {
      auto it = made.find(code);
      if (it == made.end()) it = made.emplace(code, MakePostureClass(instances->second, 0.1 * all_sd)).first;
      const PostureClass& pc = it->second;
      Eigen::RowVectorXd v(P + 6);
      v << out->hand_params.row(f), out->forearm_in_head.row(f);
      const double dist = (v - pc.mean).cwiseQuotient(pc.sd).norm() / n;
      out->postures[i].distance = dist;
      if (dist > o.posture_radius) {
        // Toward the exemplar, stopping posture_radius from it.
        const double to_exemplar = (v - pc.exemplar).cwiseQuotient(pc.sd).norm() / n;
        if (to_exemplar > o.posture_radius) {
          c = (pc.exemplar - v) * (1.0 - o.posture_radius / to_exemplar);
          out->postures[i].pulled = true;
        }
      }
    }
    at.push_back(f);
    corr.push_back(std::move(c));
  }
  std::vector<Eigen::RowVectorXd> hand, pose;
  for (const Eigen::RowVectorXd& c : corr) {
    hand.push_back(c.head(P));
    pose.push_back(c.tail(6));
  }
  AddRamped(at, hand, &out->hand_params);
  AddRamped(at, pose, &out->forearm_in_head);
}

}  // namespace

HandTrack ConcatenateDikeys(const Dictionary& d, const std::vector<KeyTarget>& keys, double duration_s,
                            const ConcatOptions& o) {
  if (const std::string why = o.Check(); !why.empty()) throw InvalidInput(why);
  CheckDikeys(d);
  if (keys.size() < 2)
    throw InvalidInput("need at least two keys (rest 00 at both ends), got " + std::to_string(keys.size()));
  for (size_t i = 0; i < keys.size(); ++i) {
    const KeyCode& k = keys[i].code;
    if (k.placement < 0 || k.placement > kMaxPlacement || k.shape < 0 || k.shape > kMaxShape)
      throw InvalidInput("key " + std::to_string(i + 1) + ": not a key code (" + std::to_string(k.placement) + ", " +
                         std::to_string(k.shape) + ")");
  }
  std::vector<double> times;
  for (const KeyTarget& k : keys) times.push_back(k.target_s);
  const std::vector<int64_t> key_frames = KeyFrames(times, duration_s, o.rate_hz, "key");

  const Eigen::Index P = d.dikeys.front().hand_params.cols();
  const Eigen::Index C = P + 12;
  // Scales: every frame of every unit.
  ColumnSpread spread;
  double rows = 0;
  for (const DikeyUnit& u : d.dikeys) {
    spread.Add(u.hand_params, 0);
    spread.Add(u.forearm_in_head, P);
    spread.Add(u.head_pose, P + 6);
    rows += static_cast<double>(u.frames());
  }
  Eigen::VectorXd w(C);
  w << Weights(o.hand_weights, P, "hand_weights"), Eigen::VectorXd::Ones(12);
  const Eigen::VectorXd a = JumpFactors(spread, rows, w);
  auto jump_cost = [&](const Eigen::RowVectorXd& from, const Eigen::RowVectorXd& to) {
    return (a.transpose().array() * (to - from).array()).matrix().norm();
  };

  // Each unit's movement onsets, per stream (ConcatOptions::keep_movement_duration):
  // a stream whose key component does not change holds all along.
  // The pose stream first arrives at the leaving key's placement (DikeyUnit::from_placement_lag_s).
  std::vector<double> shape_onset(d.dikeys.size()), pose_onset(d.dikeys.size()), pose_arrival(d.dikeys.size());
  if (o.keep_movement_duration || o.movement_onsets) {
    const Eigen::VectorXd inv = ColumnSigma(spread, rows, P + 6).cwiseInverse();
    for (size_t j = 0; j < d.dikeys.size(); ++j) {
      const DikeyUnit& u = d.dikeys[j];
      const double lag = u.from_placement_lag_s;
      pose_arrival[j] = std::isfinite(lag) && lag > 0 ? std::min(lag, u.duration_s()) : 0.0;
      shape_onset[j] =
          u.from.shape == u.to.shape ? u.duration_s() : MovementOnset(u.hand_params, inv.head(P), u.rate_hz, 0.0);
      pose_onset[j] = u.from.placement == u.to.placement
                          ? u.duration_s()
                          : MovementOnset(u.forearm_in_head, inv.tail(6), u.rate_hz, pose_arrival[j]);
    }
  }
  // ConcatOptions::movement_onsets: where unit j's movement (from onset_s)
  // starts in slot i (keys i → i + 1, slot_s long), re the slot's start;
  // nullopt: warped as without the option.
  auto planned_start = [&](int j, size_t i, double onset_s, double slot_s) -> std::optional<double> {
    const DikeyUnit& u = d.dikeys[static_cast<size_t>(j)];
    const KeyTarget& k = keys[i + 1];
    const double movement = u.duration_s() - onset_s;
    if (!o.movement_onsets || !(movement > 0) || !std::isfinite(k.a1_s) || !std::isfinite(u.phasing_s))
      return std::nullopt;
    if (u.to_type && k.type && *u.to_type != *k.type) return std::nullopt;
    const double room = i > 0 ? o.max_onset_overlap * (keys[i].target_s - keys[i - 1].target_s) : 0.0;
    const double cmax = o.max_compression > 0 ? o.max_compression : kInf;
    const double start =
        std::min(std::max(k.a1_s + u.phasing_s - movement - keys[i].target_s, -room), slot_s - movement / cmax);
    if (start < -room) return std::nullopt;  // even the compressed movement would overlap too much
    return start;
  };
  auto shape_warp = [&](int j, size_t i, double slot_s) {
    const DikeyUnit& u = d.dikeys[static_cast<size_t>(j)];
    const double onset = shape_onset[static_cast<size_t>(j)];
    if (const auto start = planned_start(j, i, onset, slot_s))
      return OnsetWarp(u.duration_s(), slot_s, 0.0, onset, *start);
    return MakeWarp(u.duration_s(), slot_s, 0.0, onset, o);
  };
  auto pose_warp = [&](int j, size_t i, double slot_s) {
    const DikeyUnit& u = d.dikeys[static_cast<size_t>(j)];
    const double onset = pose_onset[static_cast<size_t>(j)], arrival = pose_arrival[static_cast<size_t>(j)];
    if (const auto start = planned_start(j, i, onset, slot_s))
      return OnsetWarp(u.duration_s(), slot_s, arrival, onset, *start);
    return MakeWarp(u.duration_s(), slot_s, arrival, onset, o);
  };
  // A planned stream whose movement starts before the slot begins it, for
  // the joins and the smoothing, at its unit's first row: the movement's
  // displacement until the slot's start is added to the previous slot.
  auto overlap_fix = [&](DikeyCandidate& c) {
    const DikeyUnit &us = d.dikeys[static_cast<size_t>(c.shape_unit)], &up = d.dikeys[static_cast<size_t>(c.pose_unit)];
    if (c.shape_warp.planned) {
      c.first.head(P) = us.hand_params.row(0);
      if (c.key_offset.size()) c.key_offset.head(P).setZero();
    }
    if (c.pose_warp.planned) {
      c.first.tail(12) = DikeyRow(up, 0.0).tail(12);
      if (c.key_offset.size()) c.key_offset.tail(12).setZero();
    }
  };
  // A candidate's two streams at slot fraction u, each through its warp.
  auto unit_row = [](const DikeyUnit& u, const StreamWarp& w, double f) {
    return w.UnitFraction(f) * static_cast<double>(u.frames() - 1);
  };
  // A planned movement's displacement at slot fraction f (zero before it starts).
  auto displacement = [](const DikeyUnit& u, const StreamWarp& w, double f) {
    const double g = w.MovementFraction(f);
    const double rows = static_cast<double>(u.frames() - 1);
    if (!std::isfinite(g)) return Eigen::RowVectorXd(Eigen::RowVectorXd::Zero(u.hand_params.cols() + 12));
    return Eigen::RowVectorXd(DikeyRow(u, g * rows) - DikeyRow(u, w.movement_from * rows));
  };
  auto streams_at = [&](int s, const StreamWarp& ws, int p, const StreamWarp& wp, double f) {
    const DikeyUnit &us = d.dikeys[static_cast<size_t>(s)], &up = d.dikeys[static_cast<size_t>(p)];
    Eigen::RowVectorXd v = DikeyRow(us, unit_row(us, ws, f));
    v.tail(12) = DikeyRow(up, unit_row(up, wp, f)).tail(12);
    if (ws.planned) v.head(P) += displacement(us, ws, f).head(P);
    if (wp.planned) v.tail(12) += displacement(up, wp, f).tail(12);
    return v;
  };

  KeyClasses classes;
  classes.keep_postures = o.posture_radius > 0;
  for (const DikeyUnit& u : d.dikeys) {
    classes.Add(u.from, u, 0);
    classes.Add(u.to, u, u.frames() - 1);
  }

  const size_t slots = keys.size() - 1;
  std::vector<std::vector<DikeyCandidate>> cands(slots);
  const int n_units = static_cast<int>(d.dikeys.size());
  for (size_t i = 0; i < slots; ++i) {
    const KeyCode k0 = keys[i].code, k1 = keys[i + 1].code;
    const double target = keys[i + 1].target_s - keys[i].target_s;
    std::vector<double> mismatch(d.dikeys.size());
    for (int j = 0; j < n_units; ++j)
      mismatch[static_cast<size_t>(j)] = d.dikeys[static_cast<size_t>(j)].duration_s() - target;
    auto whole = [&](const KeyCode& to, FallbackLevel level) {
      for (int j = 0; j < n_units; ++j) {
        const DikeyUnit& u = d.dikeys[static_cast<size_t>(j)];
        if (u.from != k0 || u.to != to) continue;
        DikeyCandidate c;
        c.level = level;
        c.shape_unit = c.pose_unit = j;
        c.shape_warp = shape_warp(j, i, target);
        c.pose_warp = pose_warp(j, i, target);
        c.used_to = to;
        c.selection = std::abs(mismatch[static_cast<size_t>(j)]);
        c.first = streams_at(j, c.shape_warp, j, c.pose_warp, 0);
        if (o.trim_keeps_key_posture && (c.shape_warp.trimmed() || c.pose_warp.trimmed())) {
          const Eigen::RowVectorXd untrimmed = DikeyRow(u, 0.0);
          c.key_offset = untrimmed - c.first;
          c.first = untrimmed;
        }
        overlap_fix(c);
        c.last = DikeyRow(u, static_cast<double>(u.frames() - 1));
        c.end = c.last;
        if (level == FallbackLevel::kClosestPlacement)
          c.end.segment(P, 6) = classes.placement.at(k1.placement).Value().head(6);
        cands[i].push_back(std::move(c));
      }
    };
    std::vector<DikeyCandidate>& list = cands[i];
    // Level 0: whole dikeys.
    whole(k1, FallbackLevel::kWhole);
    // Level 1: the arriving placement replaced by the closest present (same
    // leaving key, same arriving shape).
    if (list.empty() && o.max_fallback_level >= 1 && classes.placement.count(k1.placement)) {
      const Eigen::Vector3d want = classes.Translation(k1.placement);
      int best = -1;
      double best_d = kInf;
      for (const DikeyUnit& u : d.dikeys) {
        if (u.from != k0 || u.to.shape != k1.shape || u.to.placement == k1.placement) continue;
        const double dist = (classes.Translation(u.to.placement) - want).norm();
        if (dist < best_d || (dist == best_d && u.to.placement < best)) {
          best_d = dist;
          best = u.to.placement;
        }
      }
      if (best >= 0) whole(KeyCode{best, k1.shape}, FallbackLevel::kClosestPlacement);
    }
    // Level 2: two streams.
    if (list.empty() && o.max_fallback_level >= 2) {
      std::vector<int> shape_units, pose_units;
      for (int j = 0; j < n_units; ++j) {
        const DikeyUnit& u = d.dikeys[static_cast<size_t>(j)];
        if (u.from.shape == k0.shape && u.to.shape == k1.shape) shape_units.push_back(j);
        if (u.from.placement == k0.placement && u.to.placement == k1.placement) pose_units.push_back(j);
      }
      std::vector<double> abs_mismatch(mismatch.size());
      for (size_t j = 0; j < mismatch.size(); ++j) abs_mismatch[j] = std::abs(mismatch[j]);
      shape_units = ClosestInDuration(shape_units, abs_mismatch, o.max_stream_candidates);
      pose_units = ClosestInDuration(pose_units, abs_mismatch, o.max_stream_candidates);
      for (int s : shape_units) {
        for (int p : pose_units) {
          const DikeyUnit &us = d.dikeys[static_cast<size_t>(s)], &up = d.dikeys[static_cast<size_t>(p)];
          DikeyCandidate c;
          c.level = FallbackLevel::kTwoStreams;
          c.shape_unit = s;
          c.pose_unit = p;
          c.used_to = k1;
          const double ms = mismatch[static_cast<size_t>(s)], mp = mismatch[static_cast<size_t>(p)];
          c.selection = std::sqrt(0.5 * (ms * ms + mp * mp));
          c.shape_warp = shape_warp(s, i, target);
          c.pose_warp = pose_warp(p, i, target);
          c.first = streams_at(s, c.shape_warp, p, c.pose_warp, 0);
          if (o.trim_keeps_key_posture && (c.shape_warp.trimmed() || c.pose_warp.trimmed())) {
            Eigen::RowVectorXd untrimmed = DikeyRow(us, 0.0);
            untrimmed.tail(12) = DikeyRow(up, 0.0).tail(12);
            c.key_offset = untrimmed - c.first;
            c.first = untrimmed;
          }
          overlap_fix(c);
          c.last = DikeyRow(us, static_cast<double>(us.frames() - 1));
          c.last.tail(12) = DikeyRow(up, static_cast<double>(up.frames() - 1)).tail(12);
          c.end = c.last;
          list.push_back(std::move(c));
        }
      }
    }
    // Level 3: minimum-jerk interpolation between the class means.
    if (list.empty() && o.max_fallback_level >= 3) {
      for (const KeyCode& k : {k0, k1}) {
        if (!classes.shape.count(k.shape))
          throw InvalidInput("key " + k.Text() + ": the dictionary holds no key with shape " + std::to_string(k.shape));
        if (!classes.placement.count(k.placement))
          throw InvalidInput("key " + k.Text() + ": the dictionary holds no key with placement " +
                             std::to_string(k.placement));
      }
      DikeyCandidate c;
      c.level = FallbackLevel::kInterpolated;
      c.used_to = k1;
      c.first = classes.Of(k0);
      c.last = classes.Of(k1);
      c.end = c.last;
      c.selection = 0;
      list.push_back(std::move(c));
    }
    if (list.empty()) {
      throw InvalidInput("key " + std::to_string(i + 2) + " (" + SuccessionCode(k0, k1) + " at " +
                         Num(keys[i + 1].target_s) + " s): no dikey unit up to fallback level " +
                         std::to_string(o.max_fallback_level));
    }
  }

  // Target cost: RMS standardised distances from the key classes' means, the
  // hand parameters (weighted as the joins) for the shape and the
  // forearm-in-head pose for the placement.
  Eigen::VectorXd shape_factor(P), pose_factor(6);
  {
    ColumnSpread s;
    double n = 0;
    for (const DikeyUnit& u : d.dikeys) {
      s.Add(u.hand_params, 0);
      s.Add(u.forearm_in_head, P);
      n += static_cast<double>(u.frames());
    }
    Eigen::VectorXd ws(P + 6);
    ws << Weights(o.hand_weights, P, "hand_weights"), Eigen::VectorXd::Zero(6);
    shape_factor = JumpFactors(s, n, ws).head(P);
    ws.head(P).setZero();
    ws.tail(6).setOnes();
    pose_factor = JumpFactors(s, n, ws).tail(6);
  }
  auto atypical = [&](const Eigen::RowVectorXd& v, const KeyCode& k) {
    double cost = 0;
    if (classes.shape.count(k.shape))
      cost +=
          (shape_factor.transpose().array() * (v.head(P) - classes.shape.at(k.shape).Value()).array()).matrix().norm();
    if (classes.placement.count(k.placement))
      cost += (pose_factor.transpose().array() *
               (v.segment(P, 6) - classes.placement.at(k.placement).Value().head(6)).array())
                  .matrix()
                  .norm();
    return cost;
  };
  std::vector<std::vector<double>> local(slots);
  for (size_t i = 0; i < slots; ++i) {
    for (const DikeyCandidate& c : cands[i]) {
      double cost = o.selection_weight * c.selection;
      if (o.target_weight > 0) {
        double t = atypical(c.first, keys[i].code);
        if (i + 1 == slots) t += atypical(c.end, keys[i + 1].code);
        cost += o.target_weight * t;
      }
      local[i].push_back(cost);
    }
  }
  HandTrack out;
  const std::vector<int> path = Viterbi(
      local,
      [&](size_t i, int p, int c) {
        return o.concatenation_weight *
               jump_cost(cands[i - 1][static_cast<size_t>(p)].last, cands[i][static_cast<size_t>(c)].first);
      },
      &out.total_cost);

  auto chosen = [&](size_t i) -> const DikeyCandidate& { return cands[i][static_cast<size_t>(path[i])]; };
  auto sample = [&](size_t i, double u) -> Eigen::RowVectorXd {
    const DikeyCandidate& c = chosen(i);
    if (c.level == FallbackLevel::kInterpolated) return c.first + MinimumJerk(u) * (c.last - c.first);
    Eigen::RowVectorXd v = streams_at(c.shape_unit, c.shape_warp, c.pose_unit, c.pose_warp, u);
    if (c.key_offset.size()) v += (1.0 - u) * c.key_offset;
    return v;
  };
  auto first = [&](size_t i) -> Eigen::RowVectorXd { return chosen(i).first; };
  auto last = [&](size_t i) -> Eigen::RowVectorXd { return chosen(i).last; };
  auto end = [&](size_t i) -> Eigen::RowVectorXd { return chosen(i).end; };
  const int64_t frames = static_cast<int64_t>(std::llround(duration_s * o.rate_hz)) + 1;
  Eigen::MatrixXd track(frames, C);
  Render(key_frames, o.smoothing, sample, first, last, end, &track);
  // Overlapping movements (ConcatOptions::movement_onsets): each one's
  // displacement from its starting posture, added to the previous slot's
  // frames from its onset on (the slot's warp continued backwards).
  for (size_t i = 1; i < slots; ++i) {
    const DikeyCandidate& c = chosen(i);
    const int64_t f0 = key_frames[i], f1 = key_frames[i + 1];
    if (c.level == FallbackLevel::kInterpolated || f1 <= f0) continue;
    const double n = static_cast<double>(f1 - f0);
    auto add = [&](const DikeyUnit& u, const StreamWarp& w, Eigen::Index col, Eigen::Index cols, bool pose) {
      if (!w.planned || !(w.movement_start < 0)) return;
      const auto first_frame = static_cast<int64_t>(std::ceil(static_cast<double>(f0) + w.movement_start * n));
      for (int64_t f = std::max<int64_t>(first_frame, 0); f <= f0 && f < frames; ++f) {
        const Eigen::RowVectorXd v = displacement(u, w, static_cast<double>(f - f0) / n);
        track.row(f).segment(col, cols) += pose ? Eigen::RowVectorXd(v.tail(12)) : Eigen::RowVectorXd(v.head(P));
      }
    };
    add(d.dikeys[static_cast<size_t>(c.shape_unit)], c.shape_warp, 0, P, false);
    add(d.dikeys[static_cast<size_t>(c.pose_unit)], c.pose_warp, P, 12, true);
  }

  out.rate_hz = o.rate_hz;
  out.hand_params = track.leftCols(P);
  out.forearm_in_head = track.middleCols(P, 6);
  out.head_pose = track.rightCols(6);
  for (size_t i = 0; i < slots; ++i) {
    const DikeyCandidate& c = chosen(i);
    KeyReport r;
    r.code = keys[i + 1].code;
    r.target_s = keys[i + 1].target_s;
    r.level = c.level;
    r.used_to = c.used_to;
    if (c.shape_unit >= 0) r.units.push_back(c.shape_unit);
    if (c.level == FallbackLevel::kTwoStreams) r.units.push_back(c.pose_unit);
    if (c.pose_unit >= 0) {
      const DikeyUnit& up = d.dikeys[static_cast<size_t>(c.pose_unit)];
      const double lag = up.from_placement_lag_s, dur = up.duration_s();
      if (std::isfinite(lag) && lag < 0) {
        r.leaving_placement_lag_s = lag;
      } else if (std::isfinite(lag) && dur > 0) {
        // Unit fraction → slot fraction (0 when trimmed away).
        const double u = c.pose_warp.SlotFraction(lag / dur);
        r.leaving_placement_lag_s = u * (keys[i + 1].target_s - keys[i].target_s);
      }
    }
    out.keys.push_back(std::move(r));
  }
  if (o.posture_radius > 0) PullKeyPostures(classes, spread, rows, keys, key_frames, o, &out);
  return out;
}

// ---------------------------------------------------------------------------
// Diphones.

namespace {

struct DiphoneCandidate {
  DiphoneLevel level = DiphoneLevel::kWhole;
  int left = -1, right = -1;  // the same unit for level 0
  double selection = 0;       // RMS of the two half-phone duration mismatches (s)
  double internal = 0;        // jump cost at the phone boundary (half units)
  Eigen::RowVectorXd first, last, left_at_boundary, right_at_boundary;
};

// A diphone unit's fractional row at unit time t.
double UnitRow(const DiphoneUnit& u, double t) {
  const double span = u.end_s - u.start_s;
  if (!(span > 0)) return 0.0;
  return (t - u.start_s) / span * static_cast<double>(u.frames() - 1);
}

// Normalized position of the phone boundary in a unit (0..1).
double UnitBoundary(const DiphoneUnit& u) {
  const double span = u.end_s - u.start_s;
  if (!(span > 0)) return 0.5;
  return std::clamp((u.phone1_end_s - u.start_s) / span, 0.0, 1.0);
}

}  // namespace

void CheckDiphoneUnits(const Dictionary& d) {
  if (d.diphones.empty()) throw InvalidInput("the dictionary has no diphone units");
  const Eigen::Index q = d.diphones.front().face_params.cols();
  for (size_t i = 0; i < d.diphones.size(); ++i) {
    const DiphoneUnit& u = d.diphones[i];
    const std::string where =
        "diphone unit " + std::to_string(i) + " (take '" + u.take + "', " + u.phone1 + "+" + u.phone2 + ")";
    if (u.frames() < 1 || u.face_params.cols() != q)
      throw InvalidInput(where + ": its face parameters have another size");
    if (!u.face_params.allFinite()) throw InvalidInput(where + ": a value is not finite");
    if (!std::isfinite(u.start_s) || !std::isfinite(u.end_s) || !std::isfinite(u.phone1_end_s) ||
        !std::isfinite(u.phone1_start_s) || !std::isfinite(u.phone2_start_s) || !std::isfinite(u.phone2_end_s) ||
        !(u.rate_hz > 0) || !std::isfinite(u.rate_hz))
      throw InvalidInput(where + ": its times are not finite");
  }
}

std::vector<double> PhoneMiddles(const std::vector<PhoneTarget>& phones, double duration_s) {
  if (phones.size() < 2) throw InvalidInput("need at least two phones, got " + std::to_string(phones.size()));
  std::vector<double> middles;
  for (size_t i = 0; i < phones.size(); ++i) {
    const PhoneTarget& p = phones[i];
    const std::string where = "phone " + std::to_string(i + 1) + " ('" + p.phone + "')";
    if (!std::isfinite(p.start_s) || !std::isfinite(p.end_s)) throw InvalidInput(where + ": time is not finite");
    if (!(p.end_s > p.start_s))
      throw InvalidInput(where + ": it ends (" + Num(p.end_s) + " s) before it starts (" + Num(p.start_s) + " s)");
    if (i > 0 && std::abs(p.start_s - phones[i - 1].end_s) > 1e-6)
      throw InvalidInput(where + ": starts at " + Num(p.start_s) + " s, not where the previous ends (" +
                         Num(phones[i - 1].end_s) + " s)");
    middles.push_back(0.5 * (p.start_s + p.end_s));
  }
  if (!std::isfinite(duration_s) || phones.front().start_s < -1e-9 || phones.back().end_s > duration_s + 1e-6)
    throw InvalidInput("phones span [" + Num(phones.front().start_s) + ", " + Num(phones.back().end_s) +
                       "] s, outside [0, " + Num(duration_s) + "] s");
  return middles;
}

FaceTrack ConcatenateDiphones(const Dictionary& d, const std::vector<PhoneTarget>& phones, double duration_s,
                              const ConcatOptions& o) {
  if (const std::string why = o.Check(); !why.empty()) throw InvalidInput(why);
  CheckDiphoneUnits(d);
  const std::vector<double> middles = PhoneMiddles(phones, duration_s);
  const std::vector<int64_t> key_frames = KeyFrames(middles, duration_s, o.rate_hz, "phone middle");

  const Eigen::Index Q = d.diphones.front().face_params.cols();
  ColumnSpread spread;
  double rows = 0;
  for (const DiphoneUnit& u : d.diphones) {
    spread.Add(u.face_params, 0);
    rows += static_cast<double>(u.frames());
  }
  const Eigen::VectorXd a = JumpFactors(spread, rows, Weights(o.face_weights, Q, "face_weights"));
  auto jump_cost = [&](const Eigen::RowVectorXd& from, const Eigen::RowVectorXd& to) {
    return (a.transpose().array() * (to - from).array()).matrix().norm();
  };
  std::map<std::string, Mean> phone_mean;
  Mean global;
  for (const DiphoneUnit& u : d.diphones) {
    phone_mean[u.phone1].Add(u.face_params.row(0));
    phone_mean[u.phone2].Add(u.face_params.row(u.frames() - 1));
    global.Add(u.face_params.row(0));
    global.Add(u.face_params.row(u.frames() - 1));
  }

  const size_t slots = phones.size() - 1;
  const int n_units = static_cast<int>(d.diphones.size());
  std::vector<std::vector<DiphoneCandidate>> cands(slots);
  std::vector<double> boundary(slots);  // normalized target boundary per slot
  for (size_t i = 0; i < slots; ++i) {
    const std::string &p1 = phones[i].phone, &p2 = phones[i + 1].phone;
    const double left_target = phones[i].end_s - middles[i], right_target = middles[i + 1] - phones[i].end_s;
    boundary[i] = left_target / (left_target + right_target);
    std::vector<DiphoneCandidate>& list = cands[i];
    std::vector<int> lefts, rights;
    std::vector<double> left_mis(d.diphones.size()), right_mis(d.diphones.size());
    for (int j = 0; j < n_units; ++j) {
      const DiphoneUnit& u = d.diphones[static_cast<size_t>(j)];
      left_mis[static_cast<size_t>(j)] = (u.phone1_end_s - u.start_s) - left_target;
      right_mis[static_cast<size_t>(j)] = (u.end_s - u.phone1_end_s) - right_target;
      if (u.phone1 == p1 && u.phone2 == p2) {
        DiphoneCandidate c;
        c.left = c.right = j;
        const double l = left_mis[static_cast<size_t>(j)], r = right_mis[static_cast<size_t>(j)];
        c.selection = std::sqrt(0.5 * (l * l + r * r));
        c.first = u.face_params.row(0);
        c.last = u.face_params.row(u.frames() - 1);
        list.push_back(std::move(c));
      }
      if (u.phone1 == p1) lefts.push_back(j);
      if (u.phone2 == p2) rights.push_back(j);
    }
    if (list.empty() && o.max_fallback_level >= 1 && !lefts.empty() && !rights.empty()) {
      std::vector<double> la(left_mis.size()), ra(right_mis.size());
      for (size_t j = 0; j < la.size(); ++j) {
        la[j] = std::abs(left_mis[j]);
        ra[j] = std::abs(right_mis[j]);
      }
      lefts = ClosestInDuration(lefts, la, o.max_stream_candidates);
      rights = ClosestInDuration(rights, ra, o.max_stream_candidates);
      for (int l : lefts) {
        for (int r : rights) {
          const DiphoneUnit &ul = d.diphones[static_cast<size_t>(l)], &ur = d.diphones[static_cast<size_t>(r)];
          DiphoneCandidate c;
          c.level = DiphoneLevel::kHalfUnits;
          c.left = l;
          c.right = r;
          const double lm = left_mis[static_cast<size_t>(l)], rm = right_mis[static_cast<size_t>(r)];
          c.selection = std::sqrt(0.5 * (lm * lm + rm * rm));
          c.first = ul.face_params.row(0);
          c.last = ur.face_params.row(ur.frames() - 1);
          c.left_at_boundary = SampleRow(ul.face_params, UnitRow(ul, ul.phone1_end_s));
          c.right_at_boundary = SampleRow(ur.face_params, UnitRow(ur, ur.phone1_end_s));
          c.internal = jump_cost(c.left_at_boundary, c.right_at_boundary);
          list.push_back(std::move(c));
        }
      }
    }
    if (list.empty() && o.max_fallback_level >= 2) {
      DiphoneCandidate c;
      const bool known = phone_mean.count(p1) && phone_mean.count(p2);
      if (!known && o.max_fallback_level < 3) {
        throw InvalidInput("phone " + std::to_string(i + (phone_mean.count(p1) ? 2 : 1)) + " ('" +
                           (phone_mean.count(p1) ? p2 : p1) + "'): the dictionary holds no diphone with it");
      }
      c.level = known ? DiphoneLevel::kInterpolated : DiphoneLevel::kUnknownPhone;
      c.first = phone_mean.count(p1) ? phone_mean.at(p1).Value() : global.Value();
      c.last = phone_mean.count(p2) ? phone_mean.at(p2).Value() : global.Value();
      list.push_back(std::move(c));
    }
    if (list.empty()) {
      throw InvalidInput("phones " + std::to_string(i + 1) + "-" + std::to_string(i + 2) + " (" + p1 + "+" + p2 +
                         " at " + Num(middles[i]) + " s): no diphone unit up to fallback level " +
                         std::to_string(o.max_fallback_level));
    }
  }

  std::vector<std::vector<double>> local(slots);
  for (size_t i = 0; i < slots; ++i)
    for (const DiphoneCandidate& c : cands[i])
      local[i].push_back(o.selection_weight * c.selection + o.concatenation_weight * c.internal);
  FaceTrack out;
  const std::vector<int> path = Viterbi(
      local,
      [&](size_t i, int p, int c) {
        return o.concatenation_weight *
               jump_cost(cands[i - 1][static_cast<size_t>(p)].last, cands[i][static_cast<size_t>(c)].first);
      },
      &out.total_cost);
  auto chosen = [&](size_t i) -> const DiphoneCandidate& { return cands[i][static_cast<size_t>(path[i])]; };
  auto sample = [&](size_t i, double u) -> Eigen::RowVectorXd {
    const DiphoneCandidate& c = chosen(i);
    if (c.left < 0) return c.first + MinimumJerk(u) * (c.last - c.first);
    const double bt = boundary[i];
    const DiphoneUnit &ul = d.diphones[static_cast<size_t>(c.left)], &ur = d.diphones[static_cast<size_t>(c.right)];
    // Piecewise linear: [0, bt] → [0, β] of the left unit, [bt, 1] → [β, 1] of the right.
    if (u <= bt) {
      const double s = bt > 0 ? u / bt : 1.0;
      const double v = s * UnitBoundary(ul);
      Eigen::RowVectorXd x = SampleRow(ul.face_params, v * static_cast<double>(ul.frames() - 1));
      if (c.left != c.right && o.smoothing) x += s * (c.right_at_boundary - c.left_at_boundary);
      return x;
    }
    const double s = bt < 1 ? (u - bt) / (1 - bt) : 1.0;
    const double beta = UnitBoundary(ur);
    return SampleRow(ur.face_params, (beta + s * (1 - beta)) * static_cast<double>(ur.frames() - 1));
  };
  auto first = [&](size_t i) -> Eigen::RowVectorXd { return chosen(i).first; };
  auto last = [&](size_t i) -> Eigen::RowVectorXd { return chosen(i).last; };
  const int64_t frames = static_cast<int64_t>(std::llround(duration_s * o.rate_hz)) + 1;
  out.face_params.resize(frames, Q);
  Render(key_frames, o.smoothing, sample, first, last, last, &out.face_params);
  out.rate_hz = o.rate_hz;
  for (size_t i = 0; i < slots; ++i) {
    const DiphoneCandidate& c = chosen(i);
    DiphoneReport r;
    r.phone1 = phones[i].phone;
    r.phone2 = phones[i + 1].phone;
    r.start_s = middles[i];
    r.end_s = middles[i + 1];
    r.level = c.level;
    if (c.left >= 0) r.units.push_back(c.left);
    if (c.right >= 0 && c.right != c.left) r.units.push_back(c.right);
    out.fallback_per_diphone.push_back(static_cast<int>(c.level));
    out.diphones.push_back(std::move(r));
  }
  return out;
}

}  // namespace csw::dict
