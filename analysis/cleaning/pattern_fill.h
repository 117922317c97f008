#pragma once
// Pattern fill (Vicon Nexus "Pattern Fill"): the gap of marker m is filled with the trajectory of
// a donor marker d over the gap, plus an offset that joins m at both ends of the gap,
//   m(f) = d(f) + o(f),  o blended linearly from o_before to o_after,
// so a marker that moves as the donor plus a constant or linearly drifting offset is reproduced
// exactly. o_before / o_after are the mean of m − d over `offset_frames` frames next to each end,
// anchored at the centre of those frames (offset_frames = 1: the end samples, as Nexus does;
// more frames average the noise of the end samples out while keeping a linear drift exact).
//
// The donor is named by the caller, or chosen among candidate columns (the job layer passes the
// markers of the same segment or cluster) as the one whose velocity correlates best with m's over
// a window on both sides of the gap: r = Σ (v_m − v̄_m)·(v_d − v̄_d) / sqrt(Σ|v_m − v̄_m|² Σ|v_d − v̄_d|²),
// the Pearson coefficient of the stacked x, y, z velocity components (each centred), velocities
// from frame differences that do not cross a gap. A donor must be visible over the whole gap and
// at the frames that anchor the offsets.
#include <map>
#include <string>
#include <vector>

#include "analysis/cleaning/fill.h"
#include "analysis/cleaning/gaps.h"
#include "core/take.h"

namespace csw::cleaning {

// Defaults measured on virtual-cuer takes (docs/cleaning-structfill.md): the error hardly moves
// with window 30-120 or lag 1-4; offset_frames 1 is best for hand markers (their offsets change
// quickly), 2-4 a little better for slow face markers.
struct PatternFillOptions {
  int window = 60;               // frames each side of the gap whose velocities enter the correlation
  int velocity_lag = 2;          // velocity = x(f) − x(f − lag)
  int min_samples = 8;           // velocity samples (both sides together) a donor score needs
  int offset_frames = 1;         // frames next to each end averaged for the offsets (1 = Nexus: the end samples)
  double min_correlation = 0.0;  // an automatically chosen donor needs at least this score
};

struct DonorScore {
  int donor = -1;
  double correlation = 0.0;  // NaN when not scored
  int64_t samples = 0;       // velocity samples used
  std::string why_not;       // "" when the donor can fill the gap
};

// Scores every candidate (columns other than gap.marker; gap.marker itself is skipped) and returns
// them best first: usable donors by decreasing correlation, then the unusable ones with why_not.
std::vector<DonorScore> ScoreDonors(const MarkerArray& in, const Gap& gap, const std::vector<int>& candidates,
                                    const PatternFillOptions& options = {});

// Why `donor` cannot fill the gap ("" when it can): not visible over the gap or at the anchors.
std::string PatternFillCheck(const MarkerArray& in, const Gap& gap, int donor, const PatternFillOptions& options = {});

// Writes the gap frames of gap.marker into *out (same shape as in) from `donor`. Returns "" on
// success, else the reason (and *out is untouched).
std::string PatternFillGap(const MarkerArray& in, const Gap& gap, int donor, MarkerArray* out,
                           const PatternFillOptions& options = {});

// The GapFiller for the FillGaps driver ("pattern"). Each marker of a candidate group gets the
// other markers of its group(s) as automatic donor candidates; a donor named for a marker is used
// alone (no fallback to automatic choice when it cannot fill).
class PatternFiller : public GapFiller {
 public:
  explicit PatternFiller(std::vector<std::vector<int>> candidate_groups, PatternFillOptions options = {},
                         std::map<int, int> named_donors = {});

  std::string name() const override { return "pattern"; }
  bool CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const override;
  bool Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const override;

  // The automatic candidates of a marker (union of its groups, without itself).
  std::vector<int> Candidates(int marker) const;
  // The donor the filler would use for the gap, or -1 with why_not; *score is its score.
  int ChooseDonor(const MarkerArray& in, const Gap& gap, DonorScore* score, std::string* why_not) const;

 private:
  std::vector<std::vector<int>> groups_;
  PatternFillOptions options_;
  std::map<int, int> named_;
};

}  // namespace csw::cleaning
