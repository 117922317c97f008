#include "analysis/cleaning/dct_fill.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <memory>
#include <vector>

#include "core/error.h"

namespace csw::cleaning {

std::string DctFillOptions::Check() const {
  if (side_frames < 1) return "dct fill: side_frames " + std::to_string(side_frames) + " must be ≥ 1";
  if (context_frames < side_frames)
    return "dct fill: context_frames " + std::to_string(context_frames) + " must be ≥ side_frames " +
           std::to_string(side_frames);
  if (max_gap_frames < 0) return "dct fill: max_gap_frames " + std::to_string(max_gap_frames) + " is negative";
  if (!(smoothing >= 0.0) || !std::isfinite(smoothing)) return "dct fill: smoothing must be a finite s ≥ 0 (0 = GCV)";
  if (max_iterations < 1) return "dct fill: max_iterations must be ≥ 1";
  if (!(tolerance_mm > 0.0)) return "dct fill: tolerance_mm must be > 0";
  if (max_window_frames < 2 * static_cast<int64_t>(context_frames) + 1 || max_window_frames > 4096)
    return "dct fill: max_window_frames must be in 2 × context_frames + 1 .. 4096";
  return "";
}

Eigen::MatrixXd DctMatrix(int n) {
  if (n < 1) throw InvalidInput("DCT matrix: size " + std::to_string(n) + " must be ≥ 1");
  Eigen::MatrixXd c(n, n);
  const double a0 = std::sqrt(1.0 / n), a = std::sqrt(2.0 / n);
  for (int k = 0; k < n; ++k)
    for (int j = 0; j < n; ++j) c(k, j) = (k == 0 ? a0 : a) * std::cos(M_PI * (2.0 * j + 1.0) * k / (2.0 * n));
  return c;
}

namespace {

// Per-thread cache of DCT matrices by window length (fills on different
// threads do not share it).
const Eigen::MatrixXd& CachedDct(int n) {
  thread_local std::map<int, std::unique_ptr<Eigen::MatrixXd>> cache;
  auto it = cache.find(n);
  if (it != cache.end()) return *it->second;
  if (cache.size() >= 64) cache.clear();
  auto m = std::make_unique<Eigen::MatrixXd>(DctMatrix(n));
  return *cache.emplace(n, std::move(m)).first->second;
}

// Linear interpolation across weight-0 frames, constant beyond the first and
// last valid frames.
Eigen::VectorXd InitialGuess(const Eigen::VectorXd& y, const Eigen::VectorXd& w) {
  const Eigen::Index n = y.size();
  Eigen::VectorXd z = y;
  Eigen::Index prev = -1;
  for (Eigen::Index i = 0; i <= n; ++i) {
    if (i < n && !(w[i] > 0)) continue;
    for (Eigen::Index j = prev + 1; j < i; ++j) {
      if (prev < 0)
        z[j] = y[i];
      else if (i == n)
        z[j] = y[prev];
      else
        z[j] = y[prev] + (y[i] - y[prev]) * static_cast<double>(j - prev) / static_cast<double>(i - prev);
    }
    prev = i;
  }
  return z;
}

}  // namespace

DctSmoothResult DctSmooth(const Eigen::MatrixXd& y, const Eigen::VectorXd& w, double smoothing, int max_iterations,
                          double tolerance) {
  if (y.rows() != w.size())
    throw InvalidInput("DCT smooth: " + std::to_string(y.rows()) + " rows but " + std::to_string(w.size()) +
                       " weights");
  if (!(smoothing >= 0.0) || !std::isfinite(smoothing))
    throw InvalidInput("DCT smooth: smoothing must be a finite s ≥ 0 (0 = GCV)");
  if (max_iterations < 1 || !(tolerance > 0.0))
    throw InvalidInput("DCT smooth: max_iterations must be ≥ 1 and the tolerance > 0");
  if (y.rows() > 4096)
    throw InvalidInput("DCT smooth: window of " + std::to_string(y.rows()) +
                       " frames, at most 4096 for the matrix DCT");
  const int n = static_cast<int>(y.rows());
  double wmax = 0.0;
  int64_t valid = 0;
  for (int i = 0; i < n; ++i) {
    if (!(w[i] >= 0.0) || !std::isfinite(w[i]))
      throw InvalidInput("DCT smooth: weight " + std::to_string(i) + " is not a finite number ≥ 0");
    wmax = std::max(wmax, w[i]);
    valid += w[i] > 0 ? 1 : 0;
  }
  if (valid == 0) throw InvalidInput("DCT smooth: no frame with a weight > 0");
  const Eigen::VectorXd wn = w / wmax;  // Garcia: weights scaled to max 1
  const bool weighted = (wn.array() < 1.0).any();
  const double relax = weighted ? 1.75 : 1.0;  // smoothn's over-relaxation

  const Eigen::MatrixXd& c = CachedDct(n);
  Eigen::ArrayXd lambda2(n);
  for (int k = 0; k < n; ++k) {
    const double l = -2.0 + 2.0 * std::cos(k * M_PI / n);
    lambda2[k] = l * l;
  }
  // smoothn's bounds on s from the leverage h (one dimension).
  auto s_bound = [](double h) {
    const double h2 = h * h;
    const double t = (1.0 + std::sqrt(1.0 + 8.0 * h2)) / 4.0 / h2;
    return (t * t - 1.0) / 16.0;
  };
  const double log_s_min = std::log10(s_bound(0.99));
  const double log_s_max = std::min(12.0, std::log10(s_bound(1e-6)));

  // DᵀD = D² for the symmetric reflective second-difference matrix D.
  Eigen::MatrixXd second_diff_sq;
  if (weighted) {
    Eigen::MatrixXd d = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i) {
      d(i, i) = (i == 0 || i == n - 1) ? -1.0 : -2.0;
      if (i > 0) d(i, i - 1) = 1.0;
      if (i + 1 < n) d(i, i + 1) = 1.0;
    }
    if (n == 1) d(0, 0) = 0.0;
    second_diff_sq = d * d;
  }
  DctSmoothResult result;
  result.z.resize(n, y.cols());
  result.s.resize(y.cols());
  result.gcv.resize(y.cols());
  result.iterations.resize(y.cols());
  for (Eigen::Index col = 0; col < y.cols(); ++col) {
    // Centre on the weighted mean (the penalty ignores constants: Λ_0 = 0).
    double mean = 0.0;
    for (int i = 0; i < n; ++i) mean += wn[i] * (wn[i] > 0 ? y(i, col) : 0.0);
    mean /= wn.sum();
    Eigen::VectorXd yc(n);
    for (int i = 0; i < n; ++i) yc[i] = wn[i] > 0 ? y(i, col) - mean : 0.0;
    Eigen::VectorXd z = InitialGuess(yc, wn);
    double s = smoothing > 0 ? smoothing : 1.0;
    double gcv = std::numeric_limits<double>::quiet_NaN();
    Eigen::ArrayXd gamma = 1.0 / (1.0 + s * lambda2);
    int it = 0;
    bool converged = false;
    while (it < max_iterations) {
      ++it;
      const Eigen::VectorXd dct_y = c * (wn.cwiseProduct(yc - z) + z);
      // GCV score of log10 s on the current DCT coefficients (Garcia 2010, §2.3 and smoothn).
      auto score = [&](double log_s) {
        const Eigen::ArrayXd g = 1.0 / (1.0 + std::pow(10.0, log_s) * lambda2);
        const Eigen::VectorXd yhat = c.transpose() * (g * dct_y.array()).matrix();
        double rss = 0.0;
        for (int i = 0; i < n; ++i) rss += wn[i] * (yc[i] - yhat[i]) * (yc[i] - yhat[i]);
        const double tr = g.sum();
        const double d = 1.0 - tr / n;
        return rss / static_cast<double>(valid) / std::max(d * d, 1e-300);
      };
      if (smoothing <= 0 && (it & (it - 1)) == 0) {
        // Half-decade grid over the bounds, then golden-section refinement
        // (smoothn uses fminbnd; the grid guards against a local minimum).
        double best = log_s_min, best_score = std::numeric_limits<double>::infinity();
        for (double e = log_s_min; e <= log_s_max + 1e-9; e += 0.5) {
          const double v = score(e);
          if (v < best_score) {
            best_score = v;
            best = e;
          }
        }
        double a = std::max(log_s_min, best - 0.5), b = std::min(log_s_max, best + 0.5);
        const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
        double x1 = b - phi * (b - a), x2 = a + phi * (b - a);
        double f1 = score(x1), f2 = score(x2);
        for (int g = 0; g < 10; ++g) {
          if (f1 < f2) {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - phi * (b - a);
            f1 = score(x1);
          } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + phi * (b - a);
            f2 = score(x2);
          }
        }
        const double e = f1 < f2 ? x1 : x2;
        if (std::min(f1, f2) < best_score) best = e;
        s = std::pow(10.0, best);
        gamma = 1.0 / (1.0 + s * lambda2);
        gcv = score(best);
      }
      const Eigen::VectorXd znew = relax * (c.transpose() * (gamma * dct_y.array()).matrix()) - (relax - 1.0) * z;
      const double change = (znew - z).cwiseAbs().maxCoeff();
      z = znew;
      if (!weighted || change < tolerance) {
        converged = true;
        break;
      }
    }
    if (weighted) {
      // The iteration's limit, computed directly: (W + s DᵀD) z = W y with D
      // the reflective second difference (D = Cᵀ Λ C, so DᵀD = Cᵀ Λ² C). The
      // iteration converges slowly when s is small (little smoothing, long
      // gaps); its fixed point is this solution (tests/analysis/dct_fill_test.cc).
      Eigen::MatrixXd a = s * second_diff_sq;
      a.diagonal() += wn;
      z = a.ldlt().solve(wn.cwiseProduct(yc));
    }
    if (smoothing > 0 || std::isnan(gcv)) {
      // GCV at the final s (fixed s, or reported for the converged fit).
      double rss = 0.0;
      for (int i = 0; i < n; ++i) rss += wn[i] * (yc[i] - z[i]) * (yc[i] - z[i]);
      const double d = 1.0 - gamma.sum() / n;
      gcv = rss / static_cast<double>(valid) / std::max(d * d, 1e-300);
    }
    result.z.col(col) = z.array() + mean;
    result.s[col] = s;
    result.gcv[col] = gcv;
    result.iterations[col] = it;
    result.converged = result.converged && converged;
  }
  return result;
}

DctFiller::DctFiller(const DctFillOptions& options) : options_(options) {
  const std::string err = options_.Check();
  if (!err.empty()) throw InvalidInput(err);
}

bool DctFiller::CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const {
  std::string why;
  if (options_.max_gap_frames > 0 && gap.length > options_.max_gap_frames)
    why = "gap of " + std::to_string(gap.length) + " frames longer than the DCT fill's maximum of " +
          std::to_string(options_.max_gap_frames) + " frames";
  else if (gap.length + 2 * static_cast<int64_t>(options_.context_frames) > options_.max_window_frames)
    why = "gap of " + std::to_string(gap.length) + " frames too long for the DCT window of at most " +
          std::to_string(options_.max_window_frames) + " frames";
  else
    why = CheckSides(in, gap, options_.side_frames);
  if (why_not != nullptr) *why_not = why;
  return why.empty();
}

bool DctFiller::Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const {
  if (!CanFill(in, gap, nullptr)) return false;
  const int64_t first = std::max<int64_t>(0, gap.start - options_.context_frames);
  const int64_t last = std::min<int64_t>(in.frames(), gap.end() + options_.context_frames);
  const int n = static_cast<int>(last - first);
  Eigen::MatrixXd y(n, 3);
  Eigen::VectorXd w(n);
  for (int i = 0; i < n; ++i) {
    const int64_t f = first + i;
    const bool ok = !SampleMissing(in, f, gap.marker);
    w[i] = ok ? 1.0 : 0.0;
    const float* p = in.at(f, gap.marker);
    for (int c = 0; c < 3; ++c) y(i, c) = ok ? p[c] : 0.0;
  }
  DctSmoothResult fit;
  try {
    fit = DctSmooth(y, w, options_.smoothing, options_.max_iterations, options_.tolerance_mm);
  } catch (const InvalidInput&) {
    return false;
  }
  for (int64_t f = gap.start; f < gap.end(); ++f) {
    const int i = static_cast<int>(f - first);
    if (!fit.z.row(i).allFinite()) return false;
    float* q = out->at(f, gap.marker);
    for (int c = 0; c < 3; ++c) q[c] = static_cast<float>(fit.z(i, c));
  }
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "kind=DCT penalised least squares (Garcia 2010), s=%s[%.3g, %.3g, %.3g], iterations=[%d, %d, %d]%s, "
                "window=%lld+%lld frames",
                options_.smoothing > 0 ? "fixed" : "GCV", fit.s[0], fit.s[1], fit.s[2], fit.iterations[0],
                fit.iterations[1], fit.iterations[2], fit.converged ? "" : " (not converged)",
                static_cast<long long>(gap.start - first), static_cast<long long>(last - gap.end()));
  record->method = name();
  record->parameters = buf;
  return true;
}

}  // namespace csw::cleaning
