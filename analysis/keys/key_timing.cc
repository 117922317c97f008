#include "analysis/keys/key_timing.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

#include "core/error.h"

namespace csw::keys {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// Keys where the component differs from the previous key's (key 0 always).
std::vector<size_t> Changes(const std::vector<ExpectedKey>& expected, bool shape) {
  std::vector<size_t> out;
  for (size_t k = 0; k < expected.size(); ++k) {
    const int v = shape ? expected[k].shape : expected[k].placement;
    const int u = k == 0 ? -1 : (shape ? expected[k - 1].shape : expected[k - 1].placement);
    if (v != u) out.push_back(k);
  }
  return out;
}

// RMS standardised distance of row t of `x` to the mean of class `label`
// (+inf when nothing is observed).
double Distance(const GaussianClassifier& c, const Eigen::MatrixXd& x, int64_t t, int label) {
  const Eigen::RowVectorXd row = x.row(t);
  std::vector<double> closeness(static_cast<size_t>(c.num_labels()));
  c.Closeness(row.data(), closeness.data());
  const double v = closeness[static_cast<size_t>(label)];
  return std::isnan(v) ? kInf : std::sqrt(std::max(0.0, -v));
}

// First frame of [start, end) whose distance comes within `tolerance` of the
// segment's range above its smallest finite value; the middle of the segment
// when nothing is observed.
int64_t Arrival(int64_t start, int64_t end, double tolerance, const std::function<double(int64_t)>& distance) {
  double lo = kInf, hi = -kInf;
  std::vector<double> d(static_cast<size_t>(end - start));
  for (int64_t t = start; t < end; ++t) {
    d[static_cast<size_t>(t - start)] = distance(t);
    const double v = d[static_cast<size_t>(t - start)];
    if (std::isfinite(v)) {
      lo = std::min(lo, v);
      hi = std::max(hi, v);
    }
  }
  if (!std::isfinite(lo)) return start + (end - start) / 2;
  const double threshold = lo + tolerance * (hi - lo);
  for (int64_t t = start; t < end; ++t)
    if (d[static_cast<size_t>(t - start)] <= threshold) return t;
  return start;
}

// Keys where neither component changes (a repeated code): the hand holds, so
// neither the posteriors (equal over the whole stretch) nor the kinematics
// (a movement no larger than the cuer's variability) say when the key's
// target is. Its target is interpolated by key index between the targets of
// the nearest keys with a change (keys follow the syllables at a roughly
// steady rate); after the last change, the take's mean interval between
// changed keys is added, within the take.
void InterpolateRepeats(std::vector<TimedKey>& keys, double end_s) {
  std::vector<size_t> anchors;
  for (size_t k = 0; k < keys.size(); ++k)
    if (keys[k].shape.changes || keys[k].placement.changes) anchors.push_back(k);
  if (anchors.empty()) return;
  double step = 0.0;
  if (anchors.size() >= 2)
    step = (keys[anchors.back()].target_s - keys[anchors.front()].target_s) /
           static_cast<double>(anchors.back() - anchors.front());
  size_t a = 0;
  for (size_t k = 0; k < keys.size(); ++k) {
    if (keys[k].shape.changes || keys[k].placement.changes || keys[k].target_from_speech) continue;
    while (a + 1 < anchors.size() && anchors[a + 1] < k) ++a;
    if (anchors[a] > k) continue;  // no change before it (the first key always changes)
    const size_t p = anchors[a];
    const double tp = keys[p].target_s;
    double t;
    if (a + 1 < anchors.size()) {
      const size_t q = anchors[a + 1];
      t = tp + (keys[q].target_s - tp) * static_cast<double>(k - p) / static_cast<double>(q - p);
    } else {
      if (!(step > 0.0)) continue;
      t = std::min(end_s, tp + step * static_cast<double>(k - p));
    }
    keys[k].target_s = t;
  }
}

// Median and robust spread (1.4826 × the median absolute deviation) of `v`.
struct Lag {
  bool known = false;
  double median = 0.0, spread = 0.0;
};
Lag MedianSpread(std::vector<double> v) {
  Lag out;
  if (v.empty()) return out;
  auto median = [](std::vector<double>& x) {
    const size_t h = x.size() / 2;
    std::nth_element(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(h), x.end());
    const double upper = x[h];
    if (x.size() % 2 == 1) return upper;
    return 0.5 * (upper + *std::max_element(x.begin(), x.begin() + static_cast<std::ptrdiff_t>(h)));
  };
  out.known = true;
  out.median = median(v);
  for (double& x : v) x = std::abs(x - out.median);
  out.spread = 1.4826 * median(v);
  return out;
}

}  // namespace

// Speech anchors (key_timing.h): outlying component targets and repeated keys
// timed from A1 + the take's own lag.
void AnchorToSpeech(std::vector<TimedKey>& keys, const std::vector<ExpectedKey>& expected,
                    const KeyTimingOptions& options, const Eigen::MatrixXd& shape_post,
                    const Eigen::MatrixXd& place_post, double rate_hz) {
  const size_t n = std::min(keys.size(), expected.size());
  for (const bool shape : {true, false}) {
    auto timing = [&](size_t k) -> ComponentTiming& { return shape ? keys[k].shape : keys[k].placement; };
    std::vector<double> lags[2], pooled;  // lags[vowel_anchor]
    for (size_t k = 0; k < n; ++k)
      if (std::isfinite(expected[k].anchor_s) && timing(k).changes && std::isfinite(timing(k).target_s)) {
        lags[expected[k].vowel_anchor ? 1 : 0].push_back(timing(k).target_s - expected[k].anchor_s);
        pooled.push_back(timing(k).target_s - expected[k].anchor_s);
      }
    const auto min_keys = static_cast<size_t>(options.anchor_min_keys);
    const Lag all = pooled.size() >= min_keys ? MedianSpread(pooled) : Lag{};
    const Lag group[2] = {lags[0].size() >= min_keys ? MedianSpread(lags[0]) : all,
                          lags[1].size() >= min_keys ? MedianSpread(lags[1]) : all};
    for (size_t k = 0; k < n; ++k) {
      if (!std::isfinite(expected[k].anchor_s)) continue;
      const Lag& lag = group[expected[k].vowel_anchor ? 1 : 0];
      if (!lag.known) continue;
      const double at = expected[k].anchor_s + lag.median;
      ComponentTiming& c = timing(k);
      if (c.changes) {
        bool nearer_neighbour = false;
        if (options.anchor_nearest && std::abs(c.target_s - at) > options.anchor_outlier_floor_s) {
          const double d = std::abs(c.target_s - at);
          // The nearest keys before and after with a known A1 + lag.
          auto nearer = [&](size_t j) {
            const Lag& l = group[expected[j].vowel_anchor ? 1 : 0];
            return l.known && std::abs(c.target_s - (expected[j].anchor_s + l.median)) < d;
          };
          // A neighbour without A1 (a rest) whose component changes: its own
          // timed target (the return to rest has no syllable to follow).
          auto nearer_unanchored = [&](size_t j) {
            return timing(j).changes && std::isfinite(timing(j).target_s) &&
                   std::abs(c.target_s - timing(j).target_s) < d;
          };
          if (k > 0 && !std::isfinite(expected[k - 1].anchor_s))
            nearer_neighbour = nearer_neighbour || nearer_unanchored(k - 1);
          if (k + 1 < n && !std::isfinite(expected[k + 1].anchor_s))
            nearer_neighbour = nearer_neighbour || nearer_unanchored(k + 1);
          for (size_t j = k; j-- > 0;)
            if (std::isfinite(expected[j].anchor_s)) {
              nearer_neighbour = nearer_neighbour || nearer(j);
              break;
            }
          for (size_t j = k + 1; j < n; ++j)
            if (std::isfinite(expected[j].anchor_s)) {
              nearer_neighbour = nearer_neighbour || nearer(j);
              break;
            }
        }
        // Within the gate, or a fitted target where the hand holds the key's
        // own class, not too far from A1 + lag (the gate assumes a steady
        // lag; a cuer's lag can stray beyond it on one key).
        bool in_class = false;
        if (options.anchor_keep_in_class && c.kinematic && std::abs(c.target_s - at) <= options.anchor_in_class_max_s) {
          const Eigen::MatrixXd& post = shape ? shape_post : place_post;
          const int label = shape ? expected[k].shape : expected[k].placement;
          const auto f = std::clamp<int64_t>(std::llround(c.target_s * rate_hz), 0, post.rows() - 1);
          in_class = post.rows() > 0 && label >= 0 && label < post.cols() && std::isfinite(post(f, label)) &&
                     post(f, label) >= options.anchor_in_class_posterior;
        }
        const bool within_gate = std::abs(c.target_s - at) <=
                                 std::max(options.anchor_outlier_sd * lag.spread, options.anchor_outlier_floor_s);
        if (!nearer_neighbour && (within_gate || in_class)) {
          if (!c.kinematic || !std::isfinite(c.target_sd_s) || !(options.anchor_fit_sd_factor > 0) || !(lag.spread > 0))
            continue;
          c.target_s = CombineWithSpeech(c.target_s, c.target_sd_s, at, lag.spread, options.anchor_fit_sd_factor);
          c.speech_weighted = true;
        } else {
          c.target_s = at;
          c.onset_s = kNaN;
          c.kinematic = false;
          c.from_speech = true;
        }
        // The keys that hold this component keep its (new) target.
        for (size_t j = k + 1; j < keys.size() && !timing(j).changes; ++j) {
          const bool changes = timing(j).changes;
          timing(j) = c;
          timing(j).changes = changes;
        }
      } else if (shape && !keys[k].placement.changes) {
        keys[k].target_s = at;
        keys[k].target_from_speech = true;
      }
    }
  }
}

double CombineWithSpeech(double fit_s, double fit_sd_s, double anchor_s, double spread_s, double sd_factor) {
  if (!(sd_factor > 0) || std::isnan(fit_sd_s) || !(spread_s > 0) || !std::isfinite(anchor_s)) return fit_s;
  if (std::isinf(fit_sd_s)) return anchor_s;
  const double v = sd_factor * sd_factor * fit_sd_s * fit_sd_s, p = spread_s * spread_s;
  return (p * fit_s + v * anchor_s) / (p + v);
}

phasing::MovementFitOptions KeyTimingOptions::ShapeFitDefaults() {
  phasing::MovementFitOptions o;
  o.path_terms = 3;  // the distances are nonlinear in the joint angles (docs/analysis-phasing.md)
  return o;
}

std::string KeyTimingOptions::Check() const {
  std::string r = decode.Check();
  if (!r.empty()) return r;
  r = shape_fit.Check();
  if (!r.empty()) return "shape fit: " + r;
  r = placement_fit.Check();
  if (!r.empty()) return "placement fit: " + r;
  if (!(arrival_tolerance >= 0 && arrival_tolerance < 1)) return "arrival_tolerance must be in [0, 1)";
  if (!(window_margin_s >= 0)) return "window_margin_s must be >= 0";
  if (max_refits < 0) return "max_refits must be >= 0";
  if (refinement_passes < 0) return "refinement_passes must be >= 0";
  if (!(max_movement_s > 0)) return "max_movement_s must be > 0";
  if (!(anchor_outlier_sd > 0)) return "anchor_outlier_sd must be > 0";
  if (!(anchor_outlier_floor_s >= 0)) return "anchor_outlier_floor_s must be >= 0";
  if (anchor_min_keys < 1) return "anchor_min_keys must be >= 1";
  if (!(anchor_fit_sd_factor >= 0)) return "anchor_fit_sd_factor must be >= 0";
  if (!(anchor_in_class_posterior > 0 && anchor_in_class_posterior <= 1))
    return "anchor_in_class_posterior must be in (0, 1]";
  if (!(anchor_in_class_max_s >= 0)) return "anchor_in_class_max_s must be >= 0";
  return "";
}

std::vector<TimedKey> DecodeAlignedTimed(const KeyModel& model, const HandFeatures& features,
                                         const KeyPosteriors& posteriors, const std::vector<ExpectedKey>& expected,
                                         double rate_hz, const KeyTimingOptions& options) {
  const std::string reason = options.Check();
  if (!reason.empty()) throw InvalidInput("key timing: " + reason);
  if (!(rate_hz > 0)) throw InvalidInput("key timing: the frame rate must be > 0");
  if (features.frames() != posteriors.frames())
    throw InvalidInput("key timing: " + std::to_string(features.frames()) + " feature frames but " +
                       std::to_string(posteriors.frames()) + " posterior frames");
  const std::vector<DecodedKey> decoded = DecodeAligned(posteriors, expected, rate_hz, options.decode);
  const int64_t n = posteriors.frames();
  const double end_s = static_cast<double>(n - 1) / rate_hz;
  std::vector<TimedKey> out(decoded.size());
  for (size_t k = 0; k < decoded.size(); ++k) out[k].key = decoded[k];

  // Times one component: its changes, aligned segments, rough and kinematic targets.
  auto time_component = [&](bool shape, const Eigen::MatrixXd& post, const Eigen::MatrixXd& x,
                            const Eigen::MatrixXd& kin, const GaussianClassifier& classifier,
                            const phasing::MovementFitOptions& fit) {
    const std::vector<size_t> changes = Changes(expected, shape);
    std::vector<int> labels;
    for (size_t k : changes) labels.push_back(shape ? expected[k].shape : expected[k].placement);
    // Each change's segment is kept near the joint segments of its keys.
    std::vector<std::pair<int64_t, int64_t>> windows;
    const auto margin = static_cast<int64_t>(std::llround(options.window_margin_s * rate_hz));
    for (size_t i = 0; i < changes.size(); ++i) {
      const size_t last = i + 1 < changes.size() ? changes[i + 1] - 1 : out.size() - 1;
      windows.emplace_back(std::max<int64_t>(0, out[changes[i]].key.start_frame - margin),
                           std::min<int64_t>(n, out[last].key.end_frame + margin));
    }
    const std::vector<ComponentSegment> segments = AlignComponent(post, labels, rate_hz, options.decode, windows);
    std::vector<ComponentTiming> timing(changes.size());
    for (size_t i = 0; i < changes.size(); ++i) {
      ComponentTiming& c = timing[i];
      c.changes = true;
      c.segment_start = segments[i].start_frame;
      c.segment_end = segments[i].end_frame;
      const int label = labels[i];
      c.rough_frame = Arrival(c.segment_start, c.segment_end, options.arrival_tolerance,
                              [&](int64_t t) { return Distance(classifier, x, t, label); });
      c.target_s = static_cast<double>(c.rough_frame) / rate_hz;
      c.onset_s = kNaN;
    }
    if (options.kinematic) {
      const phasing::SampledTrajectory traj{&kin, rate_hz, 0.0};
      // Pass 0 fits each movement around the rough targets; the refinement
      // passes refit it with its neighbours' times taken from their fits.
      std::vector<double> times(changes.size());
      for (size_t i = 0; i < changes.size(); ++i) times[i] = static_cast<double>(timing[i].rough_frame) / rate_hz;
      for (int pass = 0; pass <= options.refinement_passes; ++pass) {
        std::vector<double> fitted = times;
        for (size_t i = 1; i < changes.size(); ++i) {
          const double previous = times[i - 1];
          const double next = i + 1 < changes.size() ? times[i + 1] : std::min(end_s, times[i] + 0.3);
          // A fit that stops at the edge of its tolerance around the guess is
          // refitted around its own target (the guess was far off).
          double guess = times[i];
          phasing::MovementEstimate m;
          for (int refit = 0; refit < options.max_refits + 1; ++refit) {
            if (!(previous < guess && guess < next)) break;
            const double first = std::max(previous, guess - options.max_movement_s);
            if (i + 1 < changes.size())
              m = phasing::EstimateMovement(traj, first, guess, next, fit);
            else  // the component's last movement: no movement follows, the data run into the hold
              m = phasing::EstimateMovementAmong(traj, {first, guess}, 1, first - fit.lookback_s, next, fit);
            if (!m.Usable() || std::abs(m.target_s - guess) < 0.9 * fit.target_tolerance_s) break;
            guess = m.target_s;
          }
          if (!m.Usable()) {
            if (pass == 0) continue;
            timing[i].kinematic = false;
            continue;
          }
          timing[i].kinematic = true;
          timing[i].onset_s = m.onset_s;
          timing[i].target_s = m.target_s;
          timing[i].target_sd_s = m.target_sd_s;
          fitted[i] = m.target_s;
        }
        times = fitted;
      }
      for (auto& c : timing)
        if (!c.kinematic) {
          c.onset_s = kNaN;
          c.target_sd_s = kNaN;
          c.target_s = static_cast<double>(c.rough_frame) / rate_hz;
        }
    }
    // Every key: its own change, or the held component of the last change.
    size_t i = 0;
    for (size_t k = 0; k < out.size(); ++k) {
      if (i + 1 < changes.size() && changes[i + 1] == k) ++i;
      ComponentTiming c = timing[i];
      c.changes = changes[i] == k;
      (shape ? out[k].shape : out[k].placement) = c;
    }
  };
  const bool tips = options.shape_on_tips && features.tips_in_palm.rows() == n;
  time_component(true, posteriors.shape, features.distances, tips ? features.tips_in_palm : features.distances,
                 model.shape, options.shape_fit);

  // The placement point: the tip of the longest extended finger, blended
  // between the index (weight 1 for the model's index shapes) and the middle
  // finger over each shape movement (minimum-jerk profile between the timed
  // onset and target; a rough change without a fit switches over 0.2 s).
  Eigen::VectorXd lambda(n);
  {
    auto weight = [&](size_t k) { return model.IndexFinger(expected[k].shape) ? 1.0 : 0.0; };
    double w0 = out.empty() ? 0.0 : weight(0);
    lambda.setConstant(w0);
    for (size_t k = 1; k < out.size(); ++k) {
      if (!out[k].shape.changes) continue;
      const double w1 = weight(k);
      if (w1 != w0) {
        const double target = out[k].shape.target_s;
        const double onset = out[k].shape.kinematic ? out[k].shape.onset_s : target - 0.2;
        for (int64_t t = 0; t < n; ++t) {
          const double tau = std::clamp((static_cast<double>(t) / rate_hz - onset) / (target - onset), 0.0, 1.0);
          lambda[t] += (w1 - w0) * tau * tau * tau * (10.0 - 15.0 * tau + 6.0 * tau * tau);
        }
      }
      w0 = w1;
    }
  }
  Eigen::MatrixXd tip(n, 3);
  for (int64_t t = 0; t < n; ++t) {
    const double w = std::clamp(lambda[t], 0.0, 1.0);
    if (w >= 1.0)
      tip.row(t) = features.index_tip.row(t);
    else if (w <= 0.0)
      tip.row(t) = features.middle_tip.row(t);
    else
      tip.row(t) = w * features.index_tip.row(t) + (1.0 - w) * features.middle_tip.row(t);
  }
  const Eigen::MatrixXd placement_post = model.placement.Posteriors(tip);
  time_component(false, placement_post, tip, tip, model.placement, options.placement_fit);

  if (!out.empty()) {
    // The initial hold: left at the earliest fitted onset of the next movements,
    // not before the take's first frame (an onset fitted before the data is an
    // extrapolation).
    TimedKey& first = out.front();
    double leave = kInf;
    for (size_t k = 1; k < out.size(); ++k) {
      if (out[k].shape.changes && out[k].shape.kinematic && leave == kInf)
        leave = std::min(leave, out[k].shape.onset_s);
      if (out[k].shape.changes) break;
    }
    double leave_p = kInf;
    for (size_t k = 1; k < out.size(); ++k) {
      if (out[k].placement.changes && out[k].placement.kinematic) leave_p = out[k].placement.onset_s;
      if (out[k].placement.changes) break;
    }
    leave = std::max(0.0, std::min(leave, leave_p));
    if (first.shape.segment_start == 0 && first.placement.segment_start == 0 && std::isfinite(leave)) {
      first.shape.target_s = first.placement.target_s = leave;
      for (size_t k = 1; k < out.size() && !out[k].shape.changes; ++k) out[k].shape.target_s = leave;
      for (size_t k = 1; k < out.size() && !out[k].placement.changes; ++k) out[k].placement.target_s = leave;
    }
  }
  auto frame = [&](double s) { return std::clamp<int64_t>(std::llround(s * rate_hz), 0, n - 1); };
  if (options.speech_anchors) AnchorToSpeech(out, expected, options, posteriors.shape, placement_post, rate_hz);
  for (TimedKey& t : out)
    if (!t.target_from_speech)
      t.target_s = t.shape.changes       ? t.shape.target_s
                   : t.placement.changes ? t.placement.target_s
                                         : static_cast<double>(t.key.target_frame) / rate_hz;
  if (options.interpolate_repeats) InterpolateRepeats(out, end_s);
  for (TimedKey& t : out) {
    t.key.shape_target_frame = frame(t.shape.target_s);
    t.key.placement_target_frame = frame(t.placement.target_s);
    t.key.target_frame = frame(t.target_s);
  }
  return out;
}

}  // namespace csw::keys
