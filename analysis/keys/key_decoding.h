#pragma once
// From the gestural score (key_model.h) to keys: gesture extents, free and
// aligned sequence decoding, and their scoring.
//
// Free decoding is JOINT: one Viterbi pass over the 54 keys PS (placement ×
// shape), the emission of key PS at frame t being log P(shape S | t) + log
// P(placement P | t) (each floored at DecodeOptions::floor), with a minimum key
// duration (an explicit-duration chain: a key can only be left after
// min_key_ms) and a constant log penalty per key change. Decoding jointly makes
// the slight asynchrony of the shape and placement gestures (the shape leads
// by some tens of ms) one key boundary instead of a short spurious key.
//
// Aligned decoding: the expected key sequence split the frames into one
// contiguous segment per key, in order, each at least aligned_min_key_ms long,
// maximising the same emission sum (dynamic programming, O(keys × frames)).
//
// Target frame of a decoded key: in its segment, the first frame whose
// closeness comes within arrival_tolerance × (best − worst closeness in the
// segment) of the best, i.e. where the features arrive near their closest
// approach to the key's class means (closeness, GaussianClassifier::Closeness: minus the mean
// squared standardised distance; posteriors saturate at 1 over the whole
// hold). The hand arrives, then holds: the best frame of a hold is noise, its
// first frame is the target. Joint closeness (shape + placement) for the key,
// each component alone for the shape and placement target frames. Without closeness matrices (posteriors
// built by hand) the frame where P(S)·P(P) is highest, the middle of the frames
// within plateau_log of the best log value when it saturates.
#include <Eigen/Core>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "analysis/keys/key_model.h"

namespace csw::keys {

struct DecodedKey {
  int placement = 0;
  int shape = 0;
  int64_t start_frame = 0;  // segment [start, end)
  int64_t end_frame = 0;
  int64_t target_frame = 0;
  int64_t shape_target_frame = 0;
  int64_t placement_target_frame = 0;
  std::string Code() const { return KeyCode(placement, shape); }
};

struct DecodeOptions {
  double min_key_ms = 80.0;          // free decoding: shortest key
  double switch_penalty = 4.0;       // free decoding: -log cost of a key change
  double aligned_min_key_ms = 40.0;  // aligned decoding: shortest key segment
  double floor = 1e-6;               // posterior floor before the log (free decoding, AlignComponent)
  // Aligned decoding of whole keys (DecodeAligned): a frame's evidence against
  // a key is capped at log(aligned_floor). The Gaussians extrapolate badly in
  // transitions, where a few confidently wrong frames would otherwise outvote a
  // whole hold (virtual cuer, model-filled takes: mean aligned target error
  // 29.6 ms at 1e-6, 27.6 at 3e-3; docs/analysis.md).
  double aligned_floor = 3e-3;
  double plateau_log = 1e-3;        // target-frame plateau tolerance (log units)
  double arrival_tolerance = 0.02;  // fraction of the segment's closeness range
  std::string Check() const;
};

// Free decoding of a take's posteriors (rate_hz: frame rate).
std::vector<DecodedKey> DecodeFree(const KeyPosteriors& posteriors, double rate_hz, const DecodeOptions& options = {});

struct ExpectedKey {
  int placement = 0;
  int shape = 0;
  // The key's acoustic onset A1 on the take's clock (seconds from its first
  // frame) when a phone alignment gave the key: the consonant onset for CV
  // and lone-consonant keys, the vowel onset for lone-vowel keys
  // (vowel_anchor). NaN = unknown (rest keys, keys read from a label tier).
  // Only DecodeAlignedTimed reads it (key_timing.h, "speech anchors").
  double anchor_s = std::numeric_limits<double>::quiet_NaN();
  bool vowel_anchor = false;
};
// Aligned decoding of an expected sequence. Throws InvalidInput when the
// sequence is empty or a key is out of range.
std::vector<DecodedKey> DecodeAligned(const KeyPosteriors& posteriors, const std::vector<ExpectedKey>& expected,
                                      double rate_hz, const DecodeOptions& options = {});

// Aligned decoding of one component (shape or placement posteriors, frames ×
// classes) against its own label sequence: one contiguous segment per label,
// in order, each at least aligned_min_key_ms long, maximising the summed log
// posterior. Give successive labels that differ (a component that does not
// change between keys has no segment of its own). Optional windows, one
// [first, last) frame range per label: frames of a label's segment outside its
// window count as if its posterior were below the floor (log floor − 1: a
// soft constraint, e.g. near the joint decoding's segments). Throws InvalidInput when the sequence is
// empty, a label is out of range, the windows do not match the labels or the
// take is too short.
struct ComponentSegment {
  int label = 0;
  int64_t start_frame = 0;  // [start, end)
  int64_t end_frame = 0;
};
std::vector<ComponentSegment> AlignComponent(const Eigen::MatrixXd& posteriors, const std::vector<int>& labels,
                                             double rate_hz, const DecodeOptions& options = {},
                                             const std::vector<std::pair<int64_t, int64_t>>& windows = {});

// Gesture extent: a maximal run of frames where one class has the highest
// posterior (it dominates the competing classes).
struct GestureExtent {
  int label = 0;
  int64_t start_frame = 0;  // [start, end)
  int64_t end_frame = 0;
  int64_t peak_frame = 0;
  double peak = 0.0;
};
std::vector<GestureExtent> GestureExtents(const Eigen::MatrixXd& posteriors);

enum class Component { kShape, kPlacement };
// For every key (e.g. from aligned decoding): the extent of its component's
// class that contains (or lies nearest to) its target frame inside its
// segment; nullopt for keys whose component does not change from the previous
// key (successions of identical components are excluded, as the seed does) or
// when no such extent meets the key's segment.
std::vector<std::optional<GestureExtent>> KeyExtents(const std::vector<GestureExtent>& extents,
                                                     const std::vector<DecodedKey>& keys, Component component);

// Edit-distance alignment of a decoded sequence against the expected one.
struct EditAlignment {
  int matches = 0;
  int substitutions = 0;
  int insertions = 0;  // decoded keys with no expected counterpart
  int deletions = 0;   // expected keys missed
  // (decoded index or -1, expected index or -1) in order.
  std::vector<std::pair<int, int>> pairs;
};
EditAlignment AlignSequences(const std::vector<std::string>& decoded, const std::vector<std::string>& expected);

// Confusion matrix: rows = true class, columns = decided class.
struct Confusion {
  Eigen::MatrixXi counts;
  explicit Confusion(int classes = 0) : counts(Eigen::MatrixXi::Zero(classes, classes)) {}
  void Add(int truth, int decided) { ++counts(truth, decided); }
  void Add(const Confusion& other) { counts += other.counts; }
  int64_t Total() const { return counts.sum(); }
  int64_t Correct() const { return counts.trace(); }
  double Accuracy() const { return Total() > 0 ? static_cast<double>(Correct()) / Total() : 0.0; }
};

// Most probable class of a posterior row.
int ArgMax(const Eigen::MatrixXd& posteriors, int64_t frame);

}  // namespace csw::keys
