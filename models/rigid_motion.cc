#include "models/rigid_motion.h"

#include <ceres/tiny_solver.h>
#include <ceres/tiny_solver_autodiff_function.h>

#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "core/error.h"
#include "models/so3.h"

namespace csw {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

bool ColumnFinite(const Eigen::Matrix3Xd& m, Eigen::Index c) { return m.col(c).allFinite(); }

// Least-squares rotation and translation with observed ~ R ref + t over the
// given columns. Returns false if the reference points are (nearly) collinear.
bool Kabsch(const Eigen::Matrix3Xd& ref, const Eigen::Matrix3Xd& obs, const std::vector<int>& cols,
            RigidTransform* out) {
  if (cols.size() < 3) return false;
  Eigen::Vector3d ref_mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d obs_mean = Eigen::Vector3d::Zero();
  for (int c : cols) {
    ref_mean += ref.col(c);
    obs_mean += obs.col(c);
  }
  ref_mean /= static_cast<double>(cols.size());
  obs_mean /= static_cast<double>(cols.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d ref_scatter = Eigen::Matrix3d::Zero();
  for (int c : cols) {
    const Eigen::Vector3d a = ref.col(c) - ref_mean;
    cov += (obs.col(c) - obs_mean) * a.transpose();
    ref_scatter += a * a.transpose();
  }
  // Overflowing coordinates (hostile input) give no fit rather than NaN poses.
  if (!cov.allFinite() || !ref_scatter.allFinite()) return false;
  // Rotation is determined only if the reference spans at least a plane.
  Eigen::JacobiSVD<Eigen::Matrix3d> scatter_svd(ref_scatter);
  const Eigen::Vector3d sv = scatter_svd.singularValues();
  if (!(sv(0) > 0.0) || sv(1) < 1e-10 * sv(0)) return false;

  Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d d = Eigen::Matrix3d::Identity();
  if ((svd.matrixU() * svd.matrixV().transpose()).determinant() < 0.0) d(2, 2) = -1.0;  // no reflection
  out->rotation = svd.matrixU() * d * svd.matrixV().transpose();
  out->translation = obs_mean - out->rotation * ref_mean;
  return out->rotation.allFinite() && out->translation.allFinite();
}

void FillResiduals(const Eigen::Matrix3Xd& ref, const Eigen::Matrix3Xd& obs, RigidFit* fit) {
  fit->per_marker_residual_mm = Eigen::VectorXd::Constant(ref.cols(), kNaN);
  double sum = 0.0;
  for (int c : fit->used_markers) {
    const double r = (fit->transform.Apply(ref.col(c)) - obs.col(c)).norm();
    fit->per_marker_residual_mm(c) = r;
    sum += r * r;
  }
  fit->rms_mm = fit->used_markers.empty() ? kNaN : std::sqrt(sum / static_cast<double>(fit->used_markers.size()));
}

std::vector<int> UsableColumns(const Eigen::Matrix3Xd& reference, const Eigen::Matrix3Xd& observed) {
  if (reference.cols() != observed.cols()) {
    throw InvalidInput("rigid fit: reference has " + std::to_string(reference.cols()) + " markers, observation has " +
                       std::to_string(observed.cols()));
  }
  std::vector<int> cols;
  for (Eigen::Index c = 0; c < reference.cols(); ++c) {
    if (ColumnFinite(reference, c) && ColumnFinite(observed, c)) cols.push_back(static_cast<int>(c));
  }
  return cols;
}

// q = R(aa) p by Rodrigues' formula, for doubles and Jets (ceres/rotation.h has
// the same function but, without NDEBUG, glog DCHECKs that need the glog library,
// which csw does not link). Near aa = 0 the first-order form q = p + aa × p has
// the exact value and derivative at 0.
template <typename T>
void AngleAxisRotatePoint(const T* aa, const T* p, T* q) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const T theta2 = aa[0] * aa[0] + aa[1] * aa[1] + aa[2] * aa[2];
  const T cross[3] = {aa[1] * p[2] - aa[2] * p[1], aa[2] * p[0] - aa[0] * p[2], aa[0] * p[1] - aa[1] * p[0]};
  if (theta2 > T(std::numeric_limits<double>::epsilon())) {
    const T theta = sqrt(theta2);
    const T c = cos(theta), s = sin(theta) / theta;
    const T k = (aa[0] * p[0] + aa[1] * p[1] + aa[2] * p[2]) * (T(1.0) - c) / theta2;
    for (int i = 0; i < 3; ++i) q[i] = p[i] * c + cross[i] * s + aa[i] * k;
  } else {
    for (int i = 0; i < 3; ++i) q[i] = p[i] + cross[i];
  }
}

// Robust rigid refinement as a plain least-squares problem for
// ceres::TinySolver (header-only: the csw binary does not link the Ceres
// library): marker c contributes the 3-vector sqrt(rho(s)/s) r_c, with r_c =
// R(aa) ref_c + t - obs_c and s = |r_c|^2, whose squared norm is the robust
// cost rho(s). Its minimum is the robust M-estimate that Ceres' HuberLoss and
// CauchyLoss define (same rho); only the Gauss-Newton model differs.
struct RobustMarkerResiduals {
  const Eigen::Matrix3Xd* ref = nullptr;
  const Eigen::Matrix3Xd* obs = nullptr;
  const std::vector<int>* cols = nullptr;
  RobustLoss loss = RobustLoss::kNone;
  double a = 1.0;  // loss scale (mm)
  int NumResiduals() const { return 3 * static_cast<int>(cols->size()); }

  template <typename T>
  T Scale(const T& s) const {
    using std::log1p;
    using std::sqrt;
    const double a2 = a * a;
    if (loss == RobustLoss::kHuber) {
      if (s <= T(a2)) return T(1.0);
      return sqrt((T(2.0 * a) * sqrt(s) - T(a2)) / s);
    }
    if (loss == RobustLoss::kCauchy) {
      if (s < T(1e-12 * a2)) return T(1.0) - s / T(4.0 * a2);  // series of sqrt(log1p(x)/x)
      return sqrt(T(a2) * log1p(s / T(a2)) / s);
    }
    return T(1.0);
  }

  template <typename T>
  bool operator()(const T* pose, T* residual) const {
    for (size_t i = 0; i < cols->size(); ++i) {
      const int c = (*cols)[i];
      const T p[3] = {T((*ref)(0, c)), T((*ref)(1, c)), T((*ref)(2, c))};
      T q[3];
      AngleAxisRotatePoint(pose, p, q);
      T r[3];
      for (int k = 0; k < 3; ++k) r[k] = q[k] + pose[3 + k] - T((*obs)(k, c));
      const T w = Scale(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
      for (int k = 0; k < 3; ++k) residual[3 * i + k] = w * r[k];
    }
    return true;
  }
};

double RobustCost(double squared, const RigidOptions& options) {
  const double a2 = options.loss_scale_mm * options.loss_scale_mm;
  switch (options.loss) {
    case RobustLoss::kNone:
      return squared;
    case RobustLoss::kHuber:
      return squared <= a2 ? squared : 2.0 * options.loss_scale_mm * std::sqrt(squared) - a2;
    case RobustLoss::kCauchy:
      return a2 * std::log1p(squared / a2);
  }
  return squared;
}

double TotalRobustCost(const Eigen::Matrix3Xd& ref, const Eigen::Matrix3Xd& obs, const std::vector<int>& cols,
                       const RigidTransform& t, const RigidOptions& options) {
  double cost = 0.0;
  for (int c : cols) cost += RobustCost((t.Apply(ref.col(c)) - obs.col(c)).squaredNorm(), options);
  return cost;
}

}  // namespace

RigidTransform RigidTransform::Inverse() const {
  RigidTransform inv;
  inv.rotation = rotation.transpose();
  inv.translation = -(inv.rotation * translation);
  return inv;
}

Eigen::Matrix<double, 6, 1> RigidTransform::Parameters() const {
  Eigen::Matrix<double, 6, 1> p;
  p << so3::Log(rotation), translation;
  return p;
}

RigidTransform RigidTransform::FromParameters(const Eigen::Matrix<double, 6, 1>& p) {
  RigidTransform t;
  t.rotation = so3::Exp(p.head<3>());
  t.translation = p.tail<3>();
  return t;
}

RigidFit EstimateRigidKabsch(const Eigen::Matrix3Xd& reference, const Eigen::Matrix3Xd& observed) {
  RigidFit fit;
  fit.used_markers = UsableColumns(reference, observed);
  fit.valid = Kabsch(reference, observed, fit.used_markers, &fit.transform);
  fit.converged = fit.valid;
  if (!fit.valid) fit.transform = RigidTransform{};
  FillResiduals(reference, observed, &fit);
  if (!fit.valid) fit.rms_mm = kNaN;
  return fit;
}

RigidFit EstimateRigid(const Eigen::Matrix3Xd& reference, const Eigen::Matrix3Xd& observed,
                       const RigidOptions& options) {
  if (options.loss != RobustLoss::kNone && !(options.loss_scale_mm > 0.0)) {
    throw InvalidInput("rigid fit: loss_scale_mm must be positive");
  }
  RigidFit fit = EstimateRigidKabsch(reference, observed);
  if (!fit.valid || options.loss == RobustLoss::kNone) return fit;

  // Start: the full Kabsch fit, or a leave-one-out fit if that has a lower
  // robust cost (a single gross outlier drags the full fit).
  RigidTransform start = fit.transform;
  double best = TotalRobustCost(reference, observed, fit.used_markers, start, options);
  if (fit.used_markers.size() >= 4) {
    for (size_t skip = 0; skip < fit.used_markers.size(); ++skip) {
      std::vector<int> cols;
      for (size_t i = 0; i < fit.used_markers.size(); ++i) {
        if (i != skip) cols.push_back(fit.used_markers[i]);
      }
      RigidTransform t;
      if (!Kabsch(reference, observed, cols, &t)) continue;
      const double cost = TotalRobustCost(reference, observed, fit.used_markers, t, options);
      if (cost < best) {
        best = cost;
        start = t;
      }
    }
  }

  Eigen::Matrix<double, 6, 1> pose = start.Parameters();
  RobustMarkerResiduals residuals;
  residuals.ref = &reference;
  residuals.obs = &observed;
  residuals.cols = &fit.used_markers;
  residuals.loss = options.loss;
  residuals.a = options.loss_scale_mm;
  using Function = ceres::TinySolverAutoDiffFunction<RobustMarkerResiduals, Eigen::Dynamic, 6>;
  const Function function(residuals);
  ceres::TinySolver<Function> solver;
  solver.options.max_num_iterations = std::max(1, options.max_iterations) + 1;  // the start counts as one
  solver.options.function_tolerance = 1e-14;
  solver.options.gradient_tolerance = 1e-16;
  solver.options.parameter_tolerance = 1e-14;
  solver.Solve(function, &pose);
  fit.converged = solver.summary.status != ceres::TinySolver<Function>::HIT_MAX_ITERATIONS;
  if (pose.allFinite()) {
    const RigidTransform refined = RigidTransform::FromParameters(pose);
    // Keep the better of start and refined (Ceres never worsens, but guard NaN).
    if (TotalRobustCost(reference, observed, fit.used_markers, refined, options) <= best) {
      fit.transform = refined;
    } else {
      fit.transform = start;
    }
  } else {
    fit.transform = start;
  }
  FillResiduals(reference, observed, &fit);
  return fit;
}

Eigen::Matrix3Xd ClusterReference(const MarkerArray& markers, const std::vector<int>& columns) {
  if (columns.size() < 3) throw InvalidInput("cluster reference: need at least 3 markers");
  for (int c : columns) {
    if (c < 0 || c >= markers.markers()) {
      throw InvalidInput("cluster reference: marker column " + std::to_string(c) + " out of range");
    }
  }
  const Eigen::Index n = static_cast<Eigen::Index>(columns.size());
  std::vector<Eigen::Matrix3Xd> complete;
  for (int64_t f = 0; f < markers.frames(); ++f) {
    Eigen::Matrix3Xd m(3, n);
    bool all = true;
    for (Eigen::Index i = 0; i < n && all; ++i) {
      const float* p = markers.at(f, columns[static_cast<size_t>(i)]);
      all = std::isfinite(p[0]) && std::isfinite(p[1]) && std::isfinite(p[2]);
      m.col(i) << p[0], p[1], p[2];
    }
    if (all) complete.push_back(std::move(m));
  }
  if (complete.empty()) throw InvalidInput("cluster reference: no frame has all cluster markers visible");

  std::vector<int> all_cols(columns.size());
  for (size_t i = 0; i < all_cols.size(); ++i) all_cols[i] = static_cast<int>(i);
  Eigen::Matrix3Xd mean = complete.front().colwise() - complete.front().rowwise().mean();
  for (int round = 0; round < 4; ++round) {
    Eigen::Matrix3Xd sum = Eigen::Matrix3Xd::Zero(3, n);
    int64_t used = 0;
    for (const Eigen::Matrix3Xd& m : complete) {
      RigidTransform t;  // maps the mean shape onto this frame
      if (!Kabsch(mean, m, all_cols, &t)) continue;
      const RigidTransform inv = t.Inverse();
      sum += (inv.rotation * m).colwise() + inv.translation;
      ++used;
    }
    if (used == 0) throw InvalidInput("cluster reference: the cluster markers are collinear");
    mean = sum / static_cast<double>(used);
    mean = mean.colwise() - mean.rowwise().mean();
  }
  return mean;
}

int64_t RigidSeries::CountValid() const { return std::count(valid.begin(), valid.end(), uint8_t{1}); }

RigidTransform RigidSeries::Transform(int64_t frame) const {
  return RigidTransform::FromParameters(parameters.row(static_cast<Eigen::Index>(frame)).transpose());
}

Eigen::MatrixXd RigidSeries::ValidParameters() const {
  Eigen::MatrixXd out(CountValid(), 6);
  Eigen::Index r = 0;
  for (int64_t f = 0; f < frames(); ++f) {
    if (valid[static_cast<size_t>(f)]) out.row(r++) = parameters.row(static_cast<Eigen::Index>(f));
  }
  return out;
}

RigidSeries EstimateRigidSeries(const MarkerArray& markers, const std::vector<int>& cluster_columns,
                                const Eigen::Matrix3Xd& reference, const RigidOptions& options, Progress* progress) {
  const Eigen::Index n = static_cast<Eigen::Index>(cluster_columns.size());
  if (reference.cols() != n) {
    throw InvalidInput("rigid series: reference has " + std::to_string(reference.cols()) + " markers, cluster has " +
                       std::to_string(n));
  }
  for (int c : cluster_columns) {
    if (c < 0 || c >= markers.markers()) {
      throw InvalidInput("rigid series: marker column " + std::to_string(c) + " out of range");
    }
  }
  const int64_t frames = markers.frames();
  RigidSeries s;
  s.columns = cluster_columns;
  s.reference = reference;
  s.parameters = Eigen::MatrixXd::Constant(frames, 6, kNaN);
  s.rms_mm = Eigen::VectorXd::Constant(frames, kNaN);
  s.residual_mm = Eigen::MatrixXd::Constant(frames, n, kNaN);
  s.valid.assign(static_cast<size_t>(frames), 0);
  s.converged.assign(static_cast<size_t>(frames), 0);
  Eigen::Matrix3Xd obs(3, n);
  for (int64_t f = 0; f < frames; ++f) {
    if (progress && f % 1024 == 0)
      progress->Update("rigid motion", static_cast<double>(f) / static_cast<double>(frames));
    for (Eigen::Index i = 0; i < n; ++i) {
      const float* p = markers.at(f, cluster_columns[static_cast<size_t>(i)]);
      obs.col(i) << p[0], p[1], p[2];  // NaN stays NaN
    }
    const RigidFit fit = EstimateRigid(reference, obs, options);
    if (!fit.valid) continue;
    const Eigen::Index r = static_cast<Eigen::Index>(f);
    s.valid[static_cast<size_t>(f)] = 1;
    s.converged[static_cast<size_t>(f)] = fit.converged ? 1 : 0;
    s.parameters.row(r) = fit.transform.Parameters().transpose();
    s.rms_mm(r) = fit.rms_mm;
    s.residual_mm.row(r) = fit.per_marker_residual_mm.transpose();
  }
  if (progress) progress->Update("rigid motion", 1.0);
  return s;
}

namespace {

MarkerArray ApplySeries(const MarkerArray& in, const RigidSeries& series, bool to_local) {
  if (in.frames() != series.frames()) {
    throw InvalidInput("rigid series has " + std::to_string(series.frames()) + " frames, markers have " +
                       std::to_string(in.frames()));
  }
  MarkerArray out(in.frames(), in.markers());
  for (int64_t f = 0; f < in.frames(); ++f) {
    if (!series.valid[static_cast<size_t>(f)]) continue;
    RigidTransform t = series.Transform(f);
    if (to_local) t = t.Inverse();
    for (int64_t m = 0; m < in.markers(); ++m) {
      if (!in.Visible(f, m)) continue;
      const float* p = in.at(f, m);
      const Eigen::Vector3d q = t.Apply(Eigen::Vector3d(p[0], p[1], p[2]));
      float* o = out.at(f, m);
      for (int i = 0; i < 3; ++i) o[i] = static_cast<float>(q(i));
    }
  }
  return out;
}

}  // namespace

MarkerArray ToLocalFrame(const MarkerArray& markers, const RigidSeries& series) {
  return ApplySeries(markers, series, true);
}

MarkerArray ToLabFrame(const MarkerArray& local, const RigidSeries& series) {
  return ApplySeries(local, series, false);
}

}  // namespace csw
