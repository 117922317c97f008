#pragma once
// Gap filling: the interface every fill method implements (spline, DCT here;
// rigid cluster and pattern fills beside them) and the driver that fills the
// gaps of a take with a list of methods.
//
// Semantics of FillGaps (issue 12, "Fills"):
//  - the gaps are those of `in` (FindAllGaps: maximal runs of missing frames
//    per marker, leading/trailing flagged);
//  - methods are tried in the order given; each gap takes the FIRST method
//    whose CanFill says yes and whose Fill succeeds; a method that cannot fill
//    a gap (or fails) passes it on to the next;
//  - max_gap_frames (0 = no limit) applies to every method: longer gaps are
//    not offered to any method and are listed as unfilled;
//  - fills read ONLY `in`: a filled gap never feeds the fill of another gap
//    (the result does not depend on the order of the gaps, and every fill is
//    from measured data only); `out` is a copy of `in` with the filled gaps'
//    samples written, everything else bit-identical; `in` is never touched;
//  - every gap ends up in exactly one of report.filled (with the method and
//    its parameters: the take version's provenance) or report.unfilled (with
//    the reason of every method, "spline: …; dct: …").
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "analysis/cleaning/gaps.h"
#include "core/progress.h"
#include "core/take.h"

namespace csw::cleaning {

// How one gap was filled: the provenance of a filled gap.
struct FillRecord {
  int marker = 0;
  int64_t start = 0;
  int64_t length = 0;
  std::string method;      // GapFiller::name(): "spline", "dct", "rigid", "pattern", …
  std::string parameters;  // human-readable key=value list, e.g. "kind=smoothing, order=quintic, gcv_p=…, before=30,
                           // after=30"
};

// A fill method. Implementations must be safe to call concurrently on
// different gaps (const, no shared mutable state), so a job may fill markers
// in parallel.
class GapFiller {
 public:
  virtual ~GapFiller();
  // Short method name recorded in FillRecord::method ("spline", "dct", …).
  virtual std::string name() const = 0;
  // Whether this method can fill this gap of `in`; when it cannot, *why_not
  // (may be null) says why, e.g. "leading gap: no valid frame before it" or
  // "3 valid frames after the gap, 5 needed".
  virtual bool CanFill(const MarkerArray& in, const Gap& gap, std::string* why_not) const = 0;
  // Fills the gap: writes the gap's frames [gap.start, gap.end()) of column
  // gap.marker into *out (a copy of `in`, same shape), reading only `in`, and
  // writes nothing else. Fills record->method/parameters (marker, start and
  // length are set by the caller too). Returns false when the fill failed
  // (the driver then restores the gap and tries the next method).
  virtual bool Fill(const MarkerArray& in, const Gap& gap, MarkerArray* out, FillRecord* record) const = 0;
};

struct FillReport {
  std::vector<FillRecord> filled;                     // in gap order (marker, then time)
  std::vector<std::pair<Gap, std::string>> unfilled;  // gap, reasons ("spline: …; dct: …")
  int64_t filled_samples() const;                     // frames written over all filled gaps
  int64_t unfilled_samples() const;
};

// A plausibility check applied to every fill before it is accepted (a fill
// that fails it is undone and the gap offered to the next method): the fill's
// peak frame-to-frame speed, joins to the measured edge samples included, must
// not exceed speed_factor × the largest of (a) the marker's peak measured speed
// within context_frames on each side of the gap, (b) the mean speed needed to
// cross the gap (edge to edge), (c) floor_mm_per_frame. A smoothing spline or
// DCT bridging a long gap after a fast movement can overshoot by hundreds of
// millimetres (seen on virtual-cuer hand gaps of 40-60 frames): such a fill is
// refused rather than written. The fill must also stay near the measured
// samples of the context: no filled sample may lie farther outside their
// bounding box than box_margin × the box's diagonal (or box_floor_mm, when
// larger). speed_factor 0 turns both checks off.
struct FillGuardOptions {
  double speed_factor = 2.0;
  int context_frames = 30;
  double floor_mm_per_frame = 1.0;
  double box_margin = 0.25;
  double box_floor_mm = 10.0;
};
// "" when the filled gap in `out` passes the check, else the reason.
std::string CheckFillSpeed(const MarkerArray& in, const MarkerArray& out, const Gap& gap,
                           const FillGuardOptions& guard);

// Fills the gaps of `in` into *out (see the semantics above). Throws
// InvalidInput when out is null or is `in`, or when a method is null.
// progress (optional) is updated as "fill gaps" and may cancel (csw::Cancelled).
FillReport FillGaps(const MarkerArray& in, const std::vector<const GapFiller*>& methods, int64_t max_gap_frames,
                    MarkerArray* out, Progress* progress = nullptr, const FillGuardOptions& guard = {});

// For the gap report: which methods can handle each gap (no filling).
struct GapMethods {
  Gap gap;
  std::vector<std::string> can_fill;                        // method names, in the order given
  std::vector<std::pair<std::string, std::string>> cannot;  // method name, why not
  bool too_long = false;                                    // longer than max_gap_frames (no method asked)
};
std::vector<GapMethods> AssessGaps(const MarkerArray& in, const std::vector<Gap>& gaps,
                                   const std::vector<const GapFiller*>& methods, int64_t max_gap_frames);

// Helpers for methods that need the marker's own data around the gap: the
// number of consecutive valid frames of the gap's marker just before the gap
// (0 for a leading gap) and just after it (0 for a trailing gap).
// Counting stops at `limit`.
int64_t ValidFramesBefore(const MarkerArray& in, const Gap& gap, int64_t limit = INT64_MAX);
int64_t ValidFramesAfter(const MarkerArray& in, const Gap& gap, int64_t limit = INT64_MAX);
// "" when the gap has at least `min_frames` consecutive valid frames on each
// side, else the reason ("leading gap: no valid frame before it", "3 valid
// frames after the gap, 5 needed").
std::string CheckSides(const MarkerArray& in, const Gap& gap, int64_t min_frames);

}  // namespace csw::cleaning
