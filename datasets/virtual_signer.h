#pragma once
// The virtual signer (issue 14, item 1; docs/signing.md): simulated
// sign-language captures with ground truth, the sign-language counterpart of
// the virtual cuer. No open sign-language motion capture with manual
// sign/transition labels exists, so the project makes its own.
//
// A take is a sequence of signs drawn from a small lexicon (one-hand,
// two-hand and symmetric signs) signed by a BVH skeleton (torso, neck, head,
// two arms with collar, shoulder, elbow, wrist and a few finger joints with end
// sites):
//   rest -> preparation -> stroke 1 -> transition -> stroke 2 -> ... ->
//   stroke N -> retraction -> rest
// Every phase of each hand is one minimum-jerk movement in joint space (a
// stroke with repetitions is several), so each hand's speed is zero — its
// minimum — exactly at its simulated phase changes, which lie on frames. The
// durations of the movements between strokes (preparation, transition,
// retraction) follow a configurable law of the distances between the postures
// that bound them (the seed's SURFACE plane by default, or SIMPLE), rounded to
// whole frames. The two hands are not synchronous: each hand's movement
// between two strokes is shifted by its own whole-frame offset (same
// duration). Measurement noise is added to the joint positions.
//
// Conventions: lab axes x = the signer's left, y = up, z = forward (the
// signer faces +z), millimetres; every joint has channels "Zrotation
// Xrotation Yrotation" (the root "Xposition Yposition Zposition" first), the
// local rotation being Rz·Rx·Ry (BVH: channels compose left to right), degrees.
// Same options and seed -> identical takes.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/take.h"

namespace csw {

enum class SignType { kOneHand, kTwoHands, kSymmetric };
// "one_hand", "two_hands", "symmetric" (the labels of the `sign_types` tier).
const char* SignTypeName(SignType type);

// How the duration of a movement between two strokes is drawn.
enum class DurationLaw {
  // duration = θ0 + θ1·G + θ2·E (the seed's SURFACE_DURATION, its eq. 4).
  kSurface,
  // duration = α·2E/(v1 + v2) + (1 − α)·2G/(ω1 + ω2) (the seed's eq. 3): v and ω
  // are the mean linear and angular speeds of the two strokes around it (E and
  // G of the stroke's start and end postures times its movements, over its
  // duration); next to rest only the sign's own speeds count.
  kSimple,
};
const char* DurationLawName(DurationLaw law);  // "surface", "simple"
bool ParseDurationLaw(const std::string& name, DurationLaw* law);

// Joint names of the simulated skeleton (the same hierarchy and channels).
//   "csw":    Hips Spine Chest Neck Head, RightCollar RightShoulder RightElbow
//             RightWrist RightThumb1 RightIndex1 RightIndex2 RightPinky1 (and Left*),
//             end sites <parent>_End;
//   "mixamo": mixamorig:Hips ... mixamorig:RightArm RightForeArm RightHand
//             RightHandThumb1 RightHandIndex1 ... (the wrist is "...Hand"), end
//             sites <parent>_End.
std::vector<std::string> SignerNamings();

struct SignerOptions {
  uint64_t seed = 1;
  double rate_hz = 100.0;  // the seed's capture rate
  int min_signs = 3;       // signs per take, drawn uniformly in [min_signs, max_signs]
  int max_signs = 6;
  // Transition duration law and its parameters.
  DurationLaw law = DurationLaw::kSurface;
  std::array<double, 3> theta = {0.148777, 0.663958, 0.275229};  // SURFACE θ0 (s), θ1 (s/rad), θ2 (s/unit)
  double simple_alpha = 0.5;                                     // SIMPLE α
  // Unit of the Euclidean distance E in the laws and the ground truth, in mm
  // (1000 = metres; the seed does not state its unit).
  double distance_unit_mm = 1000.0;
  double duration_noise_sd_s = 0.0;  // Gaussian noise added to the law (0 = exact law)
  double min_movement_s = 0.05;      // law results are clamped to [min, max] (then rounded to frames)
  double max_movement_s = 2.0;
  // Each hand's movement between two strokes is shifted by a whole number of
  // frames drawn uniformly in [-hand_offset_max_s, +hand_offset_max_s] (0 = synchronous hands).
  double hand_offset_max_s = 0.03;
  double stroke_time_sd = 0.1;  // relative sd of a stroke's duration around its lexicon value (truncated at 2 sd)
  double posture_sd_deg = 2.0;  // per-occurrence variability of every posture angle (truncated at 2.5 sd)
  double noise_mm = 0.5;        // σ of the Gaussian noise of every joint position coordinate
  double rest_s = 0.5;          // rest before the preparation and after the retraction
  // Skeleton: joint names and proportions.
  std::string naming = "csw";
  double body_scale = 1.0;    // all offsets
  double arm_scale = 1.0;     // arm and hand offsets on top of body_scale
  std::string Check() const;  // "" when valid, else the reason
};

// A posture of one arm, in degrees, written for the right arm (the left arm's
// is mirrored through the body's mid-sagittal plane, so equal values on both
// arms make a symmetric posture): shoulder Z (abduction, 0 = T-pose, 90 = arm
// down), shoulder X (twist), shoulder Y (forward flexion), elbow Y (flexion),
// wrist Z, X, Y, finger curl.
using ArmPosture = std::array<double, 8>;

struct LexiconSign {
  std::string gloss;
  SignType type = SignType::kOneHand;
  int movements = 1;      // stroke movements start→end, end→start, ...: an even count ends at the start posture
  double stroke_s = 0.4;  // mean stroke duration
  ArmPosture right_start{}, right_end{};
  ArmPosture left_start{}, left_end{};  // two-hand signs; symmetric signs use the right's
};

// The 14 signs of the shipped lexicon (5 one-hand, 4 two-hand, 5 symmetric).
const std::vector<LexiconSign>& SignerLexicon();
// The arms' rest posture (hands lowered in front of the hips), also the
// non-dominant (left) hand's posture during one-hand signs.
ArmPosture SignerRestPosture();

// A skeleton posture: joint positions (mm, lab) and global orientations, one
// per skeleton entry (end sites included, with their parent's orientation).
struct SkeletonPose {
  Eigen::Matrix3Xd positions;
  std::vector<Eigen::Quaterniond> orientations;
};

// Mean over the entries of ‖log(a⁻¹b)‖ (the quaternion logarithm's norm: half
// the rotation angle, radians), as the seed's eq. 1.
double MeanGeodesicDistance(const SkeletonPose& a, const SkeletonPose& b);
// Mean over the entries of the distance between positions, in units of unit_mm.
double MeanEuclideanDistance(const SkeletonPose& a, const SkeletonPose& b, double unit_mm);

// Forward kinematics of a BVH hierarchy: `values` holds every joint's
// channels in skeleton order (positions mm, rotations degrees; channels in any
// order, each "Xposition", ..., "Zrotation").
SkeletonPose ForwardKinematics(const std::vector<SkeletonJoint>& skeleton, const Eigen::VectorXd& values);

// One sign of a take.
struct SignOccurrence {
  int lexicon = 0;  // index into SignerLexicon()
  std::string gloss;
  SignType type = SignType::kOneHand;
  double start_s = 0.0;  // nominal stroke (the synchronous `signs` tier)
  double end_s = 0.0;
  double right_start_s = 0.0, right_end_s = 0.0;  // the right hand's stroke
  double left_start_s = 0.0, left_end_s = 0.0;    // the left hand's (NaN for one-hand signs: it rests)
};

// One movement between strokes (or from / to rest), as the law drew it.
struct TransitionTruth {
  std::string kind;                                  // "preparation" (from rest), "transition", "retraction" (to rest)
  int from_sign = -1, to_sign = -1;                  // indices into the take's signs, -1 = rest
  double start_s = 0.0, end_s = 0.0;                 // nominal (the `signs` tier); end - start = duration_s
  double right_offset_s = 0.0, left_offset_s = 0.0;  // each hand's movement is [start, end] + its offset
  // G and E between the bounding postures (the previous stroke's last posture or
  // rest, the next stroke's first posture or rest), whole skeleton: both hands'
  // target postures, whatever their offsets. With hand_offset_max_s = 0 they are
  // the skeleton's poses at the frames start_s and end_s.
  double geodesic = 0.0;    // G (rad)
  double euclidean = 0.0;   // E in units of distance_unit_mm
  double law_s = 0.0;       // the law's value (with its noise, before clamping and rounding)
  double duration_s = 0.0;  // simulated: clamped, rounded to whole frames
};

// A boundary of the nominal `signs` tier and where each hand's phase changes
// there (NaN when that hand keeps resting across it).
struct BoundaryTruth {
  double nominal_s = 0.0;
  double right_s = 0.0;
  double left_s = 0.0;
  bool stroke = false;  // the start or end of a sign's stroke (else rest → preparation or retraction → rest)
  // Per hand: the hand is still on one side (arrives at or leaves its rest).
  bool right_at_rest = false, left_at_rest = false;
};

struct SignerTake {
  // Markers = global joint positions (mm, noisy) of every skeleton entry
  // (end sites included), orientations, skeleton, rate, and the tiers:
  //   `signs` (nominal, both hands: rest, preparation, GLOSS, transition, ...,
  //   retraction, rest), `right_hand` and `left_hand` (each hand's true phases,
  //   same labels; the left hand's "rest" also during one-hand signs), and
  //   `sign_types` (one_hand / two_hands / symmetric over each sign of `signs`,
  //   "" elsewhere).
  Take take;
  MarkerArray clean;         // joint positions without noise
  Eigen::MatrixXd channels;  // frames × channel values (BVH MOTION order: mm, degrees)
  std::vector<SignOccurrence> signs;
  std::vector<TransitionTruth> transitions;  // preparation, transitions, retraction in time order
  std::vector<BoundaryTruth> boundaries;     // every interior boundary of `signs`, in time order
};

inline constexpr const char* kSignsTier = "signs";
inline constexpr const char* kRightHandTier = "right_hand";
inline constexpr const char* kLeftHandTier = "left_hand";
inline constexpr const char* kSignTypesTier = "sign_types";

class VirtualSigner {
 public:
  explicit VirtualSigner(const SignerOptions& options);  // throws InvalidInput for bad options
  const SignerOptions& options() const { return options_; }
  const std::vector<SkeletonJoint>& skeleton() const { return skeleton_; }
  // Marker names of the takes (the skeleton's names, end sites included).
  std::vector<std::string> JointNames() const;
  // Indices of the wrists in the skeleton.
  int right_wrist() const { return right_wrist_; }
  int left_wrist() const { return left_wrist_; }

  // The pose of given arm postures (torso at its fixed pose).
  SkeletonPose Pose(const ArmPosture& right, const ArmPosture& left) const;
  // Take `index` of the seed: its sign sequence and every draw come from
  // (seed, index) only. Name "signs<index>" with three digits.
  SignerTake SimulateTake(int index) const;
  // A given sign sequence (indices into SignerLexicon()), draws from (seed, name).
  SignerTake SimulateSequence(const std::string& name, const std::vector<int>& signs) const;

 private:
  Eigen::VectorXd Channels(const ArmPosture& right, const ArmPosture& left) const;
  SignerOptions options_;
  std::vector<SkeletonJoint> skeleton_;
  std::vector<int> right_arm_,
      left_arm_;  // skeleton indices: collar, shoulder, elbow, wrist, thumb1, index1, index2, pinky1
  int right_wrist_ = -1, left_wrist_ = -1;
};

// Takes 0 .. count-1 of the seed. Reports progress; throws Cancelled.
std::vector<SignerTake> SimulateSigner(const SignerOptions& options, int count, Progress& progress);

// An annotator's tier: a copy of `tier` named `name` whose every interior
// boundary is moved by an offset drawn uniformly in [-max_offset_s,
// +max_offset_s] (seeded), redrawn when it would not stay at least one frame
// after the previous boundary and before the next one's original time minus
// one frame. offsets (optional) gets each boundary's offset in order.
LabelTier JitterBoundaries(const LabelTier& tier, const std::string& name, double max_offset_s, double rate_hz,
                           uint64_t seed, std::vector<double>* offsets = nullptr);

// The ground truth as JSON text (signs, transitions with G, E and durations,
// boundaries), deterministic formatting.
std::string SignerTruthToJson(const SignerTake& take, const SignerOptions& options);

}  // namespace csw
