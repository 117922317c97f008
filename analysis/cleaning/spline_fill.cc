#include "analysis/cleaning/spline_fill.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <unsupported/Eigen/Splines>
#include <vector>

#include "core/error.h"

namespace csw::cleaning {

const char* SplineKindName(SplineKind kind) {
  switch (kind) {
    case SplineKind::kCubic:
      return "cubic";
    case SplineKind::kQuintic:
      return "quintic";
    case SplineKind::kSmoothing:
      return "smoothing";
  }
  return "?";
}

std::string SplineFillOptions::Check() const {
  const int degree = kind == SplineKind::kQuintic ? 5 : 3;
  if (side_frames < 1) return "spline fill: side_frames " + std::to_string(side_frames) + " must be ≥ 1";
  if (kind != SplineKind::kSmoothing && 2 * side_frames < degree + 1)
    return "spline fill: the " + std::string(SplineKindName(kind)) + " spline needs side_frames ≥ " +
           std::to_string((degree + 2) / 2) + " (" + std::to_string(degree + 1) + " frames in all), got " +
           std::to_string(side_frames);
  if (max_gap_frames < 0) return "spline fill: max_gap_frames " + std::to_string(max_gap_frames) + " is negative";
  if (kind == SplineKind::kSmoothing) {
    if (order < 1 || order > 6) return "spline fill: order " + std::to_string(order) + " must be in 1..6";
    if (context_frames < side_frames)
      return "spline fill: context_frames " + std::to_string(context_frames) + " must be ≥ side_frames " +
             std::to_string(side_frames);
    if (2 * side_frames < order + 1)
      return "spline fill: order " + std::to_string(order) + " needs side_frames ≥ " + std::to_string((order + 2) / 2);
    if (!(smoothing >= 0.0) || !std::isfinite(smoothing))
      return "spline fill: smoothing must be a finite p ≥ 0 (0 = GCV)";
  }
  return "";
}

// ---------------------------------------------------------------------------
// Banded penalised least squares.
namespace {

// Symmetric positive definite band matrix of half-bandwidth m, its LDLᵀ factor
// (Golub & Van Loan, Matrix Computations, 4th ed., §4.3.6: band LDLᵀ) and the
// band of its inverse (Takahashi recursion). Eigen has no banded solver, and
// the selected inverse needs the band of L directly.
template <int M>
class BandLdlt {
 public:
  explicit BandLdlt(int n) : n_(n), l_(static_cast<size_t>(n) * (M + 1), 0.0), d_(static_cast<size_t>(n), 0.0) {}

  // a(i, k) = A(i, i − k), k = 0..m, row-major n × (m + 1). Returns false when
  // A is not numerically positive definite.
  bool Factor(const std::vector<double>& a) {
    for (int j = 0; j < n_; ++j) {
      double d = a[Idx(j, 0)];
      for (int k = std::max(0, j - m_); k < j; ++k) d -= L(j, k) * L(j, k) * d_[k];
      if (!(d > 1e-12 * std::max(1.0, a[Idx(j, 0)]))) return false;
      d_[j] = d;
      for (int i = j + 1; i <= std::min(n_ - 1, j + m_); ++i) {
        double s = a[Idx(i, i - j)];
        for (int k = std::max(0, i - m_); k < j; ++k) s -= L(i, k) * L(j, k) * d_[k];
        l_[Idx(i, i - j)] = s / d;
      }
    }
    return true;
  }

  // Solves A x = b in place.
  void Solve(double* b) const {
    for (int i = 0; i < n_; ++i)
      for (int k = std::max(0, i - m_); k < i; ++k) b[i] -= L(i, k) * b[k];
    for (int i = 0; i < n_; ++i) b[i] /= d_[i];
    for (int i = n_ - 1; i >= 0; --i)
      for (int k = i + 1; k <= std::min(n_ - 1, i + m_); ++k) b[i] -= L(k, i) * b[k];
  }

  // Diagonal of A⁻¹ (Takahashi, Fagan & Chin 1973; Hutchinson & de Hoog 1985):
  // Z = D⁻¹L⁻¹ + (I − Lᵀ) Z, evaluated from the last row up inside the band.
  void InverseDiagonal(std::vector<double>* diag) {
    std::vector<double>& z = z_;  // z(i, k) = Z(i, i + k)
    z.assign(static_cast<size_t>(n_) * (m_ + 1), 0.0);
    auto zget = [&](int a, int b) {
      if (a > b) std::swap(a, b);
      return z[Idx(a, b - a)];
    };
    for (int i = n_ - 1; i >= 0; --i) {
      const int kmax = std::min(n_ - 1, i + m_);
      for (int j = kmax; j > i; --j) {
        double s = 0.0;
        for (int k = i + 1; k <= kmax; ++k) s += L(k, i) * zget(k, j);
        z[Idx(i, j - i)] = -s;
      }
      double s = 0.0;
      for (int k = i + 1; k <= kmax; ++k) s += L(k, i) * z[Idx(i, k - i)];
      z[Idx(i, 0)] = 1.0 / d_[i] - s;
    }
    diag->resize(static_cast<size_t>(n_));
    for (int i = 0; i < n_; ++i) (*diag)[i] = z[Idx(i, 0)];
  }

 private:
  size_t Idx(int i, int k) const { return static_cast<size_t>(i) * (m_ + 1) + k; }
  double L(int i, int j) const { return l_[Idx(i, i - j)]; }  // j < i, i − j ≤ m
  static constexpr int m_ = M;  // half-bandwidth, known at compile time so the band loops unroll
  int n_;
  std::vector<double> l_, d_, z_;
};

// The band of DᵀD for the m-th difference matrix D ((n − m) × n).
std::vector<double> DifferencePenalty(int n, int m) {
  std::vector<double> c(static_cast<size_t>(m) + 1);
  for (int k = 0; k <= m; ++k) {
    double b = 1.0;  // C(m, k)
    for (int j = 1; j <= k; ++j) b = b * (m - k + j) / j;
    c[k] = ((m - k) % 2 == 0 ? 1.0 : -1.0) * b;
  }
  std::vector<double> p(static_cast<size_t>(n) * (m + 1), 0.0);
  for (int r = 0; r + m < n; ++r)
    for (int a = 0; a <= m; ++a)
      for (int b = 0; b <= a; ++b) p[static_cast<size_t>(r + a) * (m + 1) + (a - b)] += c[a] * c[b];
  return p;
}

template <int M>
class PenalisedProblem {
 public:
  PenalisedProblem(const Eigen::MatrixXd& y, const Eigen::VectorXd& w)
      : n_(static_cast<int>(y.rows())), w_(w), penalty_(DifferencePenalty(n_, M)), ldlt_(n_) {
    for (int i = 0; i < n_; ++i) valid_ += w_[i] > 0 ? 1 : 0;
    // Centre each column on its weighted mean (the penalty ignores constants,
    // so this is exact) to keep the solve well conditioned at large p.
    mean_.resize(y.cols());
    wy_.resize(n_, y.cols());
    yc_.resize(n_, y.cols());
    const double wsum = w_.sum();
    for (Eigen::Index c = 0; c < y.cols(); ++c) {
      double s = 0.0;
      for (int i = 0; i < n_; ++i)
        if (w_[i] > 0) s += w_[i] * y(i, c);
      mean_[c] = s / wsum;
      for (int i = 0; i < n_; ++i) {
        yc_(i, c) = w_[i] > 0 ? y(i, c) - mean_[c] : 0.0;
        wy_(i, c) = w_[i] * yc_(i, c);
      }
    }
  }

  int64_t valid() const { return valid_; }

  // Fits with smoothing p; fills z (centred), the trace and per-column GCV.
  bool Evaluate(double p, Eigen::MatrixXd* z, double* trace, Eigen::VectorXd* gcv) {
    std::vector<double>& a = a_;
    a.resize(penalty_.size());
    for (size_t k = 0; k < a.size(); ++k) a[k] = p * penalty_[k];
    for (int i = 0; i < n_; ++i) a[static_cast<size_t>(i) * (m_ + 1)] += w_[i];
    if (!ldlt_.Factor(a)) return false;
    std::vector<double>& zd = zd_;
    ldlt_.InverseDiagonal(&zd);
    double tr = 0.0;
    for (int i = 0; i < n_; ++i) tr += w_[i] * zd[i];
    *trace = tr;
    *z = wy_;
    gcv->resize(z->cols());
    const double nn = static_cast<double>(valid_);
    const double denom = std::max(1.0 - tr / nn, 1e-12);
    for (Eigen::Index c = 0; c < z->cols(); ++c) {
      ldlt_.Solve(z->col(c).data());
      double rss = 0.0;
      for (int i = 0; i < n_; ++i) {
        const double r = yc_(i, c) - (*z)(i, c);
        rss += w_[i] * r * r;
      }
      (*gcv)[c] = rss / nn / (denom * denom);
    }
    return true;
  }

  double mean(Eigen::Index c) const { return mean_[c]; }

 private:
  static constexpr int m_ = M;
  int n_;
  Eigen::VectorXd w_;
  std::vector<double> penalty_;
  BandLdlt<M> ldlt_;
  int64_t valid_ = 0;
  Eigen::VectorXd mean_;
  Eigen::MatrixXd wy_, yc_;
  std::vector<double> a_, zd_;
};

}  // namespace

namespace {

template <int M>
PenalisedFit SmoothImpl(const Eigen::MatrixXd& y, const Eigen::VectorXd& w, double smoothing, bool joint) {
  const int n = static_cast<int>(y.rows());
  const int order = M;
  PenalisedProblem<M> problem(y, w);
  if (problem.valid() < order + 1)
    throw InvalidInput("penalised smooth: " + std::to_string(problem.valid()) + " weighted frames, at least " +
                       std::to_string(order + 1) + " needed for order " + std::to_string(order));
  const Eigen::Index cols = y.cols();
  PenalisedFit fit;
  fit.valid = problem.valid();
  fit.z.resize(n, cols);
  fit.p.resize(cols);
  fit.trace.resize(cols);
  fit.gcv.resize(cols);
  Eigen::MatrixXd z;
  Eigen::VectorXd gcv;
  double trace = 0.0;
  auto fail = [&](double p) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.3g", p);
    return InvalidInput(std::string("penalised smooth: the system is not positive definite at p = ") + buf +
                        " (too few distinct valid frames?)");
  };
  auto store = [&](Eigen::Index c, double p) {
    fit.z.col(c) = z.col(c).array() + problem.mean(c);
    fit.p[c] = p;
    fit.trace[c] = trace;
    fit.gcv[c] = gcv[c];
  };
  if (smoothing > 0.0) {
    if (!problem.Evaluate(smoothing, &z, &trace, &gcv)) throw fail(smoothing);
    for (Eigen::Index c = 0; c < cols; ++c) store(c, smoothing);
    return fit;
  }
  // GCV: a one-decade grid of log10 p over cut-offs from the Nyquist
  // frequency (p·π^(2m) = 1, no smoothing) down to about 1/N rad per frame
  // (a polynomial fit of the window), capped at 1e10 for conditioning; then
  // one parabolic step around the best grid point.
  const double lo = -2.0 * order * std::log10(M_PI);
  const double hi = std::min(10.0, 2.0 * order * std::log10(std::max(n, 4)));
  const double step = 1.0;
  std::vector<double> grid;
  for (double e = lo; e < hi + 1e-9; e += step) grid.push_back(e);
  std::vector<Eigen::VectorXd> scores(grid.size());
  std::vector<bool> ok(grid.size(), false);
  for (size_t g = 0; g < grid.size(); ++g) {
    ok[g] = problem.Evaluate(std::pow(10.0, grid[g]), &z, &trace, &gcv);
    if (ok[g]) scores[g] = gcv;
  }
  // The criterion of column c, or of all columns together (joint: one p,
  // GCV of the pooled residuals, Σ_c RSS_c with the common tr H).
  auto crit = [&](const Eigen::VectorXd& v, Eigen::Index c) { return joint ? v.sum() : v[c]; };
  for (Eigen::Index c = 0; c < (joint ? 1 : cols); ++c) {
    int best = -1;
    for (size_t g = 0; g < grid.size(); ++g)
      if (ok[g] && (best < 0 || crit(scores[g], c) < crit(scores[static_cast<size_t>(best)], c)))
        best = static_cast<int>(g);
    if (best < 0) throw fail(std::pow(10.0, grid.back()));
    double best_e = grid[static_cast<size_t>(best)];
    const double fb = crit(scores[static_cast<size_t>(best)], c);
    if (best > 0 && best + 1 < static_cast<int>(grid.size()) && ok[static_cast<size_t>(best) - 1] &&
        ok[static_cast<size_t>(best) + 1]) {
      // Parabolic refinement through the best grid point and its neighbours
      // (one step of Brent's method on log10 p).
      const double fa = crit(scores[static_cast<size_t>(best) - 1], c);
      const double fc = crit(scores[static_cast<size_t>(best) + 1], c);
      const double curv = fa - 2.0 * fb + fc;
      if (curv > 0) {
        const double e = best_e - 0.5 * step * (fc - fa) / curv;
        if (problem.Evaluate(std::pow(10.0, e), &z, &trace, &gcv) && crit(gcv, c) < fb) best_e = e;
      }
    }
    if (!problem.Evaluate(std::pow(10.0, best_e), &z, &trace, &gcv)) throw fail(std::pow(10.0, best_e));
    if (joint)
      for (Eigen::Index k = 0; k < cols; ++k) store(k, std::pow(10.0, best_e));
    else
      store(c, std::pow(10.0, best_e));
  }
  return fit;
}

}  // namespace

PenalisedFit PenalisedSmooth(const Eigen::MatrixXd& y, const Eigen::VectorXd& w, int order, double smoothing,
                             bool joint) {
  if (y.rows() != w.size())
    throw InvalidInput("penalised smooth: " + std::to_string(y.rows()) + " rows but " + std::to_string(w.size()) +
                       " weights");
  if (order < 1) throw InvalidInput("penalised smooth: order " + std::to_string(order) + " must be ≥ 1");
  if (!(smoothing >= 0.0) || !std::isfinite(smoothing))
    throw InvalidInput("penalised smooth: smoothing must be a finite p ≥ 0 (0 = GCV)");
  for (Eigen::Index i = 0; i < w.size(); ++i)
    if (!(w[i] >= 0.0) || !std::isfinite(w[i]))
      throw InvalidInput("penalised smooth: weight " + std::to_string(i) + " is not a finite number ≥ 0");
  switch (order) {
    case 1:
      return SmoothImpl<1>(y, w, smoothing, joint);
    case 2:
      return SmoothImpl<2>(y, w, smoothing, joint);
    case 3:
      return SmoothImpl<3>(y, w, smoothing, joint);
    case 4:
      return SmoothImpl<4>(y, w, smoothing, joint);
    case 5:
      return SmoothImpl<5>(y, w, smoothing, joint);
    case 6:
      return SmoothImpl<6>(y, w, smoothing, joint);
    default:
      throw InvalidInput("penalised smooth: order " + std::to_string(order) + " must be in 1..6");
  }
}

// ---------------------------------------------------------------------------
// The filler.

SplineFiller::SplineFiller(const SplineFillOptions& options) : options_(options) {
  const std::string err = options_.Check();
  if (!err.empty()) throw InvalidInput(err);
}

bool SplineFiller::CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const {
  std::string why;
  if (options_.max_gap_frames > 0 && gap.length > options_.max_gap_frames)
    why = "gap of " + std::to_string(gap.length) + " frames longer than the spline's maximum of " +
          std::to_string(options_.max_gap_frames) + " frames";
  else
    why = CheckSides(in, gap, options_.side_frames);
  if (why_not != nullptr) *why_not = why;
  return why.empty();
}

bool SplineFiller::Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const {
  if (!CanFill(in, gap, nullptr)) return false;
  if (options_.kind == SplineKind::kSmoothing) return FillSmoothing(in, gap, out, record);
  return FillInterpolating(in, gap, out, record);
}

bool SplineFiller::FillInterpolating(const MarkerArray& in, const Gap& gap, MarkerArray* out,
                                     FillRecord* record) const {
  using Spline3 = Eigen::Spline<double, 3>;
  const int degree = options_.kind == SplineKind::kQuintic ? 5 : 3;
  const int k = options_.side_frames;
  const int n = 2 * k;
  Eigen::Array3Xd pts(3, n);
  Eigen::Array<double, 1, Eigen::Dynamic> u(n);
  // Frames gap.start − k … gap.start − 1 and gap.end() … gap.end() + k − 1,
  // parameterised by time mapped to [0, 1].
  const double t0 = static_cast<double>(gap.start - k);
  const double span = static_cast<double>(gap.end() + k - 1) - t0;
  for (int i = 0; i < n; ++i) {
    const int64_t f = i < k ? gap.start - k + i : gap.end() + (i - k);
    const float* p = in.at(f, gap.marker);
    pts.col(i) << p[0], p[1], p[2];
    u[i] = (static_cast<double>(f) - t0) / span;
  }
  const Eigen::Array3d centre = pts.rowwise().mean();
  pts.colwise() -= centre;
  const Spline3 spline = Eigen::SplineFitting<Spline3>::Interpolate(pts, degree, u);
  for (int64_t f = gap.start; f < gap.end(); ++f) {
    const Eigen::Array3d v = spline((static_cast<double>(f) - t0) / span) + centre;
    if (!v.allFinite()) return false;
    float* q = out->at(f, gap.marker);
    for (int c = 0; c < 3; ++c) q[c] = static_cast<float>(v[c]);
  }
  record->method = name();
  record->parameters = std::string("kind=") + SplineKindName(options_.kind) +
                       " interpolating, degree=" + std::to_string(degree) +
                       ", knots=knot averaging, frames=" + std::to_string(k) + "+" + std::to_string(k);
  return true;
}

bool SplineFiller::FillSmoothing(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const {
  const int64_t first = std::max<int64_t>(0, gap.start - options_.context_frames);
  const int64_t last = std::min<int64_t>(in.frames(), gap.end() + options_.context_frames);  // one past
  const int n = static_cast<int>(last - first);
  Eigen::MatrixXd y(n, 3);
  Eigen::VectorXd w(n);
  int64_t valid_before = 0, valid_after = 0;
  for (int i = 0; i < n; ++i) {
    const int64_t f = first + i;
    const bool ok = !SampleMissing(in, f, gap.marker);
    w[i] = ok ? 1.0 : 0.0;
    const float* p = in.at(f, gap.marker);
    for (int c = 0; c < 3; ++c) y(i, c) = ok ? p[c] : 0.0;
    if (ok && f < gap.start) ++valid_before;
    if (ok && f >= gap.end()) ++valid_after;
  }
  PenalisedFit fit;
  try {
    fit = PenalisedSmooth(y, w, options_.order, options_.smoothing, !options_.per_coordinate);
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
  std::snprintf(
      buf, sizeof buf,
      "kind=smoothing, order=%d (%s), p=%s%s[%.3g, %.3g, %.3g], dof=[%.1f, %.1f, %.1f], window=%lld+%lld frames "
      "(%lld+%lld valid)",
      options_.order,
      options_.order == 3   ? "quintic"
      : options_.order == 2 ? "cubic"
                            : "other",
      options_.smoothing > 0 ? "fixed" : "GCV", options_.per_coordinate ? "" : " joint", fit.p[0], fit.p[1], fit.p[2],
      fit.trace[0], fit.trace[1], fit.trace[2], static_cast<long long>(gap.start - first),
      static_cast<long long>(last - gap.end()), static_cast<long long>(valid_before),
      static_cast<long long>(valid_after));
  record->method = name();
  record->parameters = buf;
  return true;
}

}  // namespace csw::cleaning
