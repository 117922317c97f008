#include "models/hand_regression.h"

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <cmath>
#include <string>

#include "core/error.h"
#include "models/joint_angles.h"

namespace csw {
namespace {

std::string AngleName(int angle, const std::vector<std::string>& names) {
  return static_cast<size_t>(angle) < names.size() ? names[static_cast<size_t>(angle)]
                                                   : "angle " + std::to_string(angle);
}

// One line for the dropped features: "a, b, cos(c)" (a bare name: both its cos and sin).
std::string DroppedFeaturesWarning(const std::vector<bool>& dropped, int num_angles,
                                   const std::vector<std::string>& names) {
  std::string list;
  int count = 0;
  for (int i = 0; i < num_angles; ++i) {
    const bool c = dropped[static_cast<size_t>(i)], s = dropped[static_cast<size_t>(num_angles + i)];
    if (!c && !s) continue;
    const std::string name = AngleName(i, names);
    list += (count++ ? ", " : "") + (c && s ? name : std::string(c ? "cos(" : "sin(") + name + ")");
  }
  return std::to_string(count) + (count == 1 ? " angle" : " angles") +
         " constant over the training frames, dropped from the regression (the intercept holds them): " + list;
}

}  // namespace

Eigen::RowVectorXd AngleFeatures(const Eigen::VectorXd& angles) {
  const Eigen::Index n = angles.size();
  Eigen::RowVectorXd p(1 + 2 * n);
  p(0) = 1;
  for (Eigen::Index i = 0; i < n; ++i) {
    p(1 + i) = std::cos(angles(i));
    p(1 + n + i) = std::sin(angles(i));
  }
  return p;
}

Eigen::VectorXd HandRegression::Predict(const Eigen::VectorXd& angles) const {
  if (angles.size() != num_angles) {
    throw InvalidInput("hand regression expects " + std::to_string(num_angles) + " angles, got " +
                       std::to_string(angles.size()));
  }
  return (AngleFeatures(angles) * coefficients).transpose();
}

Eigen::MatrixXd HandRegression::PredictFrames(const Eigen::MatrixXd& angles) const {
  if (angles.cols() != num_angles) {
    throw InvalidInput("hand regression expects " + std::to_string(num_angles) + " angles, got " +
                       std::to_string(angles.cols()));
  }
  Eigen::MatrixXd out(angles.rows(), coefficients.cols());
  for (Eigen::Index f = 0; f < angles.rows(); ++f) {
    out.row(f) = AngleFeatures(angles.row(f).transpose()) * coefficients;
  }
  return out;
}

HandRegression FitHandRegression(const Eigen::MatrixXd& angles, const Eigen::MatrixXd& coordinates,
                                 const HandRegressionOptions& options) {
  const Eigen::Index frames = angles.rows();
  const Eigen::Index n = angles.cols();
  const Eigen::Index d = coordinates.cols();
  if (frames < 2) throw InvalidInput("hand regression needs at least 2 frames");
  if (coordinates.rows() != frames) {
    throw InvalidInput("hand regression: " + std::to_string(frames) + " frames of angles but " +
                       std::to_string(coordinates.rows()) + " frames of coordinates");
  }
  if (d == 0) throw InvalidInput("hand regression: no coordinates");
  if (!angles.allFinite() || !coordinates.allFinite()) {
    throw InvalidInput("hand regression: a non-finite angle or coordinate (drop frames with gaps)");
  }
  if (!(options.ridge >= 0) || !std::isfinite(options.ridge)) {
    throw InvalidInput("hand regression: ridge must be a finite value >= 0");
  }

  HandRegression out;
  out.num_angles = static_cast<int>(n);
  const double nf = static_cast<double>(frames);

  // Non-intercept features, centred and scaled to unit RMS.
  Eigen::MatrixXd g(frames, 2 * n);
  g.leftCols(n) = angles.array().cos().matrix();
  g.rightCols(n) = angles.array().sin().matrix();
  const Eigen::RowVectorXd g_mean = g.colwise().mean();
  g.rowwise() -= g_mean;
  std::vector<Eigen::Index> kept;
  std::vector<bool> dropped(static_cast<size_t>(2 * n), false);
  Eigen::VectorXd scale(2 * n);
  for (Eigen::Index j = 0; j < 2 * n; ++j) {
    scale(j) = g.col(j).norm() / std::sqrt(nf);
    if (scale(j) < 1e-9) {
      dropped[static_cast<size_t>(j)] = true;
    } else {
      kept.push_back(j);
    }
  }
  if (static_cast<Eigen::Index>(kept.size()) < 2 * n) {
    out.warnings.push_back(DroppedFeaturesWarning(dropped, static_cast<int>(n), options.angle_names));
  }
  const Eigen::Index k = static_cast<Eigen::Index>(kept.size());
  Eigen::MatrixXd z(frames, k);
  for (Eigen::Index c = 0; c < k; ++c) z.col(c) = g.col(kept[c]) / scale(kept[c]);
  const Eigen::RowVectorXd y_mean = coordinates.colwise().mean();
  const Eigen::MatrixXd yc = coordinates.rowwise() - y_mean;

  Eigen::MatrixXd beta(k, d);
  if (k == 0) {
    out.rank = 0;
  } else if (options.ridge == 0) {
    Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod;
    cod.setThreshold(options.rank_tolerance);
    cod.compute(z);
    out.rank = static_cast<int>(cod.rank());
    beta = cod.solve(yc);
    if (out.rank < k) {
      out.warnings.push_back("features are rank-deficient (rank " + std::to_string(out.rank) + " of " +
                             std::to_string(k) + "): minimum-norm solution");
    }
  } else {
    Eigen::MatrixXd za(frames + k, k);
    za.topRows(frames) = z;
    za.bottomRows(k) = std::sqrt(options.ridge * nf) * Eigen::MatrixXd::Identity(k, k);
    Eigen::MatrixXd ya = Eigen::MatrixXd::Zero(frames + k, d);
    ya.topRows(frames) = yc;
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(za);
    beta = qr.solve(ya);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr_plain(z);
    qr_plain.setThreshold(options.rank_tolerance);
    out.rank = static_cast<int>(qr_plain.rank());
  }

  out.coefficients = Eigen::MatrixXd::Zero(1 + 2 * n, d);
  Eigen::RowVectorXd intercept = y_mean;
  for (Eigen::Index c = 0; c < k; ++c) {
    const Eigen::Index j = kept[c];
    out.coefficients.row(1 + j) = beta.row(c) / scale(j);
    intercept -= g_mean(j) * out.coefficients.row(1 + j);
  }
  out.coefficients.row(0) = intercept;
  const Eigen::MatrixXd fitted = z * beta;
  out.rms_residual = k == 0 ? std::sqrt(yc.squaredNorm() / static_cast<double>(yc.size()))
                            : std::sqrt((yc - fitted).squaredNorm() / static_cast<double>(yc.size()));
  return out;
}

Eigen::VectorXd AnglePca::Angles(const Eigen::VectorXd& params) const {
  if (params.size() != components.cols()) {
    throw InvalidInput("angle PCA has " + std::to_string(components.cols()) + " parameters, got " +
                       std::to_string(params.size()));
  }
  return mean + components * params;
}

Eigen::VectorXd AnglePca::Params(const Eigen::VectorXd& angles) const {
  if (angles.size() != mean.size()) {
    throw InvalidInput("angle PCA has " + std::to_string(mean.size()) + " angles, got " +
                       std::to_string(angles.size()));
  }
  Eigen::VectorXd dev(angles.size());
  for (Eigen::Index i = 0; i < angles.size(); ++i) dev(i) = WrapAngle(angles(i) - mean(i));
  return components.transpose() * dev;
}

AnglePca FitAnglePca(const Eigen::MatrixXd& angles, int components) {
  const Eigen::Index frames = angles.rows();
  const Eigen::Index n = angles.cols();
  if (frames < 2) throw InvalidInput("angle PCA needs at least 2 frames");
  if (n == 0) throw InvalidInput("angle PCA: no angles");
  if (!angles.allFinite()) throw InvalidInput("angle PCA: a non-finite angle");
  if (components < 1 || components > n) {
    throw InvalidInput("angle PCA: asks for " + std::to_string(components) + " components, allowed 1.." +
                       std::to_string(n));
  }
  AnglePca pca;
  pca.mean.resize(n);
  Eigen::MatrixXd dev(frames, n);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double c = angles.col(i).array().cos().mean();
    const double s = angles.col(i).array().sin().mean();
    const double circular = std::atan2(s, c);
    for (Eigen::Index f = 0; f < frames; ++f) dev(f, i) = WrapAngle(angles(f, i) - circular);
    // The wrapped deviations have a small mean of their own: the model's
    // origin is the circular mean moved by it, so the deviations are centred
    // exactly and data on an affine subspace stay on a linear one.
    const double shift = dev.col(i).mean();
    dev.col(i).array() -= shift;
    pca.mean(i) = WrapAngle(circular + shift);
  }
  const Eigen::MatrixXd cov = dev.transpose() * dev / static_cast<double>(frames - 1);
  Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(cov);
  const double total = cov.trace();
  pca.components.resize(n, components);
  pca.variances.resize(components);
  for (int k = 0; k < components; ++k) {
    const Eigen::Index src = n - 1 - k;  // eigenvalues ascend
    Eigen::VectorXd v = eig.eigenvectors().col(src);
    Eigen::Index big = 0;
    v.cwiseAbs().maxCoeff(&big);
    if (v(big) < 0) v = -v;  // deterministic sign
    pca.components.col(k) = v;
    pca.variances(k) = std::max(0.0, eig.eigenvalues()(src));
    pca.variance_explained.push_back(total > 0 ? pca.variances(k) / total : 0.0);
  }
  return pca;
}

Eigen::VectorXd HandShapeModel::Predict(const Eigen::VectorXd& params) const {
  return regression.Predict(angle_pca.Angles(params));
}

HandShapeModel FitHandShapeModel(const Eigen::MatrixXd& angles, const Eigen::MatrixXd& coordinates,
                                 int angle_components, const HandRegressionOptions& options) {
  HandShapeModel model;
  model.angle_pca = FitAnglePca(angles, angle_components);
  Eigen::MatrixXd predicted(angles.rows(), angles.cols());
  for (Eigen::Index f = 0; f < angles.rows(); ++f) {
    predicted.row(f) = model.angle_pca.Angles(model.angle_pca.Params(angles.row(f).transpose())).transpose();
  }
  model.regression = FitHandRegression(predicted, coordinates, options);
  return model;
}

}  // namespace csw
