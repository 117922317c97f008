#pragma once
// The virtual cuer's right hand and forearm: an articulated skeleton (wrist,
// thumb with its carpometacarpal joint, four fingers of three phalanges) with
// joint limits, the nine LfPC postures as joint-angle targets read from a JSON
// configuration (datasets/config/hand.json), and 50 skin markers whose
// positions are a smooth function of the joint angles (rigid attachment plus
// sub-millimetre soft-tissue sliding in sin/cos of the adjacent joint angle).
//
// Forearm frame: origin at the wrist centre, y along the forearm towards the
// fingers, z out of the back of the hand (dorsal), x = y × z (ulnar side).
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace csw {

struct HandJoint {
  std::string name;
  double min_rad = 0.0;
  double max_rad = 0.0;
};

struct HandPosture {
  int shape = 0;  // 0 = rest, 1-8 = LfPC hand shapes
  std::string name;
  std::string reference_finger;  // "index" or "middle": the finger brought to the placement
  Eigen::VectorXd angles;        // radians, one per joint
};

struct HandConfig {
  std::vector<HandJoint> joints;
  std::vector<HandPosture> postures;  // indexed by shape, 0..8

  int JointIndex(const std::string& name) const;  // -1 when unknown
  const HandPosture& Posture(int shape) const;    // throws InvalidInput for an unknown shape
  Eigen::VectorXd Clamp(const Eigen::VectorXd& angles) const;
  bool WithinLimits(const Eigen::VectorXd& angles, double slack_rad = 1e-9) const;
};

// Parses a hand configuration. Throws ParseError (file, line) for malformed JSON
// and InvalidInput (naming the file and the rule) for a bad definition: unknown
// joint names, a posture outside the joint limits, a missing shape.
HandConfig ParseHandConfig(const std::string& json_text, const std::string& file = "");
HandConfig LoadHandConfig(const std::string& path);
// The shipped datasets/config/hand.json (compiled in).
const std::string& DefaultHandConfigJson();
HandConfig DefaultHandConfig();

// A capsule (segment a-b with radius) used for occlusion tests and drawing.
struct Capsule {
  std::string segment;
  Eigen::Vector3d a = Eigen::Vector3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  double radius = 0.0;
};

class VirtualHand {
 public:
  enum Finger { kThumb = 0, kIndex = 1, kMiddle = 2, kRing = 3, kLittle = 4 };

  explicit VirtualHand(HandConfig config);
  // The hand of a simulator layout (SimulatorLayouts() in face_model.h): "lab2"
  // is kLab2HandScale the size and has 43 markers: no FA5 (6 forearm
  // markers), no PD2, two markers on every phalanx (the distal ones: the
  // dorsal distal marker and the nail), names prefixed "RH_". Throws InvalidInput for an unknown layout.
  VirtualHand(HandConfig config, const std::string& layout);
  // The same with the hand `size` times the layout's (every segment and marker
  // offset scaled; the joint angles unchanged). Throws InvalidInput unless
  // size is in [0.5, 2].
  VirtualHand(HandConfig config, const std::string& layout, double size);
  double scale() const { return scale_; }

  const HandConfig& config() const { return config_; }
  int num_joints() const { return static_cast<int>(config_.joints.size()); }
  const std::vector<std::string>& marker_names() const { return marker_names_; }
  int num_markers() const { return static_cast<int>(marker_names_.size()); }

  // Rigid forearm cluster, palm markers, fingertip (nail) markers, and the
  // markers of each hand segment (palm, thumb1..3, index1..3, ...), by name.
  const std::vector<std::string>& forearm_markers() const { return forearm_markers_; }
  const std::vector<std::string>& palm_markers() const { return palm_markers_; }
  const std::vector<std::string>& fingertip_markers() const { return fingertip_markers_; }
  struct SegmentMarkers {
    std::string name;
    std::string parent;  // "" = forearm
    std::vector<std::string> markers;
  };
  const std::vector<SegmentMarkers>& segments() const { return segments_; }
  // Pairs of marker names joined by a line when drawn.
  const std::vector<std::pair<std::string, std::string>>& sticks() const { return sticks_; }

  // Skin markers in the forearm frame (3 × num_markers), angles in radians.
  Eigen::Matrix3Xd MarkersInForearm(const Eigen::VectorXd& angles) const;
  // Distal end of a finger's last bone in the forearm frame.
  Eigen::Vector3d TipInForearm(const Eigen::VectorXd& angles, Finger finger) const;
  // Capsules of the forearm, palm and 15 phalanges in the forearm frame.
  std::vector<Capsule> CapsulesInForearm(const Eigen::VectorXd& angles) const;

 private:
  struct Frames;
  Frames ComputeFrames(const Eigen::VectorXd& angles) const;
  void ApplyLab2Layout();

  struct SkinMarker {
    int segment = 0;  // index into the frames of ComputeFrames
    Eigen::Vector3d local = Eigen::Vector3d::Zero();
    int slide_joint = -1;  // joint whose angle makes the skin slide
    Eigen::Vector3d slide_sin = Eigen::Vector3d::Zero();
    Eigen::Vector3d slide_cos = Eigen::Vector3d::Zero();  // times (1 - cos)
  };

  HandConfig config_;
  std::vector<std::string> marker_names_;
  std::vector<SkinMarker> markers_;
  std::vector<std::string> forearm_markers_, palm_markers_, fingertip_markers_;
  std::vector<SegmentMarkers> segments_;
  std::vector<std::pair<std::string, std::string>> sticks_;
  // Joint indices per finger: thumb {cmc_flex, cmc_abd, mcp, ip}, fingers {mcp_flex, mcp_abd, pip, dip}.
  int finger_joints_[5][4] = {};
  int wrist_flex_ = -1, wrist_dev_ = -1;
  double scale_ = 1.0;  // hand size relative to the default geometry
};

}  // namespace csw
