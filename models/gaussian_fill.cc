#include "models/gaussian_fill.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <string>

#include "core/error.h"

namespace csw {
namespace {

// Coordinate indices of the seen and missing markers of a pattern.
void Indices(const std::vector<uint8_t>& pattern, std::vector<int>* seen, std::vector<int>* missing) {
  seen->clear();
  missing->clear();
  for (size_t m = 0; m < pattern.size(); ++m) {
    for (int k = 0; k < 3; ++k) (pattern[m] ? seen : missing)->push_back(static_cast<int>(3 * m) + k);
  }
}

// (Σ + ρI)⁻¹: with it, the gain of any pattern needs only a solve of the
// missing block's size. (Σ + ρI) and Σ share Σ_hv, so the conditional mean
// under Σ + ρI is exactly μ_h + Σ_hv (Σ_vv + ρI)⁻¹ (x_v − μ_v).
Eigen::MatrixXd Precision(const Eigen::MatrixXd& cov, double ridge) {
  Eigen::MatrixXd c = cov;
  c.diagonal().array() += ridge;
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(c);
  return ldlt.solve(Eigen::MatrixXd::Identity(c.rows(), c.cols()));
}

// Gain Σ_hv (Σ_vv + ρI)⁻¹ = −P_hh⁻¹ P_hv (P the precision above) and, when
// wanted, the conditional covariance of the missing block,
// Σ_hh − Σ_hv (Σ_vv + ρI)⁻¹ Σ_vh = P_hh⁻¹ − ρI.
Eigen::MatrixXd Gain(const Eigen::MatrixXd& precision, double ridge, const std::vector<int>& seen,
                     const std::vector<int>& missing, Eigen::MatrixXd* conditional) {
  const Eigen::Index nv = static_cast<Eigen::Index>(seen.size()), nh = static_cast<Eigen::Index>(missing.size());
  Eigen::MatrixXd phh(nh, nh), phv(nh, nv);
  for (Eigen::Index a = 0; a < nh; ++a) {
    for (Eigen::Index b = 0; b < nh; ++b) phh(a, b) = precision(missing[a], missing[b]);
    for (Eigen::Index b = 0; b < nv; ++b) phv(a, b) = precision(missing[a], seen[b]);
  }
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(phh);
  if (conditional) {
    *conditional = ldlt.solve(Eigen::MatrixXd::Identity(nh, nh));
    conditional->diagonal().array() -= ridge;
  }
  return -ldlt.solve(phv);
}

}  // namespace

GaussianFill FitGaussianFill(const Eigen::MatrixXd& data, const GaussianFillOptions& options, Progress* progress) {
  if (data.cols() == 0 || data.cols() % 3 != 0) {
    throw InvalidInput("gaussian fill: " + std::to_string(data.cols()) + " columns, not 3 per marker");
  }
  if (data.array().isInf().any()) throw InvalidInput("gaussian fill: an infinite coordinate");
  if (!(options.ridge_mm2 >= 0) || options.max_iterations < 1 || !(options.tolerance_mm > 0)) {
    throw InvalidInput("gaussian fill: ridge must be >= 0, iterations >= 1, tolerance > 0");
  }
  const Eigen::Index markers = data.cols() / 3, d = data.cols();
  // Usable rows and their patterns (a marker is seen when its 3 values are finite).
  std::vector<Eigen::Index> rows;
  std::map<std::vector<uint8_t>, std::vector<Eigen::Index>> groups;  // pattern → positions in `rows`
  for (Eigen::Index f = 0; f < data.rows(); ++f) {
    std::vector<uint8_t> pattern(static_cast<size_t>(markers));
    int seen = 0;
    for (Eigen::Index m = 0; m < markers; ++m) {
      pattern[static_cast<size_t>(m)] = data.row(f).segment<3>(3 * m).allFinite() ? 1 : 0;
      seen += pattern[static_cast<size_t>(m)];
    }
    if (seen < std::max(1, options.min_visible_markers)) continue;
    groups[pattern].push_back(static_cast<Eigen::Index>(rows.size()));
    rows.push_back(f);
  }
  const Eigen::Index n = static_cast<Eigen::Index>(rows.size());
  if (n < 2) throw InvalidInput("gaussian fill: " + std::to_string(n) + " usable frames (need at least 2)");
  Eigen::MatrixXd x(n, d);
  Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> seen(n, d);
  for (Eigen::Index r = 0; r < n; ++r) {
    for (Eigen::Index m = 0; m < markers; ++m) {
      const bool ok = data.row(rows[static_cast<size_t>(r)]).segment<3>(3 * m).allFinite();
      for (int k = 0; k < 3; ++k) {
        seen(r, 3 * m + k) = ok;
        x(r, 3 * m + k) = ok ? data(rows[static_cast<size_t>(r)], 3 * m + k) : 0.0;
      }
    }
  }
  // Start: each missing value at its column's mean.
  for (Eigen::Index c = 0; c < d; ++c) {
    double sum = 0;
    Eigen::Index count = 0;
    for (Eigen::Index r = 0; r < n; ++r) {
      if (seen(r, c)) {
        sum += x(r, c);
        ++count;
      }
    }
    if (count == 0) {
      throw InvalidInput("gaussian fill: marker " + std::to_string(c / 3) + " is never seen in the training frames");
    }
    for (Eigen::Index r = 0; r < n; ++r) {
      if (!seen(r, c)) x(r, c) = sum / static_cast<double>(count);
    }
  }
  GaussianFill out;
  out.ridge_mm2 = options.ridge_mm2;
  out.frames = n;
  Eigen::MatrixXd extra = Eigen::MatrixXd::Zero(d, d);  // Σ of the conditional covariances
  std::vector<int> vi, hi;
  Eigen::MatrixXd conditional;
  for (int it = 0; it < options.max_iterations; ++it) {
    if (progress) progress->Update("gaussian fill (EM)", static_cast<double>(it) / options.max_iterations);
    // M step.
    out.mean = x.colwise().mean().transpose();
    const Eigen::MatrixXd centred = x.rowwise() - out.mean.transpose();
    out.covariance = (centred.transpose() * centred + extra) / static_cast<double>(n);
    out.iterations = it + 1;
    // E step.
    extra.setZero();
    const Eigen::MatrixXd precision = Precision(out.covariance, options.ridge_mm2);
    double change = 0;
    for (const auto& [pattern, members] : groups) {
      Indices(pattern, &vi, &hi);
      if (hi.empty()) continue;
      const Eigen::MatrixXd gain = Gain(precision, options.ridge_mm2, vi, hi, &conditional);
      Eigen::VectorXd dv(static_cast<Eigen::Index>(vi.size()));
      for (Eigen::Index r : members) {
        for (size_t a = 0; a < vi.size(); ++a) dv(static_cast<Eigen::Index>(a)) = x(r, vi[a]) - out.mean(vi[a]);
        const Eigen::VectorXd xh = gain * dv;
        for (size_t b = 0; b < hi.size(); ++b) {
          const double value = out.mean(hi[b]) + xh(static_cast<Eigen::Index>(b));
          change = std::max(change, std::abs(value - x(r, hi[b])));
          x(r, hi[b]) = value;
        }
      }
      const double count = static_cast<double>(members.size());
      for (size_t a = 0; a < hi.size(); ++a)
        for (size_t b = 0; b < hi.size(); ++b)
          extra(hi[a], hi[b]) += count * conditional(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
    }
    if (change < options.tolerance_mm) break;
  }
  out.mean = x.colwise().mean().transpose();
  const Eigen::MatrixXd centred = x.rowwise() - out.mean.transpose();
  out.covariance = (centred.transpose() * centred + extra) / static_cast<double>(n);
  out.covariance = 0.5 * (out.covariance + out.covariance.transpose()).eval();
  if (progress) progress->Update("gaussian fill (EM)", 1.0);
  return out;
}

GaussianFiller::GaussianFiller(const GaussianFill& fill)
    : fill_(fill), precision_(fill.empty() ? Eigen::MatrixXd() : Precision(fill.covariance, fill.ridge_mm2)) {}

int GaussianFiller::Fill(Eigen::Matrix3Xd* markers) {
  const Eigen::Index nm = fill_.markers();
  if (markers->cols() != nm) {
    throw InvalidInput("gaussian fill: " + std::to_string(markers->cols()) + " markers given, the fill has " +
                       std::to_string(nm));
  }
  std::vector<uint8_t> pattern(static_cast<size_t>(nm));
  int seen = 0;
  for (Eigen::Index m = 0; m < nm; ++m) {
    pattern[static_cast<size_t>(m)] = markers->col(m).allFinite() ? 1 : 0;
    seen += pattern[static_cast<size_t>(m)];
  }
  if (seen == 0 || seen == nm) return 0;
  SetPattern(pattern);
  Eigen::VectorXd dv(static_cast<Eigen::Index>(seen_.size()));
  for (size_t a = 0; a < seen_.size(); ++a) {
    dv(static_cast<Eigen::Index>(a)) = (*markers)(seen_[a] % 3, seen_[a] / 3) - fill_.mean(seen_[a]);
  }
  const Eigen::VectorXd xh = gain_ * dv;
  for (size_t b = 0; b < missing_.size(); ++b) {
    (*markers)(missing_[b] % 3, missing_[b] / 3) = fill_.mean(missing_[b]) + xh(static_cast<Eigen::Index>(b));
  }
  return static_cast<int>(nm - seen);
}

void GaussianFiller::SetPattern(const std::vector<uint8_t>& pattern) {
  if (pattern == pattern_) return;
  Indices(pattern, &seen_, &missing_);
  gain_ = Gain(precision_, fill_.ridge_mm2, seen_, missing_, nullptr);
  pattern_ = pattern;
}

Eigen::Vector3d GaussianFiller::Predict(const std::vector<uint8_t>& pattern, int marker,
                                        const Eigen::Matrix3Xd& markers) {
  const Eigen::Index nm = fill_.markers();
  if (markers.cols() != nm || static_cast<Eigen::Index>(pattern.size()) != nm) {
    throw InvalidInput("gaussian fill: " + std::to_string(markers.cols()) + " markers given, the fill has " +
                       std::to_string(nm));
  }
  const Eigen::Vector3d nan = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  if (marker < 0 || marker >= nm || pattern[static_cast<size_t>(marker)]) return nan;
  int seen = 0;
  for (uint8_t v : pattern) seen += v ? 1 : 0;
  if (seen == 0) return nan;
  SetPattern(pattern);
  // Rows of the marker's three coordinates in the missing block.
  const auto it = std::lower_bound(missing_.begin(), missing_.end(), 3 * marker);
  const Eigen::Index row = it - missing_.begin();
  Eigen::Vector3d out = fill_.mean.segment<3>(3 * marker);
  for (size_t a = 0; a < seen_.size(); ++a) {
    const double dv = markers(seen_[a] % 3, seen_[a] / 3) - fill_.mean(seen_[a]);
    for (int k = 0; k < 3; ++k) out(k) += gain_(row + k, static_cast<Eigen::Index>(a)) * dv;
  }
  return out;
}

}  // namespace csw
