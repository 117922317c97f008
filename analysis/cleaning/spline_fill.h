#pragma once
// Spline gap fills (Nexus' "Woltring fill", MoCap Toolbox mcfillgaps):
//
//  - INTERPOLATING cubic or quintic spline through the `side_frames` valid
//    frames on each side of the gap (x, y, z alike; each coordinate is an
//    independent spline on the same knots). The spline is the B-spline
//    interpolant with knots placed by knot averaging (de Boor 1978, ch. XIII;
//    Piegl & Tiller, The NURBS Book, 2nd ed. 1997, §9.2.1), computed by
//    Eigen's Splines module. Its spline space contains every polynomial of the
//    spline's degree, so a polynomial trajectory of degree ≤ 3 (cubic) or ≤ 5
//    (quintic) is reproduced exactly; "natural" end conditions (zero second,
//    resp. third and fourth, derivatives at the ends) would not do that, and
//    with only a few frames on each side the ends matter.
//
//  - SMOOTHING spline whose smoothing parameter is chosen by generalised
//    cross-validation (Craven & Wahba 1979, Numer. Math. 31:377-403; Woltring
//    1986, Adv. Eng. Software 8:104-113, GCVSPL), so the measurement noise of
//    the frames around the gap is not copied into the fill. Implemented as the
//    discrete penalised least-squares spline (Whittaker 1923; Eilers 2003,
//    Anal. Chem. 75:3631-3636, "A perfect smoother") on a window of uniformly
//    sampled frames around the gap:
//        minimise  Σ_i w_i (y_i − z_i)² + p Σ_i (Δ^m z)_i²,   w_i = 0 at missing frames,
//    i.e. z = (W + p DᵀD)⁻¹ W y with D the m-th difference matrix. Inside the
//    gap z is a discrete spline of degree 2m − 1 (m = 3: quintic, Woltring's
//    usual choice; m = 2: cubic), the discrete counterpart of GCVSPL's natural
//    smoothing spline of order 2m. p minimises
//        GCV(p) = (RSS(p) / n) / (1 − tr H(p) / n)²,   H(p) = (W + p DᵀD)⁻¹ W,
//    n = valid frames in the window (by default one p for the three
//    coordinates, minimising the GCV of the pooled residuals); tr H is the sum of the diagonal of
//    (W + p DᵀD)⁻¹ over the valid frames, computed exactly from the banded
//    LDLᵀ factor by the Takahashi / Hutchinson & de Hoog (1985, Numer. Math.
//    47:99-106) recursion in O(N m²). The search is a grid over log10 p
//    (one-decade steps) refined by one parabolic step through the best grid
//    point and its neighbours.
#include <Eigen/Core>
#include <cstdint>
#include <string>

#include "analysis/cleaning/fill.h"

namespace csw::cleaning {

enum class SplineKind { kCubic, kQuintic, kSmoothing };
const char* SplineKindName(SplineKind kind);  // "cubic", "quintic", "smoothing"

struct SplineFillOptions {
  SplineKind kind = SplineKind::kSmoothing;
  // Consecutive valid frames needed on each side of the gap; the interpolating
  // splines interpolate exactly these frames (side_frames + side_frames). 5 by
  // default: the quintic needs 6 frames at least and each side should pin
  // position, velocity and acceleration with some redundancy (≥ 3 frames),
  // while 5 frames at 100-120 Hz (40-50 ms) stay well inside one cueing
  // movement (300-400 ms), over which a low-degree polynomial follows the
  // motion; more frames reach into motion the spline cannot follow.
  int side_frames = 5;
  // Gaps longer than this are refused (0 = no limit of the method's own; the
  // FillGaps maximum applies anyway).
  int64_t max_gap_frames = 0;
  // Smoothing spline: order m of the difference penalty (2 = cubic, 3 = quintic).
  int order = 3;
  // Smoothing spline: frames taken on each side of the gap for the fit (valid
  // or not; missing frames get weight 0). Must be ≥ side_frames.
  int context_frames = 30;
  // Smoothing spline: fixed p > 0, or 0 to choose p by GCV.
  double smoothing = 0.0;
  // Smoothing spline: each coordinate is always fitted apart; p is chosen
  // either once for the marker's three coordinates (false, the default: the
  // GCV of the pooled residuals, as GCVSPL does for its K data columns sampled
  // at the same points; steadier on short windows) or for each coordinate
  // apart (true).
  bool per_coordinate = false;
  std::string Check() const;  // "" when valid, else the reason
};

// The smoothing fit of one window (exposed for tests and reuse).
struct PenalisedFit {
  Eigen::MatrixXd z;      // N × columns: the smoothed (and filled) signal
  Eigen::VectorXd p;      // per column: the smoothing parameter used
  Eigen::VectorXd trace;  // per column: tr H(p) (effective degrees of freedom)
  Eigen::VectorXd gcv;    // per column: GCV score at p
  int64_t valid = 0;      // n: frames with weight > 0
};

// Penalised least squares on a uniform grid: y is N × columns (values at
// weight-0 frames are ignored), w N weights (0 or 1 for missing/valid; any
// w ≥ 0 works), order m ≥ 1. smoothing > 0: that p for every column; 0: p by
// GCV for each column. Throws InvalidInput when fewer than m + 1 frames have
// weight > 0 or the sizes disagree.
// joint: one p for all columns, minimising the GCV of the pooled residuals.
PenalisedFit PenalisedSmooth(const Eigen::MatrixXd& y, const Eigen::VectorXd& w, int order, double smoothing = 0.0,
                             bool joint = false);

class SplineFiller : public GapFiller {
 public:
  explicit SplineFiller(const SplineFillOptions& options = {});  // throws InvalidInput on bad options
  std::string name() const override { return "spline"; }
  bool CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const override;
  bool Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const override;
  const SplineFillOptions& options() const { return options_; }

 private:
  bool FillInterpolating(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const;
  bool FillSmoothing(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const;
  SplineFillOptions options_;
};

}  // namespace csw::cleaning
