#pragma once
// DCT gap fill (seed 003 §5.1 "DCT"): penalised least squares in the basis of
// the discrete cosine transform with missing values, D. Garcia, "Robust
// smoothing of gridded data in one and higher dimensions with missing
// values", Comput. Stat. Data Anal. 54 (2010) 1167-1178 (the smoothn
// algorithm), as used for gap filling by G. Wang, D. Garcia, Y. Liu, R. de
// Jeu, A. J. Dolman, "A three-dimensional gap filling method for large
// geophysical datasets", Environ. Model. Softw. 30 (2012) 139-142.
//
// On a window of frames around the gap (each coordinate apart), the fill z
// minimises  ||W^½ (y − z)||² + s ||D z||²,  D the second-difference operator
// with reflective ends, whose eigenvectors are the DCT-II basis: D = Cᵀ Λ C,
// Λ_k = −2 + 2 cos(kπ/N). With all frames valid the solution is direct,
// z = Cᵀ Γ C y, Γ_k = 1 / (1 + s Λ_k²). With missing frames (W = 0 there)
// Garcia's iteration (his eq. 11, over-relaxed by 1.75 as in smoothn)
//     z ← 1.75 · Cᵀ Γ C (W (y − z) + z) − 0.75 · z
// converges to the weighted solution, from a linear interpolation across the
// missing frames (Garcia starts from the nearest valid value and a coarse DCT
// smoothing; in one dimension the linear interpolant is closer and converges
// sooner). The iteration converges slowly when s is small; once it has
// chosen s (at most 100 iterations, smoothn's default), the fill is its
// limit, the solution of (W + s DᵀD) z = W y, computed directly (a dense
// LDLᵀ of the window, Eigen). s is chosen by minimising Garcia's GCV score
//     GCV(s) = (RSS / n_valid) / (1 − tr H / N)²,  tr H = Σ_k Γ_k,
// re-estimated at iterations 1, 2, 4, 8, … as in smoothn, over the bounds
// smoothn derives from leverages h ∈ [1e-6, 0.99] (capped at s = 1e12).
//
// The DCT is a precomputed orthonormal DCT-II matrix C (N × N, cached per
// window length): windows are a few tens to a few hundred frames, where a
// matrix product (O(N²), vectorised by Eigen, exact to rounding) costs less
// than an O(N log n) FFT-based transform's set-up and needs no FFT library.
#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "analysis/cleaning/fill.h"

namespace csw::cleaning {

struct DctFillOptions {
  // Consecutive valid frames needed on each side of the gap (as the spline fill).
  int side_frames = 5;
  // Frames taken on each side of the gap for the fit (valid or not).
  int context_frames = 30;
  int64_t max_gap_frames = 0;  // 0 = no limit of the method's own
  // Longest window (gap + context) the matrix DCT accepts: N × N doubles
  // (1,000 frames: 8 MB); longer gaps are refused with a reason.
  int64_t max_window_frames = 1000;
  double smoothing = 0.0;  // fixed s > 0, or 0 to choose s by GCV
  // Garcia's iteration (smoothn's defaults: at most 100 iterations); it
  // chooses s, and the fill is then the iteration's limit at that s.
  int max_iterations = 100;
  // Stop when no value of the window moves by more than this (mm) in one iteration.
  double tolerance_mm = 1e-3;
  std::string Check() const;  // "" when valid, else the reason
};

// Orthonormal DCT-II matrix: C(k, j) = a_k cos(π (2j + 1) k / (2N)),
// a_0 = √(1/N), a_k = √(2/N); Cᵀ is the DCT-III (its inverse).
Eigen::MatrixXd DctMatrix(int n);

struct DctSmoothResult {
  Eigen::MatrixXd z;    // N × columns
  Eigen::VectorXd s;    // per column: the smoothing parameter
  Eigen::VectorXd gcv;  // per column: the GCV score at s
  Eigen::VectorXi iterations;
  bool converged = true;  // every column met the tolerance
};

// Garcia's DCT-PLS smoothing of y (N × columns, values at weight-0 frames
// ignored) with weights w (N, ≥ 0; 0 = missing). smoothing > 0: fixed s;
// 0: s by GCV per column. Throws InvalidInput when N > 4096 (the matrix DCT),
// when no frame has weight > 0,
// when the sizes disagree or an option is out of range.
// With missing frames, the returned z is the limit of the iteration at the
// final s (solved directly: (W + s DᵀD) z = W y), so it does not depend on
// how far the iteration ran; `iterations` and `converged` say how the
// iteration that chose s ended.
DctSmoothResult DctSmooth(const Eigen::MatrixXd& y, const Eigen::VectorXd& w, double smoothing = 0.0,
                          int max_iterations = 100, double tolerance = 1e-3);

class DctFiller : public GapFiller {
 public:
  explicit DctFiller(const DctFillOptions& options = {});  // throws InvalidInput on bad options
  std::string name() const override { return "dct"; }
  bool CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const override;
  bool Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const override;
  const DctFillOptions& options() const { return options_; }

 private:
  DctFillOptions options_;
};

}  // namespace csw::cleaning
