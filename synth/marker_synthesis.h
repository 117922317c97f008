#pragma once
// Markers from model parameters (issue 15 §5, the last step of synthesis):
// per-frame parameter tracks on one clock — the face model's shape
// parameters and the head pose, the hand model's shape parameters and the
// forearm pose in the head frame, as the dictionaries store them
// (synth/dictionary.h) — back to every marker of the two models, in the lab.
//
// Poses are 6-vectors (rx ry rz rad as a rotation vector, tx ty tz mm;
// models/rigid_motion.h): head_pose maps the head cluster frame to the lab
// (the face inversion's pose, InversionResult::pose), forearm_in_head maps
// the forearm cluster frame to the head cluster frame (dict::RelativePose(
// head, forearm) = head⁻¹ ∘ forearm). So the forearm's lab pose is
// head ∘ forearm_in_head, and a frame's markers are
//   face.MarkersInLab(head, face_params)  (head cluster, face, throat)
//   hand.MarkersInLab(head ∘ forearm_in_head, hand_params)  (forearm cluster, hand).
//
// Pure: no file I/O.
#include <Eigen/Core>
#include <string>
#include <vector>

#include "core/take.h"
#include "models/rigid_motion.h"

namespace csw {

struct FaceModel;
struct HandModel;

struct ParameterTracks {
  double rate_hz = 0;               // frames per second of every track
  Eigen::MatrixXd face_params;      // frames × Q (the face model's parameters)
  Eigen::MatrixXd head_pose;        // frames × 6: head cluster → lab
  Eigen::MatrixXd hand_params;      // frames × P (the hand model's parameters)
  Eigen::MatrixXd forearm_in_head;  // frames × 6: forearm cluster → head cluster
  int64_t frames() const { return head_pose.rows(); }
};

// The lab pose of the forearm cluster: head ∘ forearm_in_head (the inverse of
// dict::RelativePose(head, ·)); NaN when either has a NaN.
Eigen::Matrix<double, 6, 1> ComposePose(const Eigen::Matrix<double, 6, 1>& head,
                                        const Eigen::Matrix<double, 6, 1>& forearm_in_head);

// The marker names of MarkersFromParameters, in column order: the face
// model's (head cluster, face, throat) then the hand model's (forearm
// cluster, hand), as the models' layouts name them (the marker set's
// canonical names).
std::vector<std::string> SynthesisMarkerNames(const FaceModel& face, const HandModel& hand);

// A take of every model marker (SynthesisMarkerNames) at tracks.rate_hz, one
// frame per track row. A face marker is NaN in a frame whose head pose or
// face parameters row has a NaN; a hand marker when the head pose, the
// forearm pose or the hand parameters row has one. The take has no tiers,
// audio or marker set (the caller adds them). Throws InvalidInput naming
// take_name when the rate is not positive, the tracks have different row
// counts, a pose track has not 6 columns, a parameter track has not the
// model's number of columns, or the two models share a marker name.
Take MarkersFromParameters(const FaceModel& face, const HandModel& hand, const ParameterTracks& tracks,
                           const std::string& take_name);

// Speed limit: no marker of `take` (MarkersFromParameters of `tracks`) may
// move more than limit_mm between two frames — the fastest the corpus's cuer
// ever moved, so that a unit squeezed into a short slot does not outrun the
// cuer. Each pass finds the frame transitions where some marker moves
// further, smooths every track at their two frames with the kernel
// [1 2 1] / 4 (the transition's jump becomes the mean of its neighbours',
// weighted 1 2 1; the movement is spread over more frames, its end points,
// the keys' targets, untouched unless the transition is next to them) and
// recomputes those frames' markers; it stops when no jump exceeds the limit
// or after max_passes. A pass that takes less than 1 % off the total excess
// over the limit widens the smoothing by one more frame on each side of
// every transition above it (a stretch moving at one speed above the limit
// is a fixed point of the kernel). The first and last frames count as held (their
// missing neighbour is themselves: [1 3] / 4), so a movement that ends on the
// take's last frame is spread too. Frames with NaN tracks and their neighbours are left
// alone. Returns the number of frame smoothings made (0 = nothing was above
// the limit). Throws InvalidInput as MarkersFromParameters, or when limit_mm
// is not positive.
struct SpeedLimitResult {
  int smoothings = 0;  // frames smoothed, over all passes
  int passes = 0;      // passes that smoothed something
  double max_jump_before_mm = 0;
  double max_jump_after_mm = 0;
};
SpeedLimitResult LimitMarkerSpeed(const FaceModel& face, const HandModel& hand, double limit_mm, int max_passes,
                                  ParameterTracks* tracks, Take* take);

}  // namespace csw
