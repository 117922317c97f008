#pragma once
// Principal component analysis of row samples (one observation per row), e.g.
// marker coordinates per frame or the 6 rigid-motion parameters per frame
// (motion control parameters nmF / nmH are FitPca of RigidSeries::ValidParameters()).
#include <Eigen/Core>

namespace csw {

struct Pca {
  Eigen::VectorXd mean;                // dims
  Eigen::MatrixXd components;          // dims x k, orthonormal columns, by decreasing variance
  Eigen::VectorXd variances;           // k, sample variance (divisor n - 1) along each component
  Eigen::VectorXd explained_fraction;  // k, variances / total_variance
  double total_variance = 0.0;         // sum of the variances of all dims

  int dims() const { return static_cast<int>(mean.size()); }
  int count() const { return static_cast<int>(components.cols()); }
  // Scores: rows x k.
  Eigen::MatrixXd Project(const Eigen::MatrixXd& samples_rows) const;
  // Back to data space: rows x dims.
  Eigen::MatrixXd Reconstruct(const Eigen::MatrixXd& scores_rows) const;
};

// Keeps `components` components (<= 0 or more than available: all, i.e.
// min(dims, rows - 1)). Each component's sign is fixed so that its entry of
// largest magnitude is positive (deterministic). Throws InvalidInput with
// fewer than 2 rows, no columns, or non-finite values.
Pca FitPca(const Eigen::MatrixXd& samples_rows, int components);
// Keeps the fewest components whose cumulated explained fraction reaches
// variance_fraction (in (0, 1]).
Pca FitPcaVariance(const Eigen::MatrixXd& samples_rows, double variance_fraction);

}  // namespace csw
