#pragma once
// Gap filling by the conditional mean of a multivariate normal: the hand
// markers of a frame, in the forearm frame, are modelled as one Gaussian
// vector (mean, full covariance); the missing markers of a frame are filled
// with their conditional mean given the seen ones,
//   x_h = μ_h + Σ_hv (Σ_vv + ρ I)⁻¹ (x_v − μ_v)
// (ρ: a small ridge in mm², the marker noise). This is the linear-Gaussian
// counterpart of PCA-based marker gap filling. The mean and covariance are
// estimated from training frames that may themselves be incomplete, by the
// EM algorithm for a normal sample with missing values (each E step adds the
// conditional covariance of the missing block, so the covariance is not
// shrunk by the imputation). Occlusions hide markers precisely in some
// postures (a folded finger behind the palm); training on complete frames
// only would hardly ever see those postures.
#include <Eigen/Core>
#include <cstdint>
#include <vector>

#include "core/progress.h"

namespace csw {

struct GaussianFill {
  Eigen::VectorXd mean;        // D = 3 × markers (x0, y0, z0, x1, …)
  Eigen::MatrixXd covariance;  // D × D
  double ridge_mm2 = 0.1;      // ρ above
  int64_t frames = 0;          // training frames used
  int iterations = 0;          // EM iterations run
  bool empty() const { return mean.size() == 0; }
  int markers() const { return static_cast<int>(mean.size() / 3); }
};

struct GaussianFillOptions {
  int max_iterations = 100;
  double tolerance_mm = 0.01;  // stop when no imputed value moves more than this
  double ridge_mm2 = 0.1;
  int min_visible_markers = 1;  // frames with fewer seen markers are not used
};

// data: frames × 3·markers, NaN where a marker is missing (all three
// coordinates of a marker are missing together, or the marker counts as
// missing). Throws InvalidInput when the width is not a multiple of 3, fewer
// than 2 frames are usable, a marker is never seen, or a value is infinite.
// Progress may cancel.
GaussianFill FitGaussianFill(const Eigen::MatrixXd& data, const GaussianFillOptions& options = {},
                             Progress* progress = nullptr);

// Fills frames one at a time, reusing the gain of the previous frame while
// the pattern of seen markers does not change (gaps last many frames).
class GaussianFiller {
 public:
  explicit GaussianFiller(const GaussianFill& fill);
  // markers: 3 × markers, NaN columns missing; fills them in place. Returns
  // the number filled (0 when nothing is seen or nothing is missing).
  int Fill(Eigen::Matrix3Xd* markers);
  // The conditional mean of one marker `marker` (missing from `pattern`,
  // 1 = seen, one entry per marker) given the seen markers of `markers`
  // (3 × markers; only the columns seen in `pattern` are read and must be
  // finite). Reuses the gain of the last pattern. NaN when nothing is seen or
  // `marker` is seen in `pattern`.
  Eigen::Vector3d Predict(const std::vector<uint8_t>& pattern, int marker, const Eigen::Matrix3Xd& markers);

 private:
  void SetPattern(const std::vector<uint8_t>& pattern);

  const GaussianFill& fill_;
  Eigen::MatrixXd precision_;        // (Σ + ρI)⁻¹
  std::vector<uint8_t> pattern_;     // seen markers of the cached gain
  std::vector<int> seen_, missing_;  // coordinate indices
  Eigen::MatrixXd gain_;             // |missing| × |seen|
};

}  // namespace csw
