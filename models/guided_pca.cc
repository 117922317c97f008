#include "models/guided_pca.h"

#include <Eigen/Cholesky>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <set>
#include <string>

#include "core/error.h"

namespace csw {
namespace {

std::string StepLabel(size_t index, const GuidedPcaStep& step) {
  return "guided PCA step " + std::to_string(index + 1) + " (" + step.name + ")";
}

std::vector<int> StepColumns(size_t index, const GuidedPcaStep& step, int num_markers) {
  std::vector<int> cols;
  if (step.markers.empty()) {
    for (int c = 0; c < 3 * num_markers; ++c) cols.push_back(c);
    return cols;
  }
  std::set<int> seen;
  for (int m : step.markers) {
    if (m < 0 || m >= num_markers) {
      throw InvalidInput(StepLabel(index, step) + ": marker index " + std::to_string(m) + " is outside 0.." +
                         std::to_string(num_markers - 1));
    }
    if (!seen.insert(m).second) {
      throw InvalidInput(StepLabel(index, step) + ": marker index " + std::to_string(m) + " is listed twice");
    }
    for (int k = 0; k < 3; ++k) cols.push_back(3 * m + k);
  }
  return cols;
}

}  // namespace

GuidedPcaModel FitGuidedPca(const Eigen::MatrixXd& data, const std::vector<GuidedPcaStep>& steps) {
  const Eigen::Index n = data.rows();
  const Eigen::Index d = data.cols();
  if (n < 2) throw InvalidInput("guided PCA needs at least 2 frames, got " + std::to_string(n));
  if (d <= 0 || d % 3 != 0) {
    throw InvalidInput("guided PCA needs 3 coordinates per marker, got " + std::to_string(d) + " columns");
  }
  if (!data.allFinite()) throw InvalidInput("guided PCA data holds a non-finite value");
  if (steps.empty()) throw InvalidInput("guided PCA needs at least one step");
  const int num_markers = static_cast<int>(d / 3);

  GuidedPcaModel model;
  model.steps = steps;
  model.mean = data.colwise().mean().transpose();
  Eigen::MatrixXd residual = data.rowwise() - model.mean.transpose();
  const double total = residual.squaredNorm();
  if (!(total > 0)) throw InvalidInput("guided PCA data has no variance");

  int num_params = 0;
  for (const GuidedPcaStep& s : steps) num_params += std::max(s.components, 0);
  model.loadings.resize(d, num_params);
  const double sqrt_dof = std::sqrt(static_cast<double>(n - 1));

  int p = 0;
  for (size_t si = 0; si < steps.size(); ++si) {
    const GuidedPcaStep& step = steps[si];
    const std::vector<int> cols = StepColumns(si, step, num_markers);
    const int max_components = static_cast<int>(std::min<Eigen::Index>(n - 1, cols.size()));
    if (step.components < 1 || step.components > max_components) {
      throw InvalidInput(StepLabel(si, step) + ": asks for " + std::to_string(step.components) +
                         " components, the subset allows 1.." + std::to_string(max_components));
    }
    Eigen::MatrixXd sub(n, static_cast<Eigen::Index>(cols.size()));
    for (size_t c = 0; c < cols.size(); ++c) sub.col(static_cast<Eigen::Index>(c)) = residual.col(cols[c]);
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(sub, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd& sigma = svd.singularValues();
    // A component is usable when it carries variance well above rounding noise
    // of the whole data set.
    const double floor = 1e-10 * std::sqrt(total);
    for (int k = 0; k < step.components; ++k) {
      if (!(sigma(k) > floor)) {
        throw InvalidInput(StepLabel(si, step) + ": component " + std::to_string(k + 1) +
                           " has no variance left to model");
      }
      // Unit-variance scores t = √(n−1)·u_k; regressing the residual on t
      // gives loading Rᵀt / tᵀt = Rᵀu_k / √(n−1).
      const Eigen::VectorXd t = sqrt_dof * svd.matrixU().col(k);
      const Eigen::VectorXd loading = residual.transpose() * svd.matrixU().col(k) / sqrt_dof;
      model.loadings.col(p) = loading;
      model.parameter_names.push_back(step.components == 1 ? step.name : step.name + std::to_string(k + 1));
      const double explained = t.squaredNorm() * loading.squaredNorm();
      model.variance_explained.push_back(explained / total);
      ++p;
    }
    // Subtract the prediction of all k scores at once (they are orthonormal).
    const Eigen::MatrixXd u = svd.matrixU().leftCols(step.components);
    residual -= u * (u.transpose() * residual);
  }
  model.residual_variance = residual.squaredNorm() / total;
  return model;
}

Eigen::VectorXd GuidedPcaModel::Predict(const Eigen::VectorXd& params) const {
  if (params.size() != loadings.cols()) {
    throw InvalidInput("guided PCA model has " + std::to_string(loadings.cols()) + " parameters, got " +
                       std::to_string(params.size()));
  }
  return mean + loadings * params;
}

Eigen::VectorXd GuidedPcaModel::Estimate(const Eigen::VectorXd& coordinates, const std::vector<bool>& visible) const {
  const Eigen::Index d = loadings.rows();
  if (coordinates.size() != d || static_cast<Eigen::Index>(visible.size()) != d) {
    throw InvalidInput("guided PCA model has " + std::to_string(d) + " coordinates, got " +
                       std::to_string(coordinates.size()) + " values and " + std::to_string(visible.size()) +
                       " visibility flags");
  }
  std::vector<Eigen::Index> rows;
  for (Eigen::Index i = 0; i < d; ++i) {
    if (!visible[static_cast<size_t>(i)]) continue;
    if (!std::isfinite(coordinates(i))) {
      throw InvalidInput("guided PCA estimate: visible coordinate " + std::to_string(i) + " is not finite");
    }
    rows.push_back(i);
  }
  if (rows.empty()) throw InvalidInput("guided PCA estimate: no visible coordinate");
  const Eigen::Index np = loadings.cols();
  if (np == 0) return Eigen::VectorXd();
  Eigen::MatrixXd a(static_cast<Eigen::Index>(rows.size()), np);
  Eigen::VectorXd b(static_cast<Eigen::Index>(rows.size()));
  for (size_t r = 0; r < rows.size(); ++r) {
    a.row(static_cast<Eigen::Index>(r)) = loadings.row(rows[r]);
    b(static_cast<Eigen::Index>(r)) = coordinates(rows[r]) - mean(rows[r]);
  }
  Eigen::MatrixXd normal = a.transpose() * a;
  const double lambda = kEstimateRidge * std::max(normal.trace(), 1e-300) / static_cast<double>(np);
  normal.diagonal().array() += lambda;
  return normal.ldlt().solve(a.transpose() * b);
}

Eigen::VectorXd GuidedPcaModel::Estimate(const Eigen::VectorXd& coordinates) const {
  return Estimate(coordinates, std::vector<bool>(static_cast<size_t>(loadings.rows()), true));
}

std::vector<bool> CoordinateMaskFromMarkers(const std::vector<bool>& marker_visible) {
  std::vector<bool> out;
  out.reserve(3 * marker_visible.size());
  for (bool v : marker_visible) out.insert(out.end(), 3, v);
  return out;
}

namespace {

void AddStep(std::vector<GuidedPcaStep>& steps, const std::string& name, const std::vector<int>& markers,
             int components) {
  if (markers.empty()) return;
  steps.push_back({name, markers, components});
}

}  // namespace

std::vector<GuidedPcaStep> SeedFaceSteps(const FaceMarkerGroups& g, int residual_components) {
  std::vector<GuidedPcaStep> steps;
  AddStep(steps, "jaw", g.jaw, 1);
  AddStep(steps, "lip_rounding", g.lip_rounding, 1);
  AddStep(steps, "upper_lip", g.lips_upper, 1);
  AddStep(steps, "lower_lip", g.lips_lower, 1);
  AddStep(steps, "lip_corners", g.lip_corners, 1);
  AddStep(steps, "throat", g.throat, 1);
  if (residual_components > 0) steps.push_back({"residual", {}, residual_components});
  return steps;
}

std::vector<GuidedPcaStep> MotherFaceSteps(const FaceMarkerGroups& g) {
  std::set<int> lips;
  for (const auto* group : {&g.lip_rounding, &g.lips_upper, &g.lips_lower, &g.lip_corners}) {
    lips.insert(group->begin(), group->end());
  }
  std::vector<GuidedPcaStep> steps;
  AddStep(steps, "jaw_opening", g.jaw, 1);
  if (!lips.empty()) {
    steps.push_back({"lips", std::vector<int>(lips.begin(), lips.end()), 3});
  }
  AddStep(steps, "jaw_advance", g.jaw, 1);
  steps.push_back({"residual", {}, 1});
  return steps;
}

}  // namespace csw
