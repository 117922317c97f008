#include "analysis/target_suggestion.h"

#include <algorithm>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <utility>

#include "analysis/cleaning/filter.h"
#include "core/error.h"

namespace csw::analysis {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

std::string TargetSuggestionOptions::Check() const {
  if (!(cutoff_hz > 0) || !std::isfinite(cutoff_hz)) return "the cut-off must be a positive number of Hz";
  if (!(search_s > 0) || !std::isfinite(search_s)) return "the search half-width must be a positive number of seconds";
  if (!(min_dip_fraction >= 0 && min_dip_fraction < 1)) return "the minimum dip fraction must be in [0, 1)";
  if (!(min_dip_mm_s >= 0) || !std::isfinite(min_dip_mm_s)) return "the minimum dip must be >= 0 mm/s";
  return "";
}

Eigen::VectorXd FeatureSpeed(const Eigen::MatrixXd& series, double rate_hz, double cutoff_hz) {
  if (!(rate_hz > 0) || !std::isfinite(rate_hz)) throw InvalidInput("feature speed: the rate must be positive");
  if (!(cutoff_hz > 0 && cutoff_hz < rate_hz / 2))
    throw InvalidInput("feature speed: the cut-off must be in (0, rate / 2) = (0, " + std::to_string(rate_hz / 2) +
                       ") Hz");
  const Eigen::Index frames = series.rows(), dims = series.cols();
  // A frame is valid only when all its dimensions are: a speed over a changing
  // subset of dimensions would jump.
  std::vector<bool> valid(static_cast<size_t>(frames));
  for (Eigen::Index f = 0; f < frames; ++f) valid[static_cast<size_t>(f)] = series.row(f).allFinite();
  cleaning::ButterworthOptions filter;
  filter.cutoff_hz = cutoff_hz;
  filter.order = 2;
  Eigen::MatrixXd smooth(frames, dims);
  std::vector<double> channel(static_cast<size_t>(frames));
  for (Eigen::Index d = 0; d < dims; ++d) {
    for (Eigen::Index f = 0; f < frames; ++f)
      channel[static_cast<size_t>(f)] = valid[static_cast<size_t>(f)] ? series(f, d) : kNaN;
    const std::vector<double> out = cleaning::ButterworthFilter(channel, rate_hz, filter);
    for (Eigen::Index f = 0; f < frames; ++f) smooth(f, d) = out[static_cast<size_t>(f)];
  }
  Eigen::VectorXd speed = Eigen::VectorXd::Constant(frames, kNaN);
  for (Eigen::Index f = 1; f + 1 < frames; ++f) {
    if (!valid[static_cast<size_t>(f - 1)] || !valid[static_cast<size_t>(f + 1)] || !valid[static_cast<size_t>(f)])
      continue;
    speed(f) = (smooth.row(f + 1) - smooth.row(f - 1)).norm() * rate_hz / 2.0;
  }
  return speed;
}

std::vector<SuggestedTarget> SuggestTargetsFromSpeed(const Eigen::VectorXd& speed, double rate_hz,
                                                     const std::vector<double>& expected_s,
                                                     const TargetSuggestionOptions& options) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput("target suggestion: " + why);
  if (!(rate_hz > 0) || !std::isfinite(rate_hz)) throw InvalidInput("target suggestion: the rate must be positive");
  const auto frames = static_cast<int64_t>(speed.size());
  std::vector<SuggestedTarget> out;
  out.reserve(expected_s.size());
  // Pass 1: every key's candidate minima in its window, nearest first.
  std::vector<std::vector<std::pair<double, int64_t>>> candidates(expected_s.size());
  for (size_t k = 0; k < expected_s.size(); ++k) {
    const double t = expected_s[k];
    if (!std::isfinite(t)) throw InvalidInput("target suggestion: an expected time is not a finite number");
    SuggestedTarget s;
    s.expected_s = t;
    s.time_s = kNaN;
    s.speed_mm_s = kNaN;
    s.offset_s = kNaN;
    out.push_back(s);
    const auto lo = std::max<int64_t>(1, static_cast<int64_t>(std::floor((t - options.search_s) * rate_hz)));
    const auto hi = std::min<int64_t>(frames - 2, static_cast<int64_t>(std::ceil((t + options.search_s) * rate_hz)));
    if (hi < lo) {
      out[k].why = "the search window is outside the take";
      continue;
    }
    double peak = 0;
    int64_t valid = 0;
    for (int64_t f = lo; f <= hi; ++f)
      if (std::isfinite(speed(f))) {
        peak = std::max(peak, speed(f));
        ++valid;
      }
    if (valid == 0) {
      out[k].why = "no valid samples in the search window";
      continue;
    }
    const double ceiling = std::min(peak * (1 - options.min_dip_fraction), peak - options.min_dip_mm_s);
    for (int64_t f = lo; f <= hi; ++f) {
      const double v = speed(f);
      if (!std::isfinite(v) || v > ceiling) continue;
      // A local minimum: no lower neighbour (plateaus count once, at their first frame).
      const double before = speed(f - 1), after = speed(f + 1);
      const bool left_ok = !std::isfinite(before) || before > v;
      const bool right_ok = !std::isfinite(after) || after >= v;
      if (left_ok && right_ok) candidates[k].emplace_back(std::abs(static_cast<double>(f) / rate_hz - t), f);
    }
    std::sort(candidates[k].begin(), candidates[k].end());
    if (candidates[k].empty()) out[k].why = "the hand does not slow down near the expected time";
  }
  // Pass 2: successive keys have successive targets. Keys are served from the
  // one whose minimum lies nearest its expected time on; each takes its
  // nearest minimum that keeps the suggested frames strictly increasing in
  // the order of the expected times (two keys whose windows overlap never get
  // the same minimum).
  std::vector<size_t> by_time(expected_s.size()), rank(expected_s.size());
  for (size_t k = 0; k < by_time.size(); ++k) by_time[k] = k;
  std::stable_sort(by_time.begin(), by_time.end(), [&](size_t a, size_t b) { return expected_s[a] < expected_s[b]; });
  for (size_t r = 0; r < by_time.size(); ++r) rank[by_time[r]] = r;
  std::vector<size_t> by_confidence;
  for (size_t k = 0; k < candidates.size(); ++k)
    if (!candidates[k].empty()) by_confidence.push_back(k);
  std::stable_sort(by_confidence.begin(), by_confidence.end(),
                   [&](size_t a, size_t b) { return candidates[a].front().first < candidates[b].front().first; });
  std::map<size_t, int64_t> taken;  // rank -> frame
  for (size_t k : by_confidence) {
    auto next = taken.upper_bound(rank[k]);
    const int64_t above = next == taken.end() ? std::numeric_limits<int64_t>::max() : next->second;
    const int64_t below = next == taken.begin() ? -1 : std::prev(next)->second;
    int64_t best = -1;
    for (const auto& [distance, f] : candidates[k])
      if (f > below && f < above) {
        best = f;
        break;
      }
    if (best < 0) {
      out[k].why = "its speed minima are the targets of the neighbouring keys";
      continue;
    }
    taken[rank[k]] = best;
    SuggestedTarget& s = out[k];
    s.frame = best;
    s.time_s = static_cast<double>(best) / rate_hz;
    s.speed_mm_s = speed(best);
    s.offset_s = s.time_s - s.expected_s;
  }
  return out;
}

std::vector<SuggestedTarget> SuggestTargets(const Eigen::MatrixXd& series, double rate_hz,
                                            const std::vector<double>& expected_s,
                                            const TargetSuggestionOptions& options) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput("target suggestion: " + why);
  return SuggestTargetsFromSpeed(FeatureSpeed(series, rate_hz, options.cutoff_hz), rate_hz, expected_s, options);
}

}  // namespace csw::analysis
