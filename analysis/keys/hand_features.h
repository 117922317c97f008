#pragma once
// The characteristic hand parameters of the seed (Gibert-Bailly-Elisei §4) and
// the placement feature, per frame.
//
// Seven distances (millimetres), in this order:
//   0-4  for each finger (thumb, index, middle, ring, little): the distance from
//        the marker of its first phalanx closest to the palm to the marker of its
//        last phalanx closest to the tip (large when extended, small when folded);
//   5    the index-middle tip distance (shape 2 vs 8);
//   6    the thumb tip to palm distance (1 vs 6, 2 vs 7), measured to one palm
//        marker: by default the palm marker nearest the little finger's base.
//        With markers on the back of the hand (as on the virtual cuer and in
//        the seed's capture) the palm centre is about as far from a thumb
//        folded across the palm as from an extended one (125 vs 126 mm on the
//        virtual hand), while the ulnar edge of the palm is 30-40 mm farther
//        from an extended thumb. The point is carried by a rigid fit of the
//        palm markers, so it is known while >= 3 palm markers are visible.
// Placement feature: the 3D position (mm) in the head frame of the tip of the
// longest extended finger: the index for the shapes listed in
// KeyModel::index_shapes (1 and 6), the middle finger otherwise. The feature is
// CHOSEN (not mixed) by one shape per frame: the labelled shape at training
// frames, the most probable shape of the frame's posterior when scoring
// (key_model.h, PlacementFeatures).
//
// Which marker is which comes from the marker set's roles, never from names:
// the segment whose chain of children reaches the fingertips is the palm; each
// child chain of the palm is one finger. The thumb is the chain whose first
// segment lies farthest from the line through the other four first segments;
// the other four are ordered along that line from the thumb's side (index,
// middle, ring, little). The proximal marker of a finger is the marker of its
// first segment closest to the palm centre; the distal marker is its
// `fingertips` marker, or else the marker of its last segment farthest from
// the palm centre. Both decisions vote over frames of the take. Another lab may
// name the markers instead (HandLayout, JSON section "hand_layout").
//
// Missing markers (or no head frame) give NaN features; the key model
// marginalises them. Pure functions: no file access.
#include <Eigen/Core>
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/markerset.h"
#include "core/progress.h"
#include "core/take.h"
#include "models/rigid_motion.h"

namespace csw::keys {

inline constexpr int kNumFingers = 5;
inline constexpr int kNumDistances = 7;
// "thumb", "index", "middle", "ring", "little".
const std::array<std::string, kNumFingers>& FingerNames();
// "thumb_extension", ..., "little_extension", "index_middle_tips", "thumb_palm".
const std::vector<std::string>& DistanceNames();

// Canonical marker names behind the features.
struct HandLayout {
  std::array<std::string, kNumFingers> proximal;  // per finger: first phalanx, palm side
  std::array<std::string, kNumFingers> distal;    // per finger: last phalanx, tip side
  std::vector<std::string> palm;                  // ≥ 3 markers, fitted rigidly
  std::string thumb_palm;                         // palm marker for distance 6; "" = palm centroid
  std::vector<std::string> head;                  // head cluster, ≥ 3 markers
  std::string Check() const;                      // "" or the reason
};
bool operator==(const HandLayout& a, const HandLayout& b);

// The documented JSON section (docs/analysis.md):
//   {"fingers": {"thumb": ["T1", "TT"], "index": [...], "middle": [...],
//                "ring": [...], "little": [...]},
//    "palm": ["P1", "P2", "P3"], "thumb_palm": "P3", "head": ["H1", "H2", "H3"]}
// ("head" optional: the marker set's head cluster; "thumb_palm" optional: the
// palm centroid; each finger names [proximal, distal]). Throws InvalidInput naming
// `where` (file and section) on an unknown key or a bad value.
HandLayout ParseHandLayout(const nlohmann::json& section, const MarkerSet& set, const std::string& where);
nlohmann::json HandLayoutToJson(const HandLayout& layout);

// Derives the layout from the marker set's roles and the take's marker
// positions (see above). Throws InvalidInput (naming take_name) when the hand
// segments do not form a palm with five finger chains, or no frame shows the
// markers needed to tell the fingers apart.
HandLayout DeriveHandLayout(const MarkerSet& set, const MarkerArray& markers, const MarkerBinding& binding,
                            const std::string& take_name = "");

struct HandFeatures {
  Eigen::MatrixXd distances;   // frames × 7 (mm); NaN where a marker is missing
  Eigen::MatrixXd index_tip;   // frames × 3, head frame (mm); NaN when missing
  Eigen::MatrixXd middle_tip;  // frames × 3, head frame (mm)
  // Each finger's distal marker (thumb, index, middle, ring, little) in the
  // palm's own frame (rigid fit of >= 3 palm markers): frames × 15 (mm), NaN
  // where missing. Unlike the distances, these move at first order with every
  // joint even at full extension, so movement fits time shapes on them
  // (key_timing.h). Empty when the palm markers cannot be fitted rigidly.
  Eigen::MatrixXd tips_in_palm;
  int64_t frames() const { return distances.rows(); }
};

struct HandFeatureOptions {
  RigidOptions head_fit;  // per-frame head pose (robust by default)
};

// The head cluster's reference shape (its own frame), from frames where every
// head marker is visible (models/rigid_motion.h ClusterReference). The key model
// keeps the reference of its training data so that every take shares one head
// frame. Throws InvalidInput when no frame shows the whole cluster.
Eigen::Matrix3Xd HeadReference(const MarkerArray& markers, const MarkerBinding& binding, const HandLayout& layout);

// Features of every frame. head_reference: 3 × layout.head.size().
HandFeatures ComputeHandFeatures(const MarkerArray& markers, const MarkerBinding& binding, const HandLayout& layout,
                                 const Eigen::Matrix3Xd& head_reference, const HandFeatureOptions& options = {},
                                 Progress* progress = nullptr);

}  // namespace csw::keys
