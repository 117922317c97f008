#pragma once
// Posterior landmarks of a key (issue 11, scope item 5b; docs/analysis-phasing.md):
// in the gestural score (per-frame class posteriors of the shape or of the
// placement stream), the onset is when the key's class starts to dominate
// (its posterior exceeds every other class), the target when its posterior
// peaks. Pure computation; bad arguments throw csw::InvalidInput.
#include <Eigen/Core>
#include <string>

namespace csw::phasing {

struct PosteriorLandmarkOptions {
  // A saturated posterior (a flat top near its maximum) peaks at the centre of
  // the run of frames within this tolerance of the maximum around the first
  // maximum; 0 = the first maximum itself.
  double plateau_tolerance = 0.01;
  std::string Check() const;  // "" when valid, else the reason
};

struct PosteriorLandmarks {
  bool found = false;                  // the class dominates at its peak inside the window
  double onset_s = 0.0;                // dominance starts (linear interpolation of the margin's zero crossing)
  double target_s = 0.0;               // posterior peak (plateau centre)
  double peak = 0.0;                   // posterior at the peak
  bool onset_at_window_start = false;  // dominance already held at the window's first frame
  std::string reason;                  // why not found ("" otherwise)
};

// posteriors: frames × classes, row f at start_s + f / rate_hz, rows of NaN =
// not scored. The class `cls` is looked at in the frames whose times lie in
// [from_s, to_s] (e.g. the previous key's target to the next key's target).
PosteriorLandmarks FindPosteriorLandmarks(const Eigen::MatrixXd& posteriors, double rate_hz, double start_s, int cls,
                                          double from_s, double to_s, const PosteriorLandmarkOptions& options = {});

}  // namespace csw::phasing
