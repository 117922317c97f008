#include "analysis/phasing/posterior_landmarks.h"

#include <algorithm>
#include <cmath>

#include "core/error.h"

namespace csw::phasing {

std::string PosteriorLandmarkOptions::Check() const {
  if (!(plateau_tolerance >= 0.0 && plateau_tolerance < 1.0)) return "plateau_tolerance must be in [0, 1)";
  return "";
}

PosteriorLandmarks FindPosteriorLandmarks(const Eigen::MatrixXd& p, double rate_hz, double start_s, int cls,
                                          double from_s, double to_s, const PosteriorLandmarkOptions& o) {
  if (std::string why = o.Check(); !why.empty()) throw InvalidInput("posterior landmarks: " + why);
  if (!(rate_hz > 0.0)) throw InvalidInput("posterior landmarks: rate_hz must be > 0");
  if (cls < 0 || cls >= p.cols())
    throw InvalidInput("posterior landmarks: class " + std::to_string(cls) + " is not among the " +
                       std::to_string(p.cols()) + " columns");
  if (!(from_s < to_s)) throw InvalidInput("posterior landmarks: the window must have from_s < to_s");
  PosteriorLandmarks out;
  const auto frame = [&](double t) { return (t - start_s) * rate_hz; };
  const auto first = std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::ceil(frame(from_s) - 1e-9)), 0, p.rows());
  const auto last =
      std::clamp<Eigen::Index>(static_cast<Eigen::Index>(std::floor(frame(to_s) + 1e-9)), -1, p.rows() - 1);
  const auto time = [&](double f) { return start_s + f / rate_hz; };
  // Margin of the class over the best other class (NaN when the row is not scored).
  const auto margin = [&](Eigen::Index f) {
    double other = -1.0;
    for (Eigen::Index j = 0; j < p.cols(); ++j)
      if (j != cls) other = std::max(other, p(f, j));
    return p(f, cls) - (p.cols() > 1 ? other : 1.0 - p(f, cls));
  };
  Eigen::Index peak = -1;
  for (Eigen::Index f = first; f <= last; ++f)
    if (std::isfinite(p(f, cls)) && (peak < 0 || p(f, cls) > p(peak, cls))) peak = f;
  if (peak < 0) {
    out.reason = "no scored frame in the window";
    return out;
  }
  out.peak = p(peak, cls);
  if (!(margin(peak) > 0.0)) {
    out.reason = "the class never dominates in the window";
    return out;
  }
  Eigen::Index lo = peak, hi = peak;
  const double level = out.peak - o.plateau_tolerance;
  while (lo > first && std::isfinite(p(lo - 1, cls)) && p(lo - 1, cls) >= level) --lo;
  while (hi < last && std::isfinite(p(hi + 1, cls)) && p(hi + 1, cls) >= level) ++hi;
  out.target_s = time(0.5 * static_cast<double>(lo + hi));
  Eigen::Index f = peak;
  while (f > first && std::isfinite(p(f - 1, cls)) && margin(f - 1) > 0.0) --f;
  if (f == first || !std::isfinite(p(f - 1, cls))) {
    out.onset_s = time(static_cast<double>(f));
    out.onset_at_window_start = f == first;
  } else {  // margin(f - 1) <= 0 < margin(f): zero crossing between the two frames
    const double m0 = margin(f - 1), m1 = margin(f);
    out.onset_s = time(static_cast<double>(f - 1) + m0 / (m0 - m1));
  }
  out.found = true;
  return out;
}

}  // namespace csw::phasing
