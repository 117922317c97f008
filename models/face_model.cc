#include "models/face_model.h"

#include <ceres/tiny_solver.h>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <string>

#include "core/error.h"
#include "models/frame_selection.h"
#include "models/so3.h"

namespace csw {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string LayoutSummary(const FaceLayout& layout) {
  return std::to_string(layout.num_markers()) + " (" + std::to_string(layout.head.size()) + " head + " +
         std::to_string(layout.face.size()) + " face + " + std::to_string(layout.throat.size()) + " throat)";
}

void CheckLayout(const FaceLayout& layout, const char* who) {
  const std::string w = who;
  if (layout.head.size() < 3) {
    throw InvalidInput(w + ": the head cluster needs at least 3 markers, the layout has " +
                       std::to_string(layout.head.size()));
  }
  if (layout.num_shape_markers() < 1) throw InvalidInput(w + ": the layout has no face or throat marker");
  if (layout.throat_weights.size() != layout.throat.size()) {
    throw InvalidInput(w + ": " + std::to_string(layout.throat.size()) + " throat markers but " +
                       std::to_string(layout.throat_weights.size()) + " throat weights");
  }
  for (size_t i = 0; i < layout.throat_weights.size(); ++i) {
    const double v = layout.throat_weights[i];
    if (!std::isnan(v) && !(v >= 0.0 && v <= 1.0)) {
      throw InvalidInput(w + ": throat marker " + layout.throat[i] + " has head weight " + std::to_string(v) +
                         ", outside [0, 1]");
    }
  }
}

// Head-frame position of a shape marker seen at `lab` for head pose (R, t):
// solves lab = A x + w t + (1 − w) t̄ with A = w R + (1 − w) R̄.
Eigen::Vector3d LabToHead(const Eigen::Vector3d& lab, const RigidTransform& pose, const RigidTransform& rest, double w,
                          const Eigen::Vector3d& k = Eigen::Vector3d::Zero()) {
  const Eigen::Vector3d l =
      k.isZero() ? lab : Eigen::Vector3d(lab - (pose.rotation * rest.rotation.transpose() * k - k));
  if (w == 1.0) return pose.rotation.transpose() * (l - pose.translation);
  const Eigen::Matrix3d a = w * pose.rotation + (1.0 - w) * rest.rotation;
  const Eigen::Vector3d b = l - w * pose.translation - (1.0 - w) * rest.translation;
  return a.partialPivLu().solve(b);
}

Eigen::Vector3d OffsetOf(const FaceModel& model, int j) {
  return model.rotation_offsets.rows() > j ? Eigen::Vector3d(model.rotation_offsets.row(j).transpose())
                                           : Eigen::Vector3d::Zero();
}

// One throat marker over the selected frames, for ceres::TinySolver (header
// only; the csw binary does not link the Ceres library): frame f gives the
// 3 residuals A_f (m + L p_f) + w t_f + (1 - w) t_bar + (R_f R_barᵀ - I) k
// - obs_f, with A_f = w R_f + (1 - w) R_bar; parameters x = (w, m (3),
// L (3 x P row-major), k (3)). The Jacobian is analytic (column-major, as
// TinySolver expects).
struct ThroatProblem {
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = Eigen::Dynamic };
  const std::vector<RigidTransform>* poses = nullptr;
  const RigidTransform* rest = nullptr;
  const Eigen::MatrixXd* params = nullptr;  // P x n, one column per frame
  const Eigen::Matrix3Xd* observed = nullptr;
  int np = 0;
  bool fit_offsets = true;  // false: k stays at its start (zero Jacobian columns)
  int NumResiduals() const { return 3 * static_cast<int>(observed->cols()); }
  int NumParameters() const { return 7 + 3 * np; }

  bool operator()(const double* x, double* residuals, double* jacobian) const {
    const double w = x[0];
    const Eigen::Vector3d k(x[4 + 3 * np], x[5 + 3 * np], x[6 + 3 * np]);
    const Eigen::Index n = observed->cols();
    const Eigen::Index rows = 3 * n;
    for (Eigen::Index f = 0; f < n; ++f) {
      const RigidTransform& pose = (*poses)[static_cast<size_t>(f)];
      const double* p = params->col(f).data();
      Eigen::Vector3d v(x[1], x[2], x[3]);
      for (int i = 0; i < 3; ++i) {
        for (int c = 0; c < np; ++c) v(i) += x[4 + i * np + c] * p[c];
      }
      const Eigen::Matrix3d a = w * pose.rotation + (1.0 - w) * rest->rotation;
      Eigen::Map<Eigen::Vector3d> r(residuals + 3 * f);
      const Eigen::Matrix3d b = pose.rotation * rest->rotation.transpose() - Eigen::Matrix3d::Identity();
      r = a * v + w * pose.translation + (1.0 - w) * rest->translation + b * k - observed->col(f);
      if (jacobian == nullptr) continue;
      const Eigen::Vector3d jw = (pose.rotation - rest->rotation) * v + pose.translation - rest->translation;
      for (int row = 0; row < 3; ++row) {
        const Eigen::Index rr = 3 * f + row;
        jacobian[rr] = jw(row);
        for (int i = 0; i < 3; ++i) {
          jacobian[(1 + i) * rows + rr] = a(row, i);
          for (int c = 0; c < np; ++c) jacobian[(4 + i * np + c) * rows + rr] = a(row, i) * p[c];
          jacobian[(4 + 3 * np + i) * rows + rr] = fit_offsets ? b(row, i) : 0.0;
        }
      }
    }
    return true;
  }
};

// Least-squares parameters of every row of `data` (all coordinates visible).
Eigen::MatrixXd EstimateRows(const GuidedPcaModel& shape, const Eigen::MatrixXd& data) {
  const Eigen::MatrixXd& a = shape.loadings;
  Eigen::MatrixXd normal = a.transpose() * a;
  const double lambda = GuidedPcaModel::kEstimateRidge * std::max(normal.trace(), 1e-300) /
                        static_cast<double>(std::max<Eigen::Index>(1, a.cols()));
  normal.diagonal().array() += lambda;
  const Eigen::MatrixXd centred = data.rowwise() - shape.mean.transpose();
  return normal.ldlt().solve(a.transpose() * centred.transpose()).transpose();
}

}  // namespace

Eigen::Matrix3Xd FaceModel::ShapeMarkersInLab(const RigidTransform& pose, const Eigen::VectorXd& params) const {
  const Eigen::VectorXd x = shape.Predict(params);
  const int s = layout.num_shape_markers();
  Eigen::Matrix3Xd out(3, s);
  for (int j = 0; j < s; ++j) {
    const Eigen::Vector3d xj = x.segment<3>(3 * j);
    const double w = head_weights.size() == s ? head_weights(j) : 1.0;
    out.col(j) = w * pose.Apply(xj) + (1.0 - w) * rest_pose.Apply(xj);
    if (rotation_offsets.rows() > j) {
      const Eigen::Vector3d k = rotation_offsets.row(j).transpose();
      out.col(j) += pose.rotation * rest_pose.rotation.transpose() * k - k;
    }
  }
  return out;
}

Eigen::Matrix3Xd FaceModel::MarkersInLab(const RigidTransform& pose, const Eigen::VectorXd& params) const {
  const Eigen::Index h = head.reference.cols();
  Eigen::Matrix3Xd out(3, h + layout.num_shape_markers());
  out.leftCols(h) = (pose.rotation * head.reference).colwise() + pose.translation;
  out.rightCols(layout.num_shape_markers()) = ShapeMarkersInLab(pose, params);
  return out;
}

FaceModel FitFaceModel(const FaceLayout& layout, const std::vector<MarkerArray>& takes, const FaceModelOptions& options,
                       Progress* progress) {
  CheckLayout(layout, "face model");
  if (takes.empty()) throw InvalidInput("face model: no training take");
  const int nh = static_cast<int>(layout.head.size());
  const int ns = layout.num_shape_markers();
  const int nf = static_cast<int>(layout.face.size());
  int64_t total_frames = 0;
  for (size_t i = 0; i < takes.size(); ++i) {
    if (takes[i].markers() != layout.num_markers()) {
      throw InvalidInput("face model: training take " + std::to_string(i + 1) + " has " +
                         std::to_string(takes[i].markers()) + " columns, the layout has " + LayoutSummary(layout));
    }
    total_frames += takes[i].frames();
  }
  if (!(options.min_distance_mm > 0)) {
    throw InvalidInput("face model: min_distance_mm must be > 0, got " + std::to_string(options.min_distance_mm));
  }
  if (options.throat_weight_rounds < 0) throw InvalidInput("face model: throat_weight_rounds must be >= 0");
  if (!(options.initial_throat_weight >= 0.0 && options.initial_throat_weight <= 1.0)) {
    throw InvalidInput("face model: initial_throat_weight must be in [0, 1], got " +
                       std::to_string(options.initial_throat_weight));
  }
  std::vector<GuidedPcaStep> steps = options.steps;
  if (steps.empty()) {
    if (options.default_components < 1) {
      throw InvalidInput("face model: default_components must be >= 1, got " +
                         std::to_string(options.default_components));
    }
    steps.push_back(GuidedPcaStep{"shape", {}, options.default_components});
  }
  int num_params = 0;
  for (const GuidedPcaStep& s : steps) num_params += std::max(0, s.components);

  FaceModel model;
  model.layout = layout;

  // 1. Head cluster: reference shape and motion PCA.
  std::vector<MarkerArray> head_takes;
  head_takes.reserve(takes.size());
  for (const MarkerArray& t : takes) {
    MarkerArray h(t.frames(), nh);
    for (int64_t f = 0; f < t.frames(); ++f) std::copy(t.at(f, 0), t.at(f, 0) + 3 * nh, h.at(f, 0));
    head_takes.push_back(std::move(h));
  }
  model.head = FitRigidModel("head", layout.head, head_takes, options.head, progress);
  head_takes.clear();
  if (model.head.motion.mean.size() != 6) throw InvalidInput("face model: the head motion PCA is not 6-dimensional");
  model.rest_pose = RigidTransform::FromParameters(model.head.motion.mean.head<6>());

  // 2. Head pose of every frame; lab shape markers of all takes end to end.
  std::vector<int> head_cols(static_cast<size_t>(nh));
  for (int c = 0; c < nh; ++c) head_cols[static_cast<size_t>(c)] = c;
  std::vector<RigidTransform> poses(static_cast<size_t>(total_frames));
  std::vector<uint8_t> pose_valid(static_cast<size_t>(total_frames), 0);
  MarkerArray lab(total_frames, ns);
  int64_t at = 0;
  for (size_t i = 0; i < takes.size(); ++i) {
    const MarkerArray& t = takes[i];
    const RigidSeries series = EstimateRigidSeries(t, head_cols, model.head.reference, options.head.rigid, progress);
    for (int64_t f = 0; f < t.frames(); ++f, ++at) {
      std::copy(t.at(f, nh), t.at(f, nh) + 3 * ns, lab.at(at, 0));
      if (series.valid[static_cast<size_t>(f)]) {
        pose_valid[static_cast<size_t>(at)] = 1;
        poses[static_cast<size_t>(at)] = series.Transform(f);
      }
    }
  }

  // Head weights: 1 for face markers; throat fixed or at the start value.
  model.head_weights = Eigen::VectorXd::Ones(ns);
  model.rotation_offsets = Eigen::MatrixXd::Zero(ns, 3);
  std::vector<int> fitted;  // shape-marker indices of the fitted throat weights
  for (size_t i = 0; i < layout.throat.size(); ++i) {
    const int j = nf + static_cast<int>(i);
    if (std::isnan(layout.throat_weights[i])) {
      model.head_weights(j) = options.initial_throat_weight;
      fitted.push_back(j);
    } else {
      model.head_weights(j) = layout.throat_weights[i];
    }
  }

  // 3. Training-frame selection on the head-frame shape markers (start weights).
  auto to_head = [&](int64_t frame, int j) -> Eigen::Vector3d {
    const float* p = lab.at(frame, j);
    return LabToHead(Eigen::Vector3d(p[0], p[1], p[2]), poses[static_cast<size_t>(frame)], model.rest_pose,
                     model.head_weights(j), OffsetOf(model, j));
  };
  {
    MarkerArray local(total_frames, ns);
    for (int64_t f = 0; f < total_frames; ++f) {
      if (!pose_valid[static_cast<size_t>(f)]) continue;
      for (int j = 0; j < ns; ++j) {
        if (!lab.Visible(f, j)) continue;
        const Eigen::Vector3d x = to_head(f, j);
        float* q = local.at(f, j);
        for (int k = 0; k < 3; ++k) q[k] = static_cast<float>(x(k));
      }
    }
    std::vector<int> cols(static_cast<size_t>(ns));
    for (int j = 0; j < ns; ++j) cols[static_cast<size_t>(j)] = j;
    const FrameSelection sel = SelectTrainingFrames(local, cols, options.min_distance_mm);
    model.info.training_frames = sel.complete_frames;
    model.info.selected_frames = static_cast<int64_t>(sel.frames.size());
    if (sel.complete_frames == 0) {
      throw InvalidInput("face model: no training frame has every face and throat marker visible with a head pose (" +
                         std::to_string(total_frames) + " frames in " + std::to_string(takes.size()) + " takes)");
    }
    if (static_cast<int64_t>(sel.frames.size()) < num_params + 1) {
      throw InvalidInput("face model: " + std::to_string(sel.frames.size()) +
                         " training frames selected (min_distance_mm " + std::to_string(options.min_distance_mm) +
                         "), fewer than the " + std::to_string(num_params) + " parameters + 1");
    }
    if (progress) progress->Update("face model: training frames", 1.0);
    // Keep only the selected frames from here on.
    MarkerArray sel_lab(static_cast<int64_t>(sel.frames.size()), ns);
    std::vector<RigidTransform> sel_poses;
    sel_poses.reserve(sel.frames.size());
    for (size_t r = 0; r < sel.frames.size(); ++r) {
      const int64_t f = sel.frames[r];
      std::copy(lab.at(f, 0), lab.at(f, 0) + 3 * ns, sel_lab.at(static_cast<int64_t>(r), 0));
      sel_poses.push_back(poses[static_cast<size_t>(f)]);
    }
    lab = std::move(sel_lab);
    poses = std::move(sel_poses);
  }
  const int64_t n = lab.frames();
  auto head_frame_data = [&]() {
    Eigen::MatrixXd data(n, 3 * ns);
    for (int64_t f = 0; f < n; ++f) {
      for (int j = 0; j < ns; ++j) data.block<1, 3>(f, 3 * j) = to_head(f, j).transpose();
    }
    return data;
  };

  // 4. Guided PCA, alternating with the throat weights: first the blend
  // alone (k = 0), then with the rotation offsets; the offsets are kept when
  // they cut the fitted throat markers' training residual (sum of squares, lab)
  // by more than five times what fitting noise alone would (3 parameters per
  // marker over 3 residuals per frame: a fraction 1/n of it), else the blend's
  // weights are restored.
  const int rounds = fitted.empty() ? 0 : options.throat_weight_rounds;
  auto throat_rss = [&]() {
    const Eigen::MatrixXd data = head_frame_data();
    const GuidedPcaModel shape = FitGuidedPca(data, steps);
    const Eigen::MatrixXd params = EstimateRows(shape, data);
    double rss = 0;
    for (int64_t f = 0; f < n; ++f) {
      const Eigen::VectorXd x = shape.mean + shape.loadings * params.row(f).transpose();
      const RigidTransform& pose = poses[static_cast<size_t>(f)];
      for (int j : fitted) {
        const Eigen::Vector3d xj = x.segment<3>(3 * j), k = model.rotation_offsets.row(j).transpose();
        const double w = model.head_weights(j);
        const Eigen::Vector3d pred = w * pose.Apply(xj) + (1.0 - w) * model.rest_pose.Apply(xj) +
                                     pose.rotation * model.rest_pose.rotation.transpose() * k - k;
        const float* o = lab.at(f, j);
        rss += (pred - Eigen::Vector3d(o[0], o[1], o[2])).squaredNorm();
      }
    }
    return rss;
  };
  double blend_rss = 0;
  Eigen::VectorXd blend_weights;
  for (int round = 0; round < 2 * rounds; ++round) {
    const bool offsets = round >= rounds;
    if (round == rounds) {
      blend_rss = throat_rss();
      blend_weights = model.head_weights;
    }
    if (progress) progress->Update("face model: throat weights", 0.5 * static_cast<double>(round) / rounds);
    const GuidedPcaModel shape = FitGuidedPca(head_frame_data(), steps);
    const Eigen::MatrixXd params = EstimateRows(shape, head_frame_data());  // n × P
    const Eigen::MatrixXd params_rows = params.transpose();                 // P × n, one column per frame
    for (int j : fitted) {
      double w = model.head_weights(j);
      Eigen::VectorXd x(7 + 3 * num_params);
      x(0) = w;
      x.segment<3>(1) = shape.mean.segment<3>(3 * j);
      for (int i = 0; i < 3; ++i) {
        for (int k = 0; k < num_params; ++k) x(4 + i * num_params + k) = shape.loadings(3 * j + i, k);
      }
      x.tail<3>() = model.rotation_offsets.row(j).transpose();
      Eigen::Matrix3Xd observed(3, n);
      for (int64_t f = 0; f < n; ++f) {
        const float* o = lab.at(f, j);
        observed.col(f) << o[0], o[1], o[2];
      }
      ThroatProblem problem;
      problem.poses = &poses;
      problem.rest = &model.rest_pose;
      problem.params = &params_rows;
      problem.observed = &observed;
      problem.np = num_params;
      problem.fit_offsets = offsets;
      // Unconstrained Levenberg-Marquardt; the weight is then clamped to [0, 1]
      // (only w and k are kept: the shape is refitted by the next round's PCA).
      ceres::TinySolver<ThroatProblem> solver;
      solver.options.max_num_iterations = 51;  // the start counts as one
      solver.options.function_tolerance = 1e-12;
      solver.options.gradient_tolerance = 1e-14;
      solver.options.parameter_tolerance = 1e-12;
      solver.Solve(problem, &x);
      w = x(0);
      if (std::isfinite(w) && x.tail<3>().allFinite()) {
        model.head_weights(j) = std::clamp(w, 0.0, 1.0);
        model.rotation_offsets.row(j) = x.tail<3>().transpose();
      }
      if (progress) progress->CheckCancel();
    }
  }
  if (rounds > 0) {
    const double offset_rss = throat_rss();
    const bool keep_offsets = blend_rss - offset_rss > 5.0 * blend_rss / static_cast<double>(n);
    if (!keep_offsets) {
      model.head_weights = blend_weights;
      model.rotation_offsets.setZero();
    }
  }

  const Eigen::MatrixXd data = head_frame_data();
  model.shape = FitGuidedPca(data, steps);
  const Eigen::MatrixXd params = EstimateRows(model.shape, data);
  const Eigen::MatrixXd fit = (model.shape.loadings * params.transpose()).colwise() + model.shape.mean;
  model.info.training_rms_mm = std::sqrt((fit - data.transpose()).squaredNorm() / static_cast<double>(n * ns));
  if (progress) progress->Update("face model: throat weights", 1.0);
  return model;
}

namespace {

// Model data laid out for the per-frame solver.
struct Prepared {
  int nh = 0, ns = 0, np = 0;
  Eigen::Matrix3Xd reference;     // 3 × nh
  Eigen::VectorXd mean;           // 3ns
  Eigen::MatrixXd loadings;       // 3ns × np
  Eigen::VectorXd weights;        // ns
  Eigen::Matrix3Xd offsets;       // 3 × ns: k_j (rotation offsets)
  Eigen::Matrix3Xd rest_offsets;  // 3 × ns: R̄ᵀ k_j
  Eigen::VectorXd rest_mean;      // 3ns: (1 − w)(R̄ m_j + t̄)
  Eigen::MatrixXd rest_loadings;  // 3ns × np: (1 − w) R̄ L_j
  RigidTransform rest;
  int num_rigid_shape = 0;  // leading shape markers with w = 1 (the face)
};

// Per-frame problem for ceres::TinySolver: x = (δ, τ, p), R = exp(δ) R0,
// t = t0 + τ. Residuals: every head marker (3), every shape marker (3), the
// prior (np); hidden markers give zero rows so the size never changes.
//
// Markers that move rigidly with the head (the cluster and the face, w = 1)
// have their residual expressed in the head frame, Rᵀ(R x + t − obs) =
// x − Rᵀ(obs − t): the same length, so the same cost, but its derivative with
// respect to the shape parameters is the constant loading block, and with
// respect to δ it is −[y]× R0ᵀ J_l(δ)ᵀ with y = Rᵀ(obs − t) (exact: J_l is
// the left Jacobian of SO(3)). Throat markers (w < 1) keep the lab residual
// w (R x + t) + (1 − w)(R̄ x + t̄) + (R R̄ᵀ − I) k − obs.
template <int kNumParameters>
struct FrameProblem {
  using Scalar = double;
  enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = kNumParameters };

  const Prepared* m = nullptr;
  double prior = 0;
  Eigen::Matrix3d r0 = Eigen::Matrix3d::Identity();
  Eigen::Vector3d t0 = Eigen::Vector3d::Zero();
  Eigen::Matrix3Xd obs;            // 3 × (nh + ns), lab
  std::vector<uint8_t> visible;    // nh + ns
  mutable Eigen::VectorXd x_head;  // 3ns scratch
  mutable Eigen::VectorXd x_rest;  // 3ns scratch

  int NumResiduals() const { return 3 * (m->nh + m->ns) + m->np; }
  int NumParameters() const { return 6 + m->np; }

  bool operator()(const double* params, double* residuals, double* jacobian) const {
    const int nh = m->nh, ns = m->ns, np = m->np, nf = m->num_rigid_shape;
    const int nr = NumResiduals();
    const Eigen::Vector3d d(params[0], params[1], params[2]);
    const Eigen::Vector3d t = t0 + Eigen::Vector3d(params[3], params[4], params[5]);
    const Eigen::Map<const Eigen::VectorXd> p(params + 6, np);
    Eigen::Matrix3d e, jl;
    so3::ExpAndLeftJacobian(d, &e, jacobian ? &jl : nullptr);
    const Eigen::Matrix3d r = e * r0;
    const Eigen::Matrix3d rt = r.transpose();
    Eigen::Map<Eigen::VectorXd> res(residuals, nr);
    Eigen::Map<Eigen::MatrixXd> jac(jacobian, jacobian ? nr : 0, jacobian ? 6 + np : 0);
    Eigen::Matrix3d k;  // R0ᵀ J_lᵀ
    if (jacobian) {
      jac.setZero();
      k.noalias() = r0.transpose() * jl.transpose();
      // Face rows: constant loading blocks (hidden rows are cleared below).
      jac.block(3 * nh, 6, 3 * nf, np) = m->loadings.topRows(3 * nf);
    }
    x_head.noalias() = m->loadings * p;
    x_head += m->mean;
    // Head cluster and face markers, head frame.
    auto rigid_row = [&](int row, const Eigen::Vector3d& model_point, int column) {
      const Eigen::Vector3d y = rt * (obs.col(column) - t);
      res.segment<3>(row) = model_point - y;
      if (jacobian) {
        for (int c = 0; c < 3; ++c) jac.block<3, 1>(row, c) = -y.cross(k.col(c));
        jac.block<3, 3>(row, 3) = rt;
      }
    };
    for (int c = 0; c < nh; ++c) {
      if (visible[static_cast<size_t>(c)]) {
        rigid_row(3 * c, m->reference.col(c), c);
      } else {
        res.segment<3>(3 * c).setZero();
      }
    }
    for (int j = 0; j < nf; ++j) {
      const int row = 3 * (nh + j);
      if (visible[static_cast<size_t>(nh + j)]) {
        rigid_row(row, x_head.segment<3>(3 * j), nh + j);
      } else {
        res.segment<3>(row).setZero();
        if (jacobian) jac.block(row, 6, 3, np).setZero();
      }
    }
    // Throat markers, lab frame.
    if (nf < ns) {
      x_rest.tail(3 * (ns - nf)).noalias() = m->rest_loadings.bottomRows(3 * (ns - nf)) * p;
      x_rest.tail(3 * (ns - nf)) += m->rest_mean.tail(3 * (ns - nf));
    }
    for (int j = nf; j < ns; ++j) {
      const int row = 3 * (nh + j);
      if (!visible[static_cast<size_t>(nh + j)]) {
        res.segment<3>(row).setZero();
        continue;
      }
      const double w = m->weights(j);
      const Eigen::Vector3d u = r * x_head.segment<3>(3 * j);
      const Eigen::Vector3d v = r * m->rest_offsets.col(j);
      res.segment<3>(row) = w * (u + t) + x_rest.segment<3>(3 * j) + v - m->offsets.col(j) - obs.col(nh + j);
      if (jacobian) {
        jac.block<3, 3>(row, 0) = -so3::Hat(w * u + v) * jl;
        jac.block(row, 3, 3, 3).diagonal().setConstant(w);
        jac.block(row, 6, 3, np).noalias() = (w * r) * m->loadings.middleRows(3 * j, 3);
        jac.block(row, 6, 3, np) += m->rest_loadings.middleRows(3 * j, 3);
      }
    }
    const int prow = 3 * (nh + ns);
    res.segment(prow, np) = prior * p;
    if (jacobian) jac.block(prow, 6, np, np).diagonal().setConstant(prior);
    return true;
  }
};

// The per-frame loop; N is the solver's parameter count (6 + P) as a
// compile-time size, or Eigen::Dynamic (what InvertFace uses).
template <int N>
void SolveFrames(const FaceModel& model, const Prepared& prep, const MarkerArray& take, const InversionOptions& options,
                 Progress* progress, InversionResult& out) {
  const int nh = prep.nh, ns = prep.ns, np = prep.np;
  const int nm = nh + ns;
  const int64_t frames = take.frames();
  FrameProblem<N> problem;
  problem.m = &prep;
  problem.prior = options.prior_mm;
  problem.obs.resize(3, nm);
  problem.visible.assign(static_cast<size_t>(nm), 0);
  problem.x_head.resize(3 * ns);
  problem.x_rest.resize(3 * ns);
  ceres::TinySolver<FrameProblem<N>> solver;
  solver.options.max_num_iterations = options.max_iterations + 1;  // TinySolver counts the start as one
  solver.options.gradient_tolerance = 1e-10;
  solver.options.parameter_tolerance = 1e-9;
  solver.options.function_tolerance = 1e-12;
  solver.options.cost_threshold = 1e-24;
  Eigen::Matrix<double, N, 1> x;
  x.resize(6 + np);
  Eigen::VectorXd prev_p(np);
  bool have_prev = false;
  Eigen::Matrix3Xd lab(3, nm);
  Eigen::Matrix3Xd head_obs(3, nh);

  for (int64_t f = 0; f < frames; ++f) {
    if (progress && (f & 1023) == 0)
      progress->Update("invert face", static_cast<double>(f) / static_cast<double>(frames));
    int vis_head = 0, vis_shape = 0;
    for (int c = 0; c < nm; ++c) {
      const float* q = take.at(f, c);
      const bool v = std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]);
      problem.visible[static_cast<size_t>(c)] = v ? 1 : 0;
      if (v) {
        problem.obs.col(c) = Eigen::Vector3d(q[0], q[1], q[2]);
        (c < nh ? vis_head : vis_shape)++;
      } else {
        problem.obs.col(c).setZero();
      }
    }
    if (vis_head < std::max(3, options.min_cluster_markers) || vis_shape < std::max(1, options.min_shape_markers)) {
      have_prev = false;
      continue;  // status kTooFewMarkers
    }
    const bool cold = !(options.warm_start && have_prev);
    if (cold) {
      // Cold start: Kabsch on the head cluster, then the shape parameters
      // from the visible shape markers taken to the head frame.
      for (int k = 0; k < nh; ++k) {
        if (problem.visible[static_cast<size_t>(k)]) {
          head_obs.col(k) = problem.obs.col(k);
        } else {
          head_obs.col(k).setConstant(kNaN);
        }
      }
      const RigidFit fit = EstimateRigidKabsch(prep.reference, head_obs);
      if (!fit.valid) {
        out.status[static_cast<size_t>(f)] = FrameStatus::kNoStart;
        have_prev = false;
        continue;
      }
      problem.r0 = fit.transform.rotation;
      problem.t0 = fit.transform.translation;
      Eigen::VectorXd coords = Eigen::VectorXd::Zero(3 * ns);
      std::vector<bool> mask(static_cast<size_t>(3 * ns), false);
      for (int j = 0; j < ns; ++j) {
        if (!problem.visible[static_cast<size_t>(nh + j)]) continue;
        coords.segment<3>(3 * j) =
            LabToHead(problem.obs.col(nh + j), fit.transform, prep.rest, prep.weights(j), prep.offsets.col(j));
        for (int k = 0; k < 3; ++k) mask[static_cast<size_t>(3 * j + k)] = true;
      }
      prev_p = np > 0 ? model.shape.Estimate(coords, mask) : Eigen::VectorXd();
      if (!prev_p.allFinite()) prev_p.setZero();
    }
    x.template head<6>().setZero();
    x.tail(np) = prev_p;
    const auto& summary = solver.Solve(problem, &x);

    Eigen::Matrix3d e;
    so3::ExpAndLeftJacobian(x.template head<3>(), &e, nullptr);
    RigidTransform pose;
    pose.rotation = e * problem.r0;
    pose.translation = problem.t0 + x.template segment<3>(3);
    const Eigen::VectorXd p = x.tail(np);
    if (!pose.rotation.allFinite() || !pose.translation.allFinite() || !p.allFinite()) {
      out.status[static_cast<size_t>(f)] = FrameStatus::kFailed;
      have_prev = false;
      continue;
    }
    // Re-orthonormalise so rounding does not accumulate across warm starts.
    {
      const Eigen::Quaterniond qn(pose.rotation);
      pose.rotation = qn.normalized().toRotationMatrix();
    }
    out.solved[static_cast<size_t>(f)] = 1;
    out.converged[static_cast<size_t>(f)] =
        summary.status != ceres::TinySolver<FrameProblem<N>>::HIT_MAX_ITERATIONS ? 1 : 0;
    out.status[static_cast<size_t>(f)] =
        out.converged[static_cast<size_t>(f)] ? FrameStatus::kConverged : FrameStatus::kMaxIterations;
    out.iterations[static_cast<size_t>(f)] = summary.iterations;
    out.cold_start[static_cast<size_t>(f)] = cold ? 1 : 0;
    out.pose.row(f) = pose.Parameters().transpose();
    out.params.row(f) = p.transpose();

    // Reconstruct all model markers.
    lab.leftCols(nh) = (pose.rotation * prep.reference).colwise() + pose.translation;
    const Eigen::VectorXd xh = prep.mean + prep.loadings * p;
    const Eigen::VectorXd xr = prep.rest_mean + prep.rest_loadings * p;
    for (int j = 0; j < ns; ++j) {
      const double w = prep.weights(j);
      lab.col(nh + j) = w * (pose.rotation * xh.segment<3>(3 * j) + pose.translation) + xr.segment<3>(3 * j) +
                        pose.rotation * prep.rest_offsets.col(j) - prep.offsets.col(j);
    }
    for (int c = 0; c < nm; ++c) {
      float* q = out.reconstructed.at(f, c);
      for (int k = 0; k < 3; ++k) q[k] = static_cast<float>(lab(k, c));
      if (problem.visible[static_cast<size_t>(c)]) out.error_mm(f, c) = (lab.col(c) - problem.obs.col(c)).norm();
    }
    problem.r0 = pose.rotation;
    problem.t0 = pose.translation;
    prev_p = p;
    have_prev = true;
  }
}

}  // namespace

InversionResult InvertFace(const FaceModel& model, const MarkerArray& take, const InversionOptions& options,
                           Progress* progress) {
  const FaceLayout& layout = model.layout;
  CheckLayout(layout, "face inversion");
  const int nh = static_cast<int>(layout.head.size());
  const int ns = layout.num_shape_markers();
  const int np = model.num_parameters();
  if (model.head.reference.cols() != nh || model.head_weights.size() != ns || model.shape.num_coordinates() != 3 * ns ||
      model.shape.mean.size() != 3 * ns) {
    throw InvalidInput("face inversion: the model is inconsistent with its layout " + LayoutSummary(layout));
  }
  if (take.markers() != layout.num_markers()) {
    throw InvalidInput("face inversion: the take has " + std::to_string(take.markers()) +
                       " columns, the face model has " + LayoutSummary(layout));
  }
  if (options.max_iterations < 1) throw InvalidInput("face inversion: max_iterations must be >= 1");
  if (!(options.prior_mm >= 0)) throw InvalidInput("face inversion: prior_mm must be >= 0");

  Prepared prep;
  prep.nh = nh;
  prep.ns = ns;
  prep.np = np;
  prep.reference = model.head.reference;
  prep.mean = model.shape.mean;
  prep.loadings = model.shape.loadings;
  prep.weights = model.head_weights;
  prep.rest = model.rest_pose;
  prep.offsets = Eigen::Matrix3Xd::Zero(3, ns);
  if (model.rotation_offsets.size() > 0) {
    if (model.rotation_offsets.rows() != ns || model.rotation_offsets.cols() != 3) {
      throw InvalidInput("face inversion: the model has " + std::to_string(model.rotation_offsets.rows()) +
                         " rotation offsets for " + std::to_string(ns) + " shape markers");
    }
    prep.offsets = model.rotation_offsets.transpose();
  }
  prep.rest_offsets = prep.rest.rotation.transpose() * prep.offsets;
  prep.rest_mean.resize(3 * ns);
  prep.rest_loadings.resize(3 * ns, np);
  for (int j = 0; j < ns; ++j) {
    const double w = prep.weights(j);
    prep.rest_mean.segment<3>(3 * j) =
        (1.0 - w) * (prep.rest.rotation * prep.mean.segment<3>(3 * j) + prep.rest.translation);
    prep.rest_loadings.middleRows(3 * j, 3) = (1.0 - w) * prep.rest.rotation * prep.loadings.middleRows(3 * j, 3);
  }

  // Shape markers with w = 1 come first (face before throat); a throat
  // marker with a weight of exactly 1 keeps the lab residual: same cost.
  while (prep.num_rigid_shape < static_cast<int>(layout.face.size()) && prep.weights(prep.num_rigid_shape) == 1.0) {
    ++prep.num_rigid_shape;
  }

  const int64_t frames = take.frames();
  const int nm = nh + ns;
  InversionResult out;
  out.pose = Eigen::MatrixXd::Constant(frames, 6, kNaN);
  out.params = Eigen::MatrixXd::Constant(frames, np, kNaN);
  out.reconstructed = MarkerArray(frames, nm);
  out.error_mm = Eigen::MatrixXd::Constant(frames, nm, kNaN);
  out.ResizeFrames(frames);

  // Dynamic sizes: fixed-size instances for 1-10 parameters cost 4 minutes of
  // compilation and measured no faster (bench_face_inversion, CPU time).
  SolveFrames<Eigen::Dynamic>(model, prep, take, options, progress, out);
  if (progress) progress->Update("invert face", 1.0);
  return out;
}

}  // namespace csw
