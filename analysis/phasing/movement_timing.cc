#include "analysis/phasing/movement_timing.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/error.h"

namespace csw::phasing {

namespace {

double MinJerk(double tau) {
  if (tau <= 0.0) return 0.0;
  if (tau >= 1.0) return 1.0;
  return tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau));
}

// Least-squares fit of superposed minimum-jerk gestures to the frames
// [first, end) of a trajectory, by variable projection.
class GestureFit {
 public:
  GestureFit(const SampledTrajectory& tr, int64_t first, int64_t end, int gestures, int path_terms)
      : k_(gestures), p_(path_terms), active_(static_cast<size_t>(gestures), true) {
    const Eigen::MatrixXd& s = *tr.samples;
    const int64_t n = end - first;
    t_.resize(n);
    for (int64_t f = 0; f < n; ++f) t_[f] = tr.Time(first + f);
    x_ = s.middleRows(first, n);
    finite_ = x_.array().isFinite();
    complete_ = finite_.all();
    count_ = finite_.count();
    x_ = finite_.select(x_, 0.0);
    // Dimensions sharing one pattern of missing frames (the three coordinates
    // of a marker, usually) share one normal matrix.
    if (!complete_) {
      for (Eigen::Index j = 0; j < x_.cols(); ++j) {
        auto same = std::find_if(groups_.begin(), groups_.end(), [&](const MaskGroup& g) {
          return (finite_.col(g.dims.front()) == finite_.col(j)).all();
        });
        if (same != groups_.end()) {
          same->dims.push_back(j);
          continue;
        }
        MaskGroup g;
        g.dims.push_back(j);
        for (Eigen::Index f = 0; f < x_.rows(); ++f)
          if (finite_(f, j)) g.rows.push_back(f);
        groups_.push_back(std::move(g));
      }
      for (MaskGroup& g : groups_) g.x = x_(g.rows, g.dims);
    }
  }

  int64_t count() const { return count_; }
  int dimensions() const { return static_cast<int>(x_.cols()); }
  int gestures() const { return k_; }
  int active_count() const { return static_cast<int>(std::count(active_.begin(), active_.end(), true)); }
  int columns() const { return 1 + active_count() * p_; }
  bool active(int k) const { return active_[static_cast<size_t>(k)]; }
  void SetActive(std::vector<bool> active) { active_ = std::move(active); }
  // First column of gesture k (-1 when inactive).
  int Column(int k) const {
    if (!active(k)) return -1;
    int c = 1;
    for (int j = 0; j < k; ++j)
      if (active(j)) c += p_;
    return c;
  }

  // Basis (frames × columns) for the gesture times theta = (onset_k, duration_k).
  Eigen::MatrixXd Basis(const Eigen::VectorXd& theta) const {
    Eigen::MatrixXd a(t_.size(), columns());
    a.col(0).setOnes();
    for (int k = 0; k < k_; ++k) {
      if (!active(k)) continue;
      const double onset = theta[2 * k], duration = theta[2 * k + 1];
      const int col = Column(k);
      for (Eigen::Index f = 0; f < t_.size(); ++f) {
        const double v = MinJerk((t_[f] - onset) / duration);
        double pw = v;
        for (int p = 0; p < p_; ++p) {
          a(f, col + p) = pw;
          pw *= v;
        }
      }
    }
    return a;
  }

  // Linear coefficients (columns × dimensions) and the residual (finite samples only).
  Eigen::MatrixXd Solve(const Eigen::VectorXd& theta, Eigen::VectorXd* residual) const {
    const Eigen::MatrixXd a = Basis(theta);
    const Eigen::Index c = a.cols(), d = x_.cols();
    const double ridge = 1e-9 * static_cast<double>(t_.size());
    Eigen::MatrixXd beta(c, d);
    // The matrices are small (about a hundred frames by a few columns):
    // coefficient-based products (lazyProduct) skip the packing and the
    // scratch buffers of Eigen's blocked GEMM, which dominated this function.
    if (complete_) {
      Eigen::MatrixXd g = a.transpose().lazyProduct(a);
      g.diagonal().array() += ridge;
      const Eigen::MatrixXd atx = a.transpose().lazyProduct(x_);
      beta = g.ldlt().solve(atx);
    } else {
      for (const MaskGroup& group : groups_) {
        const Eigen::MatrixXd ag = a(group.rows, Eigen::all);
        Eigen::MatrixXd g = ag.transpose().lazyProduct(ag);
        g.diagonal().array() += ridge;
        const Eigen::MatrixXd atx = ag.transpose().lazyProduct(group.x);
        const Eigen::MatrixXd b = g.ldlt().solve(atx);
        for (size_t i = 0; i < group.dims.size(); ++i) beta.col(group.dims[i]) = b.col(static_cast<Eigen::Index>(i));
      }
    }
    if (residual) {
      const Eigen::MatrixXd r = x_ - a.lazyProduct(beta);
      residual->resize(count_);
      Eigen::Index i = 0;
      for (Eigen::Index j = 0; j < d; ++j)
        for (Eigen::Index f = 0; f < r.rows(); ++f)
          if (finite_(f, j)) (*residual)[i++] = r(f, j);
    }
    return beta;
  }

  double Cost(const Eigen::VectorXd& theta) const {
    Eigen::VectorXd r;
    Solve(theta, &r);
    return r.squaredNorm();
  }

  // Change of every dimension over gesture k (sum of its path coefficients).
  Eigen::VectorXd Change(const Eigen::MatrixXd& beta, int k) const {
    if (!active(k)) return Eigen::VectorXd::Zero(beta.cols());
    return beta.middleRows(Column(k), p_).colwise().sum().transpose();
  }

 private:
  int k_, p_;
  std::vector<bool> active_;
  Eigen::VectorXd t_;
  Eigen::MatrixXd x_;
  Eigen::Array<bool, Eigen::Dynamic, Eigen::Dynamic> finite_;
  bool complete_ = true;
  int64_t count_ = 0;
  struct MaskGroup {
    std::vector<Eigen::Index> dims, rows;  // dimensions with one finite pattern, and its finite frames
    Eigen::MatrixXd x;                     // the samples of those dimensions at those frames
  };
  std::vector<MaskGroup> groups_;
};

// Box bounds on (onset_k, duration_k), and order: the onsets and the targets of
// successive active gestures at least `gap` apart (so that two gestures cannot
// trade places or share one movement).
struct Bounds {
  Eigen::VectorXd lo, hi;
  double gap = 0.02;
  std::vector<bool> active;
  std::vector<double> min_target, max_target;  // range of each gesture's target
  Eigen::VectorXd Clamp(const Eigen::VectorXd& v) const {
    Eigen::VectorXd x = v.cwiseMax(lo).cwiseMin(hi);
    int prev = -1;
    for (int k = 0; 2 * k < x.size(); ++k) {
      if (!active[static_cast<size_t>(k)]) continue;
      const auto ku = static_cast<size_t>(k);
      // An onset from which no allowed duration reaches the target's range
      // moves towards it (else the target would leave its range).
      x[2 * k] = std::clamp(x[2 * k], std::min(min_target[ku] - hi[2 * k + 1], max_target[ku] - lo[2 * k + 1]),
                            max_target[ku] - lo[2 * k + 1]);
      x[2 * k + 1] = std::min(x[2 * k + 1], max_target[ku] - x[2 * k]);
      x[2 * k + 1] = std::max(x[2 * k + 1], min_target[ku] - x[2 * k]);
      x[2 * k + 1] = std::clamp(x[2 * k + 1], lo[2 * k + 1], hi[2 * k + 1]);
      if (prev >= 0) {
        x[2 * k] = std::max(x[2 * k], x[2 * prev] + gap);
        const double prev_target = x[2 * prev] + x[2 * prev + 1];
        x[2 * k + 1] = std::max(x[2 * k + 1], prev_target + gap - x[2 * k]);
        x[2 * k + 1] = std::min(x[2 * k + 1], hi[2 * k + 1]);
      }
      prev = k;
    }
    return x;
  }
};

// Levenberg-Marquardt on the variable-projection cost, numerical Jacobian.
bool Minimise(const GestureFit& fit, const Bounds& bounds, int max_iterations, Eigen::VectorXd* theta) {
  Eigen::VectorXd th = bounds.Clamp(*theta);
  Eigen::VectorXd r;
  fit.Solve(th, &r);
  double cost = r.squaredNorm();
  double lambda = 1e-3;
  const double h = 1e-4;
  const Eigen::Index n = th.size();
  for (int it = 0; it < max_iterations; ++it) {
    Eigen::MatrixXd jac(r.size(), n);
    for (Eigen::Index i = 0; i < n; ++i) {  // forward differences
      Eigen::VectorXd a = th;
      a[i] += h;
      Eigen::VectorXd ra;
      fit.Solve(a, &ra);
      jac.col(i) = (ra - r) / h;
    }
    const Eigen::MatrixXd hess = jac.transpose() * jac;
    const Eigen::VectorXd grad = jac.transpose() * r;
    bool accepted = false;
    Eigen::VectorXd next;
    while (lambda < 1e12) {
      Eigen::MatrixXd m = hess;
      m.diagonal().array() += lambda * hess.diagonal().array() + 1e-12;
      next = bounds.Clamp(th - m.ldlt().solve(grad));
      Eigen::VectorXd rn;
      fit.Solve(next, &rn);
      const double c = rn.squaredNorm();
      if (std::isfinite(c) && c <= cost) {
        accepted = true;
        const double step = (next - th).cwiseAbs().maxCoeff();
        th = next;
        r = rn;
        const double drop = cost - c;
        cost = c;
        lambda = std::max(lambda / 3.0, 1e-9);
        if (step < 1e-6 || drop <= 1e-12 * std::max(cost, 1e-30)) {
          *theta = th;
          return true;
        }
        break;
      }
      lambda *= 4.0;
    }
    if (!accepted) {
      *theta = th;
      return true;  // no descent direction left: at a minimum (or a bound)
    }
  }
  *theta = th;
  return false;
}

// Smoothed speed (norm over the dimensions finite at both neighbours) per frame
// of [first, end); NaN where unknown.
Eigen::VectorXd Speeds(const SampledTrajectory& tr, int64_t first, int64_t end) {
  const Eigen::MatrixXd& s = *tr.samples;
  const int64_t n = std::max<int64_t>(0, end - first);
  Eigen::VectorXd v = Eigen::VectorXd::Constant(n, std::numeric_limits<double>::quiet_NaN());
  for (int64_t i = 0; i < n; ++i) {
    const int64_t f = first + i;
    if (f < 1 || f + 1 >= s.rows()) continue;
    double sum = 0.0;
    int used = 0;
    for (Eigen::Index d = 0; d < s.cols(); ++d) {
      const double a = s(f - 1, d), b = s(f + 1, d);
      if (std::isfinite(a) && std::isfinite(b)) {
        sum += (b - a) * (b - a);
        ++used;
      }
    }
    if (used > 0) v[i] = std::sqrt(sum) * tr.rate_hz / 2.0;
  }
  // Moving average over 5 frames (finite values only).
  Eigen::VectorXd out = v;
  for (int64_t i = 0; i < n; ++i) {
    double sum = 0.0;
    int used = 0;
    for (int64_t j = std::max<int64_t>(0, i - 2); j <= std::min(n - 1, i + 2); ++j)
      if (std::isfinite(v[j])) {
        sum += v[j];
        ++used;
      }
    out[i] = used > 0 ? sum / used : std::numeric_limits<double>::quiet_NaN();
  }
  return out;
}

int64_t FrameAtOrAfter(const SampledTrajectory& tr, double t) {
  return std::clamp<int64_t>(static_cast<int64_t>(std::ceil((t - tr.start_s) * tr.rate_hz - 1e-9)), 0, tr.frames());
}

// Mean of the finite samples of the frames [first, end), per dimension (NaN when none).
Eigen::VectorXd MeanRows(const Eigen::MatrixXd& s, int64_t first, int64_t end) {
  Eigen::VectorXd m = Eigen::VectorXd::Zero(s.cols());
  for (Eigen::Index d = 0; d < s.cols(); ++d) {
    int used = 0;
    for (int64_t f = std::max<int64_t>(0, first); f < std::min<int64_t>(end, s.rows()); ++f)
      if (std::isfinite(s(f, d))) {
        m[d] += s(f, d);
        ++used;
      }
    m[d] = used > 0 ? m[d] / used : std::numeric_limits<double>::quiet_NaN();
  }
  return m;
}

// First guess (onset, duration) of a gesture whose speed peak lies in [from_s, to_s].
void GuessGesture(const SampledTrajectory& tr, double from_s, double to_s, const MovementFitOptions& o, double* onset,
                  double* duration) {
  const int64_t a = FrameAtOrAfter(tr, from_s), b = FrameAtOrAfter(tr, to_s);
  double fallback = std::clamp(0.8 * (to_s - from_s), o.min_duration_s, o.max_duration_s);
  *duration = fallback;
  *onset = to_s - fallback;
  if (b - a < 3) return;
  const Eigen::VectorXd v = Speeds(tr, a, b);
  Eigen::Index peak = -1;
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (std::isfinite(v[i]) && (peak < 0 || v[i] > v[peak])) peak = i;
  if (peak < 0 || !(v[peak] > 0.0)) return;
  const Eigen::VectorXd d = MeanRows(*tr.samples, b - 3, b) - MeanRows(*tr.samples, a, a + 3);
  double amplitude = 0.0;
  for (Eigen::Index i = 0; i < d.size(); ++i)
    if (std::isfinite(d[i])) amplitude += d[i] * d[i];
  amplitude = std::sqrt(amplitude);
  const double t_peak = tr.Time(a + peak);
  double dur = amplitude > 0.0 ? 1.875 * amplitude / v[peak] : fallback;
  dur = std::clamp(dur, o.min_duration_s, o.max_duration_s);
  *duration = dur;
  *onset = t_peak - dur / 2.0;
}

void CheckTrajectory(const SampledTrajectory& tr) {
  if (tr.samples == nullptr) throw InvalidInput("movement timing: no trajectory");
  if (!(tr.rate_hz > 0.0)) throw InvalidInput("movement timing: rate_hz must be > 0");
}

}  // namespace

std::string MovementFitOptions::Check() const {
  if (path_terms < 1 || path_terms > 3) return "path_terms must be 1, 2 or 3";
  if (!(min_duration_s > 0.0 && max_duration_s > min_duration_s)) return "need 0 < min_duration_s < max_duration_s";
  if (!(max_shift_s > 0.0)) return "max_shift_s must be > 0";
  if (!(min_amplitude >= 0.0)) return "min_amplitude must be >= 0";
  if (!(lookback_s > 0.0)) return "lookback_s must be > 0";
  if (!(target_tolerance_s > 0.0)) return "target_tolerance_s must be > 0";
  if (refinement_passes < 0 || refinement_passes > 10) return "refinement_passes must be in [0, 10]";
  if (!(lookahead_fraction > 0.0 && lookahead_fraction <= 1.0)) return "lookahead_fraction must be in (0, 1]";
  if (!(onset_window_s >= 0.0)) return "onset_window_s must be >= 0";
  if (!(max_time_sd_s > 0.0)) return "max_time_sd_s must be > 0";
  if (!(time_sd_reference_rate_hz >= 0.0 && std::isfinite(time_sd_reference_rate_hz)))
    return "time_sd_reference_rate_hz must be a finite number >= 0";
  if (max_iterations < 1) return "max_iterations must be >= 1";
  return "";
}

namespace {

// A window of the sequence: the rough targets of the gestures fitted together
// (in order; `central` is the movement measured), the data stretch, and what an
// earlier pass measured of the other gestures.
struct Window {
  std::vector<double> rough;  // rough target of each gesture in the window
  int central = 1;
  double data_start = 0.0, data_end = 0.0;
  // Per gesture: estimate of an earlier pass (known), and whether it moved.
  std::vector<bool> known, moved;
  std::vector<double> onset, target;
};

MovementEstimate FitWindow(const SampledTrajectory& tr, const Window& w, const MovementFitOptions& o) {
  MovementEstimate e;
  const int kg = static_cast<int>(w.rough.size());
  const int c = w.central;
  const int64_t first = FrameAtOrAfter(tr, w.data_start);
  const int64_t end = std::min(tr.frames(), FrameAtOrAfter(tr, w.data_end) + 1);
  if (end - first < 12) {
    e.reason = "too few frames in the window";
    return e;
  }
  GestureFit fit(tr, first, end, kg, o.path_terms);
  if (fit.count() < 4 * fit.columns()) {
    e.reason = "too few finite samples in the window";
    return e;
  }
  e.samples = fit.count();
  const double tol = o.target_tolerance_s;
  Bounds bounds{Eigen::VectorXd(2 * kg),
                Eigen::VectorXd(2 * kg),
                0.5 * o.min_duration_s,
                std::vector<bool>(static_cast<size_t>(kg), true),
                std::vector<double>(static_cast<size_t>(kg)),
                std::vector<double>(static_cast<size_t>(kg))};
  Eigen::VectorXd theta(2 * kg);
  for (int k = 0; k < kg; ++k) {
    const auto ku = static_cast<size_t>(k);
    // Each gesture reaches its target within target_tolerance_s of its rough
    // target and between the middles of the stretches around it.
    bounds.min_target[ku] =
        k == 0 ? w.rough[ku] - tol : std::max(0.5 * (w.rough[ku - 1] + w.rough[ku]), w.rough[ku] - tol);
    bounds.max_target[ku] =
        k + 1 == kg ? w.rough[ku] + tol : std::min(0.5 * (w.rough[ku] + w.rough[ku + 1]), w.rough[ku] + tol);
    // First guess: the gesture's speed peak in its own stretch.
    const double from = k == 0 ? w.data_start : w.rough[ku - 1];
    const double to = k + 1 == kg ? w.data_end : w.rough[ku];
    double onset, duration;
    GuessGesture(tr, from, to, o, &onset, &duration);
    theta[2 * k] = onset;
    theta[2 * k + 1] = duration;
    bounds.lo[2 * k] = std::min(onset, from) - o.max_shift_s;
    bounds.hi[2 * k] = std::max(onset, from) + o.max_shift_s;
    bounds.lo[2 * k + 1] = o.min_duration_s;
    bounds.hi[2 * k + 1] = o.max_duration_s;
  }
  // Gestures measured by an earlier pass: start there, move little.
  std::vector<bool> allowed(static_cast<size_t>(kg), true);
  for (int k = 0; k < kg; ++k) {
    const auto ku = static_cast<size_t>(k);
    if (k == c || ku >= w.known.size() || !w.known[ku]) continue;
    if (!w.moved[ku]) {
      allowed[ku] = false;
      continue;
    }
    constexpr double kNear = 0.03;
    theta[2 * k] = w.onset[ku];
    theta[2 * k + 1] = std::clamp(w.target[ku] - w.onset[ku], o.min_duration_s, o.max_duration_s);
    bounds.lo[2 * k] = w.onset[ku] - kNear;
    bounds.hi[2 * k] = w.onset[ku] + kNear;
    bounds.min_target[ku] = w.target[ku] - kNear;
    bounds.max_target[ku] = w.target[ku] + kNear;
  }
  fit.SetActive(allowed);
  bounds.active = allowed;
  // Two starts for this movement: its speed peak, and the rough times.
  Eigen::VectorXd alt = theta;
  const auto cu = static_cast<size_t>(c);
  alt[2 * c] = w.rough[cu - 1];
  alt[2 * c + 1] = std::clamp(w.rough[cu] - w.rough[cu - 1], o.min_duration_s, o.max_duration_s);
  e.converged = Minimise(fit, bounds, o.max_iterations, &theta);
  if (Minimise(fit, bounds, o.max_iterations, &alt) && fit.Cost(alt) < fit.Cost(theta)) theta = alt;
  // Model choice (BIC): keep a neighbouring gesture only when it explains the
  // data (a still neighbour would otherwise borrow part of this movement).
  // Backward elimination: drop the neighbour whose removal lowers BIC most,
  // while one does.
  const auto bic = [&](const GestureFit& f, const Eigen::VectorXd& th) {
    const double n = static_cast<double>(f.count());
    const double params = 2.0 * f.active_count() + f.dimensions() * static_cast<double>(f.columns());
    return n * std::log(std::max(f.Cost(th), 1e-300) / n) + params * std::log(n);
  };
  double best = bic(fit, theta);
  std::vector<bool> best_active = allowed;
  for (bool improved = true; improved;) {
    improved = false;
    std::vector<bool> round_active = best_active;
    Eigen::VectorXd round_theta = theta;
    double round_best = best;
    bool round_ok = e.converged;
    for (int k = 0; k < kg; ++k) {
      if (k == c || !best_active[static_cast<size_t>(k)]) continue;
      std::vector<bool> active = best_active;
      active[static_cast<size_t>(k)] = false;
      GestureFit reduced = fit;
      reduced.SetActive(active);
      Bounds b = bounds;
      b.active = active;
      Eigen::VectorXd th = theta;
      const bool ok = Minimise(reduced, b, o.max_iterations, &th);
      const double v = bic(reduced, th);
      if (v < round_best) {
        round_best = v;
        round_active = active;
        round_theta = th;
        round_ok = ok;
      }
    }
    if (round_best < best) {
      best = round_best;
      best_active = round_active;
      theta = round_theta;
      e.converged = round_ok;
      improved = true;
    }
  }
  fit.SetActive(best_active);
  Eigen::VectorXd r;
  const Eigen::MatrixXd beta = fit.Solve(theta, &r);
  e.fitted = true;
  e.onset_s = theta[2 * c];
  e.target_s = theta[2 * c] + theta[2 * c + 1];
  e.amplitude = fit.Change(beta, c).norm();
  e.rms_residual = std::sqrt(r.squaredNorm() / std::max<double>(1.0, static_cast<double>(r.size())));
  e.moved = e.amplitude >= o.min_amplitude;
  if (!e.moved) e.reason = "no change";
  // Standard errors of this movement's onset and target: the Gauss-Newton
  // covariance of the active times (linear coefficients profiled out),
  // sigma^2 (J^T J)^-1 with sigma^2 = residual / (n - parameters).
  {
    std::vector<int> params;
    for (int k = 0; k < kg; ++k)
      if (best_active[static_cast<size_t>(k)]) {
        params.push_back(2 * k);
        params.push_back(2 * k + 1);
      }
    const double h = 1e-4;
    Eigen::MatrixXd jac(r.size(), static_cast<Eigen::Index>(params.size()));
    for (size_t q = 0; q < params.size(); ++q) {
      Eigen::VectorXd a = theta;
      a[params[q]] += h;
      Eigen::VectorXd ra;
      fit.Solve(a, &ra);
      jac.col(static_cast<Eigen::Index>(q)) = (ra - r) / h;
    }
    const double dof = static_cast<double>(r.size()) - static_cast<double>(params.size()) -
                       static_cast<double>(fit.dimensions() * fit.columns());
    const double sigma2 = r.squaredNorm() / std::max(1.0, dof);
    Eigen::MatrixXd info = jac.transpose() * jac;
    info.diagonal().array() += 1e-12 * std::max(1.0, info.diagonal().maxCoeff());
    const Eigen::MatrixXd cov = sigma2 * info.ldlt().solve(Eigen::MatrixXd::Identity(info.rows(), info.cols()));
    int qc = 0;
    for (size_t q = 0; q < params.size(); ++q)
      if (params[q] == 2 * c) qc = static_cast<int>(q);
    // target = onset + duration
    e.onset_sd_s = std::sqrt(std::max(0.0, cov(qc, qc)));
    e.target_sd_s = std::sqrt(std::max(0.0, cov(qc, qc) + cov(qc + 1, qc + 1) + 2.0 * cov(qc, qc + 1)));
  }
  const double gate = EffectiveTimeSdLimit(o, tr.rate_hz);
  if (e.moved && !(e.onset_sd_s <= gate && e.target_sd_s <= gate)) {
    e.determined = false;
    e.reason = "undetermined";
  }
  return e;
}

void CheckTimes(const MovementFitOptions& o) {
  if (std::string why = o.Check(); !why.empty()) throw InvalidInput("movement timing options: " + why);
}

// The window of movement i of a sequence of rough targets: the gestures from
// the one into target i-1 (or an earlier one, so that the data reach back
// onset_window_s before target i) to the next movement; the last movement has
// none (no movement follows: a made-up next gesture took the slow tail of the
// return to rest, docs/analysis.md), its data running as far past the target
// as a next target one interval later would have given.
Window SequenceWindow(const std::vector<double>& targets, size_t i, const MovementFitOptions& o) {
  Window w;
  size_t j0 = i - 1;
  while (j0 > 0 && targets[j0] > targets[i] - o.onset_window_s) --j0;
  for (size_t j = j0; j <= i; ++j) w.rough.push_back(targets[j]);
  const bool last = i + 1 >= targets.size();
  const double next_target = last ? targets[i] + (targets[i] - targets[i - 1]) : targets[i + 1];
  if (!last) w.rough.push_back(next_target);
  w.central = static_cast<int>(i - j0);
  w.data_start = targets[j0] - o.lookback_s;
  w.data_end = targets[i] + o.lookahead_fraction * (next_target - targets[i]);
  return w;
}

}  // namespace

MovementEstimate EstimateMovementAmong(const SampledTrajectory& tr, const std::vector<double>& rough_targets_s,
                                       size_t central, double data_start_s, double data_end_s,
                                       const MovementFitOptions& o) {
  CheckTrajectory(tr);
  CheckTimes(o);
  if (rough_targets_s.size() < 2 || central < 1 || central >= rough_targets_s.size())
    throw InvalidInput("movement timing: the measured gesture needs a gesture before it");
  for (size_t i = 1; i < rough_targets_s.size(); ++i)
    if (!(rough_targets_s[i] > rough_targets_s[i - 1]))
      throw InvalidInput("movement timing: the target times must increase");
  if (!(data_start_s < data_end_s)) throw InvalidInput("movement timing: the data window is empty");
  Window w;
  w.rough = rough_targets_s;
  w.central = static_cast<int>(central);
  w.data_start = data_start_s;
  w.data_end = data_end_s;
  return FitWindow(tr, w, o);
}

MovementEstimate EstimateMovement(const SampledTrajectory& tr, double previous_target_s, double target_s,
                                  double next_target_s, const MovementFitOptions& o) {
  if (!(previous_target_s < target_s && target_s < next_target_s))
    throw InvalidInput("movement timing: the target times must increase (previous < target < next)");
  return EstimateMovementAmong(tr, {previous_target_s, target_s, next_target_s}, 1, previous_target_s - o.lookback_s,
                               target_s + o.lookahead_fraction * (next_target_s - target_s), o);
}

std::vector<MovementEstimate> EstimateMovements(const SampledTrajectory& tr, const std::vector<double>& targets,
                                                const MovementFitOptions& o) {
  CheckTrajectory(tr);
  CheckTimes(o);
  for (size_t i = 1; i < targets.size(); ++i)
    if (!(targets[i] > targets[i - 1])) throw InvalidInput("movement timing: the target times must increase");
  std::vector<MovementEstimate> out(targets.size());
  if (!out.empty()) out[0].reason = "first target";
  for (size_t i = 1; i < targets.size(); ++i) out[i] = FitWindow(tr, SequenceWindow(targets, i, o), o);
  // Further passes: each movement again, the other gestures of its window
  // started from (and kept near) their own estimates of the previous pass,
  // where each was the central movement of its window (block coordinate
  // descent on the whole sequence).
  for (int pass = 0; pass < o.refinement_passes; ++pass) {
    std::vector<MovementEstimate> refined = out;
    for (size_t i = 1; i < targets.size(); ++i) {
      Window w = SequenceWindow(targets, i, o);
      const size_t j0 = i - static_cast<size_t>(w.central);
      const size_t kg = w.rough.size();
      w.known.assign(kg, false);
      w.moved.assign(kg, true);
      w.onset.assign(kg, 0.0);
      w.target.assign(kg, 0.0);
      for (size_t k = 0; k < kg; ++k) {
        const size_t j = j0 + k;
        if (j == i || j < 1 || j >= out.size() || !out[j].fitted) continue;
        w.known[k] = true;
        w.moved[k] = out[j].moved;
        w.onset[k] = out[j].onset_s;
        w.target[k] = out[j].target_s;
      }
      refined[i] = FitWindow(tr, w, o);
    }
    out = refined;
  }
  return out;
}

double EffectiveTimeSdLimit(const MovementFitOptions& o, double rate_hz) {
  const double ref = o.time_sd_reference_rate_hz;
  return ref > 0.0 && rate_hz > ref ? o.max_time_sd_s * std::sqrt(ref / rate_hz) : o.max_time_sd_s;
}

MovementEstimate ThresholdMovement(const SampledTrajectory& tr, double from_s, double to_s, double fraction) {
  CheckTrajectory(tr);
  MovementEstimate e;
  const int64_t a = FrameAtOrAfter(tr, from_s), b = FrameAtOrAfter(tr, to_s);
  const Eigen::VectorXd v = Speeds(tr, a, b);
  Eigen::Index peak = -1;
  for (Eigen::Index i = 0; i < v.size(); ++i)
    if (std::isfinite(v[i]) && (peak < 0 || v[i] > v[peak])) peak = i;
  if (peak < 0) {
    e.reason = "no finite speed in the window";
    return e;
  }
  const double level = fraction * v[peak];
  Eigen::Index on = peak, off = peak;
  while (on > 0 && std::isfinite(v[on - 1]) && v[on - 1] > level) --on;
  while (off + 1 < v.size() && std::isfinite(v[off + 1]) && v[off + 1] > level) ++off;
  e.fitted = e.moved = true;
  e.onset_s = tr.Time(a + on);
  e.target_s = tr.Time(a + off);
  return e;
}

}  // namespace csw::phasing
