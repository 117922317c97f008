#pragma once
// The virtual cuer's face, head and throat: 63 skin markers in the head frame
// (x: cuer's left, y: forward, z: up; origin between the ears) driven linearly
// by six articulatory parameters in the spirit of the MOTHER talking head
// (jaw opening, jaw advance, lip protrusion, lip closure, lip raising, larynx),
// per-phoneme targets and an Öhman-style coarticulation model (vowel carrier
// plus consonant contributions weighted by coarticulation resistance).
// Throat markers follow the head's motion with weights below one.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace csw {

struct Phone;

enum ArticulatoryParameter {
  kJawOpening = 0,     // mm, chin drop at the incisors
  kJawAdvance = 1,     // mm, forward
  kLipProtrusion = 2,  // mm, rounding/protrusion (negative = spreading)
  kLipClosure = 3,     // mm, lips pressed together beyond the jaw's help
  kLipRaising = 4,     // mm, lower lip raised and retracted (labiodentals)
  kLarynx = 5,         // mm, larynx (throat skin) up
};
inline constexpr int kNumArticulatory = 6;
using ArticulatoryVector = Eigen::Matrix<double, kNumArticulatory, 1>;
const char* ArticulatoryName(int parameter);

// Small rigid motion of the head about the head-frame origin: rotation vector
// (radians) and translation (mm). The pose of a marker with head weight w is
// Exp(w * rotation) * p + w * translation (the seed's weighted Rigid_Motion).
struct HeadMotion {
  Eigen::Vector3d rotation = Eigen::Vector3d::Zero();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Isometry3d Weighted(double weight) const;
  // Fraction rotation_weight of the rotation (about the head-frame origin) and
  // translation_weight of the translation.
  Eigen::Isometry3d Weighted(double rotation_weight, double translation_weight) const;
};

// Marker layouts the virtual cuer can write (docs/virtual-cuer.md, "Layouts"):
// "default" (63 face, head and throat markers, 50 hand markers) and "lab2"
// (another lab's layout: 5 head, 20 face and 3 throat markers with other
// names, throat markers that follow the head's translation fully and only
// kLab2ThroatRotationWeight of its rotation; 43 hand markers on a hand 8 %
// smaller, 2 markers per phalanx).
const std::vector<std::string>& SimulatorLayouts();
bool IsSimulatorLayout(const std::string& name);
inline constexpr double kLab2ThroatRotationWeight = 0.4;
inline constexpr double kLab2HandScale = 0.92;

class VirtualFace {
 public:
  VirtualFace();  // the built-in 63-marker face (layout "default")
  // The face of a simulator layout (SimulatorLayouts(); InvalidInput when unknown).
  explicit VirtualFace(const std::string& layout);

  int num_markers() const { return static_cast<int>(names_.size()); }
  const std::vector<std::string>& marker_names() const { return names_; }
  int MarkerIndex(const std::string& name) const;  // -1 when unknown
  // Neutral marker positions in the head frame (3 × 63).
  const Eigen::Matrix3Xd& neutral() const { return neutral_; }
  // Displacement per unit of each articulatory parameter (3 × 63 each).
  const Eigen::Matrix3Xd& basis(int parameter) const { return basis_[static_cast<size_t>(parameter)]; }
  // Head weight of each marker: 1 for head and face markers, < 1 for throat
  // markers: the fraction of the head's rotation the marker follows.
  const Eigen::VectorXd& head_weights() const { return head_weights_; }
  // Fraction of the head's translation each marker follows: equal to the head
  // weight in the default layout (the weighted rigid motion); 1 for the
  // throat markers of "lab2".
  const Eigen::VectorXd& translation_weights() const { return translation_weights_; }
  const std::string& layout() const { return layout_; }

  // Markers in the head frame, before head motion.
  Eigen::Matrix3Xd MarkersInHead(const ArticulatoryVector& p) const;
  // Markers after a head motion (still in the reference head frame).
  Eigen::Matrix3Xd MarkersMoved(const ArticulatoryVector& p, const HeadMotion& motion) const;

  const std::vector<std::string>& rigid_markers() const { return rigid_; }
  const std::vector<std::string>& face_markers() const { return face_; }
  const std::vector<std::string>& throat_markers() const { return throat_; }
  const std::vector<std::pair<std::string, std::string>>& sticks() const { return sticks_; }

  // Half-axes of the ellipsoid approximating the head (for occlusions), centred at
  // head_centre(), and a neck cylinder from neck_top() to neck_bottom().
  Eigen::Vector3d head_radii() const { return {70.0, 92.0, 115.0}; }
  Eigen::Vector3d head_centre() const { return {0.0, 8.0, 5.0}; }
  Eigen::Vector3d neck_top() const { return {0.0, 10.0, -80.0}; }
  Eigen::Vector3d neck_bottom() const { return {0.0, 0.0, -230.0}; }
  double neck_radius() const { return 48.0; }

 private:
  std::vector<std::string> names_;
  Eigen::Matrix3Xd neutral_;
  std::vector<Eigen::Matrix3Xd> basis_;
  Eigen::VectorXd head_weights_;
  Eigen::VectorXd translation_weights_;
  std::string layout_ = "default";
  std::vector<std::string> rigid_, face_, throat_;
  std::vector<std::pair<std::string, std::string>> sticks_;
};

// Per-phoneme articulatory targets: a vowel's target, or a consonant's target
// and its coarticulation resistance per parameter (0 = takes the vowel's value,
// 1 = imposes its own). Unknown phonemes behave as a neutral schwa-like vowel;
// pauses ("") have the neutral, mouth-closed target.
struct PhonemeTarget {
  ArticulatoryVector target = ArticulatoryVector::Zero();
  ArticulatoryVector resistance = ArticulatoryVector::Zero();  // consonants only
  bool vowel = false;
};
PhonemeTarget ArticulatoryTarget(const std::string& ipa);

// Öhman coarticulation: articulatory parameters at each time of `times_s` for a
// phone sequence. The vowel carrier interpolates vowel (and pause) targets with
// minimum-jerk transitions between their centres; each consonant adds
// k_c * w_c(t) * (C - V(t)) with a smooth plateau window w_c over its duration.
std::vector<ArticulatoryVector> Coarticulate(const std::vector<Phone>& phones, const std::vector<double>& times_s);

}  // namespace csw
