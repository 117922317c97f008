#pragma once
// Transition synthesis (Naert, Larboulette & Gibet §3 and §5.2): joining two
// signs taken from captures by
//   - interpolation: from the last posture of sign 1 to the first posture of
//     sign 2, joint positions linearly and joint orientations by slerp, over
//     the frames a duration model gives;
//   - blending: the retraction that followed sign 1 in its capture and the
//     preparation that preceded sign 2 in its capture, both time-normalised to
//     the transition's frames and cross-faded (positions linearly, orientations
//     by slerp) with a weight rising from 0 to 1;
// and motion retrieval: among candidate occurrences of a sign, the one whose
// bounding postures are closest to its neighbours'. Pure functions on clips of
// skeleton takes (docs/transitions.md).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "analysis/signing/duration_models.h"
#include "analysis/signing/transitions.h"
#include "core/take.h"

namespace csw::signing {

// A stretch of skeleton motion: frames × joints positions (mm) and global
// orientations, at one frame rate. Every sample is known (a clip with missing
// samples is refused by ExtractClip).
struct Clip {
  double rate_hz = 0.0;
  int64_t frames = 0;
  int joints = 0;
  std::vector<Eigen::Vector3d> positions;        // frame-major: [f * joints + j]
  std::vector<Eigen::Quaterniond> orientations;  // the same layout
  const Eigen::Vector3d& position(int64_t f, int j) const { return positions[static_cast<size_t>(f * joints + j)]; }
  const Eigen::Quaterniond& orientation(int64_t f, int j) const {
    return orientations[static_cast<size_t>(f * joints + j)];
  }
};

// Frames [first, first + count) of a take with orientations. Throws
// InvalidInput naming the take when the range is outside it, it has no
// orientations, or a sample in the range is missing.
Clip ExtractClip(const Take& take, int64_t first, int64_t count);

// The clip's posture at a fractional frame (linear / slerp between frames;
// clamped to the clip).
void PostureAt(const Clip& clip, double frame, std::vector<Eigen::Vector3d>* positions,
               std::vector<Eigen::Quaterniond>* orientations);

// `frames` in-between frames from the last posture of `from` to the first of
// `to` (u = (i + 1) / (frames + 1)), positions linear, orientations slerp.
// Throws InvalidInput when the clips' joints or rates differ or frames < 0.
Clip InterpolateTransition(const Clip& from, const Clip& to, int64_t frames);

// `frames` frames blending `retraction` (the motion after sign 1) into
// `preparation` (the motion before sign 2), each resampled over the
// transition; weight w(u) = u (linear, as the seed) or the smooth 3u² − 2u³.
// Throws InvalidInput when the clips' joints or rates differ, a clip has
// fewer than 1 frame, or frames < 0.
Clip BlendTransition(const Clip& retraction, const Clip& preparation, int64_t frames, bool smooth = false);

// The transition's frame count at a rate: round(duration × rate) − 1 in-between
// frames for a duration between two posture frames, at least 0.
int64_t TransitionFrames(double duration_s, double rate_hz);

// `a` then `b` (same joints and rate).
Clip Concatenate(const Clip& a, const Clip& b);

// Distance between two postures as the seed measures transitions: the mean
// Euclidean distance (in length_unit_mm units) plus the mean geodesic distance.
double PostureDistance(const Clip& a, int64_t frame_a, const Clip& b, int64_t frame_b, double length_unit_mm = 1000.0);

// Motion retrieval: the index of the candidate whose first posture is closest
// to `previous`'s last posture plus whose last posture is closest to `next`'s
// first (either may be null). Throws InvalidInput when there is no candidate.
size_t RetrieveOccurrence(const std::vector<Clip>& candidates, const Clip* previous, const Clip* next,
                          double length_unit_mm = 1000.0);

// Motion retrieval for a whole sequence: candidates[i] are the occurrences of
// the i-th sign; returns one index per sign minimising the sum over
// consecutive signs of PostureDistance(last posture of sign i, first posture
// of sign i + 1) (dynamic programming). Throws InvalidInput when a sign has no
// candidate.
std::vector<size_t> RetrieveSequence(const std::vector<std::vector<Clip>>& candidates, double length_unit_mm = 1000.0);

// The transition between the last posture of `from` and the first of `to` as
// the duration models see it: distances over `joints` (every joint when
// empty), the clips' mean speeds as the signs' speeds; duration 0.
Transition MeasureBetween(const Clip& from, const Clip& to, const std::vector<int>& joints,
                          double length_unit_mm = 1000.0);

// Mean over frames and joints of the position error (mm) between two clips of
// the same size, and the mean geodesic error (rad); for comparing a synthetic
// transition with a captured one.
void CompareClips(const Clip& a, const Clip& b, double* mean_position_error_mm, double* mean_geodesic_error);

}  // namespace csw::signing
