#include "models/pca.h"

#include <Eigen/SVD>
#include <algorithm>
#include <string>

#include "core/error.h"

namespace csw {
namespace {

// All components (up to min(dims, rows - 1)), sign-fixed.
Pca FitAll(const Eigen::MatrixXd& x) {
  if (x.rows() < 2 || x.cols() < 1) {
    throw InvalidInput("PCA: need at least 2 samples and 1 dimension, got " + std::to_string(x.rows()) + " x " +
                       std::to_string(x.cols()));
  }
  if (!x.allFinite()) throw InvalidInput("PCA: samples contain missing or non-finite values");
  Pca pca;
  pca.mean = x.colwise().mean().transpose();
  const Eigen::MatrixXd centred = x.rowwise() - pca.mean.transpose();
  Eigen::BDCSVD<Eigen::MatrixXd> svd(centred, Eigen::ComputeThinV);
  const double denom = static_cast<double>(x.rows() - 1);
  const Eigen::Index k = std::min<Eigen::Index>(x.cols(), x.rows() - 1);
  pca.components = svd.matrixV().leftCols(k);
  pca.variances = svd.singularValues().head(k).array().square() / denom;
  pca.total_variance = centred.array().square().sum() / denom;
  for (Eigen::Index c = 0; c < k; ++c) {
    Eigen::Index arg = 0;
    pca.components.col(c).cwiseAbs().maxCoeff(&arg);
    if (pca.components(arg, c) < 0.0) pca.components.col(c) *= -1.0;
  }
  pca.explained_fraction =
      pca.total_variance > 0.0 ? Eigen::VectorXd(pca.variances / pca.total_variance) : Eigen::VectorXd::Zero(k);
  return pca;
}

void Truncate(Pca* pca, Eigen::Index k) {
  pca->components = pca->components.leftCols(k).eval();
  pca->variances = pca->variances.head(k).eval();
  pca->explained_fraction = pca->explained_fraction.head(k).eval();
}

}  // namespace

Eigen::MatrixXd Pca::Project(const Eigen::MatrixXd& samples_rows) const {
  if (samples_rows.cols() != mean.size()) {
    throw InvalidInput("PCA project: samples have " + std::to_string(samples_rows.cols()) + " dims, model has " +
                       std::to_string(mean.size()));
  }
  return (samples_rows.rowwise() - mean.transpose()) * components;
}

Eigen::MatrixXd Pca::Reconstruct(const Eigen::MatrixXd& scores_rows) const {
  if (scores_rows.cols() != components.cols()) {
    throw InvalidInput("PCA reconstruct: scores have " + std::to_string(scores_rows.cols()) +
                       " components, model has " + std::to_string(components.cols()));
  }
  return (scores_rows * components.transpose()).rowwise() + mean.transpose();
}

Pca FitPca(const Eigen::MatrixXd& samples_rows, int components) {
  Pca pca = FitAll(samples_rows);
  if (components > 0 && components < pca.count()) Truncate(&pca, components);
  return pca;
}

Pca FitPcaVariance(const Eigen::MatrixXd& samples_rows, double variance_fraction) {
  if (!(variance_fraction > 0.0 && variance_fraction <= 1.0)) {
    throw InvalidInput("PCA: variance fraction must be in (0, 1]");
  }
  Pca pca = FitAll(samples_rows);
  double cumulated = 0.0;
  Eigen::Index k = 0;
  while (k < pca.count() && cumulated < variance_fraction - 1e-12) cumulated += pca.explained_fraction(k++);
  Truncate(&pca, std::max<Eigen::Index>(k, 1));
  return pca;
}

}  // namespace csw
