#pragma once
// Key target times from kinematics (issue 11, scope item 4: the target frame
// of every aligned key). DecodeAligned places each key's segment where its
// posteriors dominate; the posteriors switch half-way through a movement and
// saturate over a hold, so the frames inside a segment do not tell when the
// hand arrived. Here each component is timed on its own:
//
// 1. Component segments. The shape labels of the expected keys, successive
//    repeats merged, are aligned to the shape posteriors alone (AlignComponent);
//    likewise the placements. A component that does not change between two keys
//    has one segment for both (the hand does not move for it).
// 2. Rough target: in the component's segment, the first frame whose distance
//    to the class mean (the square root of minus GaussianClassifier::Closeness:
//    the RMS standardised distance) comes within arrival_tolerance of the
//    segment's range above its smallest value. For the placement the distance
//    is that of the key's own finger tip (index for the model's index shapes,
//    middle finger otherwise).
// 3. Kinematic target: the movement into the target is fitted by superposed
//    minimum-jerk gestures (phasing::EstimateMovement, three gestures: into the
//    previous target, this one and the next) around the rough targets: for the
//    shape the five distal finger markers in the palm's frame
//    (HandFeatures::tips_in_palm, curved paths; the seven distances when the
//    palm cannot be fitted or shape_on_tips is off), the key's finger tip in
//    the head frame for the placement. A distance changes at second order
//    near full extension (it is flat in the joint angles there), so a fit on
//    the distances hardly sees a finger start to bend or finish stretching;
//    the tips move at first order with every joint (virtual cuer, 236 keys:
//    mean aligned error 27.0 -> 22.1 ms on model-filled takes,
//    docs/analysis.md). The fit window reaches back at most max_movement_s
//    before the rough target: a longer stretch since the previous change
//    holds the small re-realisations of held keys, which the three-gesture
//    fit does not model and would stretch a gesture over. A component's last
//    movement is fitted with the gesture before it only, the data running
//    0.3 s into the hold after its rough target (a made-up next gesture took
//    the slow tail of final returns to rest and ended them 40-60 ms early:
//    virtual cuer, clean markers, 145 -> 151 of 163 reached keys within 40
//    ms). When the fit says the component moved, its fitted onset and target
//    replace the rough time.
//
// A key held from the take's first frame (the initial rest) has no movement
// into it: its target is the instant the hand leaves it, the earliest fitted
// onset of its components' next movements, not before the first frame (the
// rough time when none is fitted). A key's target (target_frame, target_s) is
// its shape target when the shape changes, else its placement target — the convention of the `keys`
// label tier (targets at the shape targets, placement targets in a tier of
// their own). A key where neither changes (a repeated code) shows no movement
// and no posterior change: its target is interpolated by key index between the
// targets of the nearest keys with a change (interpolate_repeats; after the
// last change, the take's mean interval between changed keys is added; off:
// the joint arrival of DecodeAligned, which sits at one end of the repeats'
// shared stretch, 300 ms off on average on the virtual cuer).
//
// Speech anchors (speech_anchors, when the expected keys carry their acoustic
// onset A1, ExpectedKey::anchor_s): the hand's targets follow the speech at a
// cuer's own lag (../shared/docs/cued-speech.md, "Timing"), which the take
// itself measures. For each component, the lag of its changing targets from
// their A1 (median over the take's keys, separately for vowel-anchored keys
// and the others when each has at least anchor_min_keys, else pooled) and its
// spread (1.4826 × the median absolute deviation) are estimated; a target more
// than max(anchor_outlier_sd × spread, anchor_outlier_floor_s) from A1 + lag
// (a segment or a fit that landed on a neighbouring movement) is replaced by
// A1 + lag — unless it is a fitted target at which the hand is in the key's
// own class (anchor_keep_in_class: the component posterior of the key's label
// at least anchor_in_class_posterior) within anchor_in_class_max_s of A1 +
// lag: a cuer's lag can stray beyond the gate on one key, and a fit that
// ends where the hand holds the key found its movement (virtual cuer,
// model-filled: 140 -> 143 of 163 reached keys within 40 ms, docs/analysis.md)
// — and so is a target further than anchor_outlier_floor_s from its
// A1 + lag and nearer the previous or next key's A1 + lag than its own
// (anchor_nearest: it sits on a neighbour's movement however wide the spread;
// on the virtual cuer's spline/DCT-filled takes this took the worst aligned
// error from 290 to 152 ms), and a repeated key takes A1 +
// the shape lag instead of the interpolation above. Nothing is assumed about
// the lag itself: another cuer's or lab's timing gives other lags. A fitted
// target that stays (not an outlier) is combined with its A1 + lag by inverse
// variance (CombineWithSpeech): the fit weighs 1 / (anchor_fit_sd_factor ×
// its standard error)², A1 + lag 1 / spread², so a fit the data determine
// well keeps its time and one they hardly determine (overlapping gestures
// trading parts of their movements) leans on the speech. Without anchors, as
// before.
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "analysis/keys/hand_features.h"
#include "analysis/keys/key_decoding.h"
#include "analysis/keys/key_model.h"
#include "analysis/phasing/movement_timing.h"

namespace csw::keys {

struct KeyTimingOptions {
  DecodeOptions decode;
  phasing::MovementFitOptions shape_fit = ShapeFitDefaults();
  phasing::MovementFitOptions placement_fit;
  double arrival_tolerance = 0.05;       // rough target: fraction of the segment's distance range
  double window_margin_s = 0.1;          // component segments: how far outside their keys' joint segments
  bool kinematic = true;                 // false: rough targets only
  bool shape_on_tips = true;             // shape movements fitted on HandFeatures::tips_in_palm when known
  double max_movement_s = 0.8;           // fit window: at most this far back before the rough target
  int max_refits = 3;                    // refits around a fitted target that hit its tolerance
  int refinement_passes = 0;             // refits with the neighbours' fitted targets
  bool interpolate_repeats = true;       // repeated keys: target interpolated between their neighbours'
  bool speech_anchors = true;            // use ExpectedKey::anchor_s where given (see above)
  double anchor_outlier_sd = 3.0;        // a target further than this many spreads from A1 + lag is an outlier
  double anchor_outlier_floor_s = 0.08;  // ... and further than this
  int anchor_min_keys = 3;               // changing targets needed to estimate a lag
  bool anchor_nearest = true;            // ... and so is one nearer a neighbour's A1 + lag than its own
  // A kept fitted target combined with A1 + lag (CombineWithSpeech); the
  // fit's curvature standard error is multiplied by this (it understates the
  // error of overlapping fits: docs/analysis.md); 0 = fits kept as they are.
  double anchor_fit_sd_factor = 4.0;
  // A fitted target beyond the gate is kept when the hand is in the key's own
  // class there (its component posterior at least anchor_in_class_posterior)
  // and it is within anchor_in_class_max_s of A1 + lag (see above).
  bool anchor_keep_in_class = true;
  double anchor_in_class_posterior = 0.5;
  double anchor_in_class_max_s = 0.2;
  std::string Check() const;  // "" when valid, else the reason
  static phasing::MovementFitOptions ShapeFitDefaults();
};

// Timing of one component of one key.
struct ComponentTiming {
  bool changes = false;                        // differs from the previous key's (true for the first key)
  bool kinematic = false;                      // onset and target from the movement fit
  int64_t segment_start = 0, segment_end = 0;  // the component's aligned segment [start, end)
  int64_t rough_frame = 0;                     // arrival in that segment
  double onset_s = 0.0;                        // movement onset (NaN unless kinematic)
  double target_s = 0.0;                       // target time: kinematic, else rough
  bool from_speech = false;                    // target replaced by A1 + lag (speech anchors)
  double target_sd_s = std::numeric_limits<double>::quiet_NaN();  // the fit's standard error (NaN: no fit)
  bool speech_weighted = false;                                   // target_s combined with A1 + lag (CombineWithSpeech)
};

struct TimedKey {
  DecodedKey key;  // segment from DecodeAligned; target frames = rounded times below
  ComponentTiming shape, placement;
  double target_s = 0.0;
  bool target_from_speech = false;  // a repeated key timed by its A1 + the shape lag
};

// The inverse-variance combination of a fitted target time fit_s (standard
// error fit_sd_s, multiplied by sd_factor) with the speech's expectation
// anchor_s (spread spread_s): (fit / (k·sd)² + anchor / spread²) / (1 / (k·sd)²
// + 1 / spread²). fit_s unchanged when sd_factor is 0, fit_sd_s is not finite
// or spread_s is not > 0; anchor_s when fit_sd_s is infinite.
double CombineWithSpeech(double fit_s, double fit_sd_s, double anchor_s, double spread_s, double sd_factor);

// The speech anchors step of DecodeAlignedTimed (above), on keys already timed
// kinematically: outlying component targets replaced by A1 + the take's lag,
// kept ones combined with it, repeated keys timed from it. shape_post and
// place_post (frames × classes, frame f at f / rate_hz) serve the in-class
// test. A neighbour without A1 (a rest: the return to rest follows no
// syllable) counts in the nearer-neighbour test with its own timed target
// when its component changes: a fit that landed on the final return to rest
// is replaced (virtual cuer, hand 0.75 times the size, spline/DCT-filled
// takes: worst key 273 -> 190 ms). Keys and expected keys pair by index.
void AnchorToSpeech(std::vector<TimedKey>& keys, const std::vector<ExpectedKey>& expected,
                    const KeyTimingOptions& options, const Eigen::MatrixXd& shape_post,
                    const Eigen::MatrixXd& place_post, double rate_hz);

// Aligned decoding with kinematic target times. Times are seconds from the
// take's first frame (frame f at f / rate_hz). Throws InvalidInput as
// DecodeAligned, for bad options, or when the features and posteriors differ
// in length.
std::vector<TimedKey> DecodeAlignedTimed(const KeyModel& model, const HandFeatures& features,
                                         const KeyPosteriors& posteriors, const std::vector<ExpectedKey>& expected,
                                         double rate_hz, const KeyTimingOptions& options = {});

}  // namespace csw::keys
