#pragma once
// Sign-language transitions (Naert, Larboulette & Gibet, LSF coarticulation,
// §5.1): every movement between two consecutive signs of one hand's
// sign/transition tier, with its duration, the distances between the postures
// that bound it (mean Euclidean distance between joint positions, mean
// geodesic distance ‖log(a⁻¹b)‖ between joint orientations: half the rotation
// angle, as the seed writes it), the mean linear and angular speeds of the two
// signs (for SIMPLE_DURATION) and the sign types on either side (the seed's
// four-digit transition codes, Table 2). Pure functions on in-memory takes
// (docs/transitions.md).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

#include "core/take.h"

namespace csw::signing {

// ‖log(a⁻¹ b)‖ for unit quaternions: half the angle of the rotation from a to
// b, in radians, in [0, π/2] (q and −q are the same rotation).
double GeodesicDistance(const Eigen::Quaterniond& a, const Eigen::Quaterniond& b);

// The joints of one arm of a skeleton, from the shoulder to the finger tips:
// the wrist, every joint below it, and its ancestors up to (not including) the
// first ancestor that also carries the other wrist. Throws InvalidInput when a
// wrist is not a joint of the skeleton or both are the same joint.
std::vector<int> ArmJoints(const std::vector<SkeletonJoint>& skeleton, int wrist, int other_wrist);

// How a tier is read into signs and transitions.
struct TransitionOptions {
  // Labels (case-insensitive) of intervals that are transitions; an interval
  // with an empty label between two signs is one too (Praat fills the gaps of
  // an interval tier with empty intervals), and so is an unlabelled gap.
  std::vector<std::string> transition_labels = {"transition", "trans", "t", "tr"};
  // Labels (case-insensitive) of rests and of the movements from and to a
  // rest: one of them between two signs means no transition is measured there.
  std::vector<std::string> rest_labels = {"rest",        "#",          "_",    "sil", "pause",
                                          "preparation", "retraction", "prep", "retr"};
  // A gap between two signs longer than this is a pause, not a transition (s).
  double max_transition_s = 1.5;
  // Euclidean distances and linear speeds are reported in this many mm per
  // unit (1000: metres).
  double length_unit_mm = 1000.0;
  std::string Check() const;
};

// One transition of one hand.
struct Transition {
  std::string take;
  std::string hand;       // the tier's name, or what the caller passes
  std::string from_sign;  // label of the sign before
  std::string to_sign;    // label of the sign after
  std::string from_type;  // two-digit sign type of the sign before ("00", "10", "11", "20"), "" when unknown
  std::string to_type;    // the same for the sign after
  double start_s = 0.0;   // end of the sign before
  double end_s = 0.0;     // start of the sign after
  double duration_s = 0.0;
  int64_t start_frame = 0;  // the bounding postures (nearest frames)
  int64_t end_frame = 0;
  double geodesic = 0.0;   // mean geodesic distance over the joints (rad, half-angle convention)
  double euclidean = 0.0;  // mean Euclidean distance over the joints (length units)
  int joints_used = 0;     // joints with both postures known
  // Mean joint speed (length units / s) and mean angular speed (geodesic rad / s)
  // over the frames of the sign before and of the sign after (NaN when the sign
  // has fewer than two frames).
  double from_speed = 0.0, to_speed = 0.0;
  double from_angular_speed = 0.0, to_angular_speed = 0.0;
  // The mean of the two normalised distances ((d − mean) / range over the
  // transitions it was normalised with); set by NormaliseDistances.
  double normalised = 0.0;
  // The seed's code: from_type + to_type ("1011"), "" when a type is unknown.
  std::string type() const { return from_type.empty() || to_type.empty() ? "" : from_type + to_type; }
};

// A sign type label to the seed's two digits: hands (0 one, 1 two, 2 one hand
// signing while the other holds the context) then symmetry (1 symmetric). Takes
// "00", "10", "11", "20" or words: one_hand / one-hand / 1h, two_hands / 2h,
// symmetric / sym, contextualised / contextualized / context. "" when unknown.
std::string SignTypeCode(const std::string& label);

// The transitions of one hand's tier in a take. `joints` are the joints whose
// distances are averaged (ArmJoints for a per-hand tier, every joint for both
// hands); `types` (may be null) is an interval tier whose labels are sign types
// (SignTypeCode), looked up at each sign's middle. Needs the take's markers and
// orientations (Take::orientations); throws InvalidInput naming the take and
// tier when the tier is not an interval tier or the take has no orientations.
std::vector<Transition> ExtractTransitions(const Take& take, const LabelTier& tier, const LabelTier* types,
                                           const std::vector<int>& joints, const TransitionOptions& options);

// Normalisation of the distances, as LINEAR_DURATION uses them.
struct DistanceNormaliser {
  double geodesic_mean = 0.0, geodesic_range = 1.0;
  double euclidean_mean = 0.0, euclidean_range = 1.0;
  // ((g − mean_g) / range_g + (e − mean_e) / range_e) / 2
  double operator()(double geodesic, double euclidean) const;
};
// The normaliser of a set of transitions (a zero range becomes 1).
DistanceNormaliser FitNormaliser(const std::vector<Transition>& transitions);
// Sets every transition's `normalised` with the normaliser of the set.
void NormaliseDistances(std::vector<Transition>& transitions);

// Duration statistics of one transition type (the seed's Table 2).
struct TypeStatistics {
  std::string type;  // four digits, or "" for transitions of unknown type
  int count = 0;
  double mean_s = 0.0;
  double sd_s = 0.0;  // sample standard deviation (0 for one transition)
};
// Per type, in type order.
std::vector<TypeStatistics> StatisticsPerType(const std::vector<Transition>& transitions);

}  // namespace csw::signing
