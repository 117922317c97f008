#pragma once
// Hand placements of the virtual cuer, defined in the head frame from face
// landmarks (datasets/config/placements.json): where the key's reference
// fingertip goes and how the forearm is oriented there.
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <string>
#include <vector>

namespace csw {

class VirtualFace;

struct PlacementDef {
  int placement = 0;  // 0 rest, 1 side, 2 cheekbone, 3 mouth corner, 4 chin, 5 throat; 6 free space
  std::string name;
  std::vector<std::string> anchor;  // face markers whose neutral mean is the landmark
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  double frontal_rad = 0.0;
  double pitch_rad = 0.0;
  double twist_rad = 0.0;
  double contact = 0.0;  // 0-1, scales the head's movement towards the hand
};

inline constexpr int kFreeSpacePlacement = 6;

struct PlacementConfig {
  std::vector<PlacementDef> placements;         // indexed 0..6
  const PlacementDef& At(int placement) const;  // throws InvalidInput when unknown
};

// Throws ParseError (file, line) for malformed JSON, InvalidInput for a bad
// definition (missing placement, unknown anchor marker when a face is given).
PlacementConfig ParsePlacementConfig(const std::string& json_text, const std::string& file = "",
                                     const VirtualFace* face = nullptr);
PlacementConfig LoadPlacementConfig(const std::string& path, const VirtualFace* face = nullptr);
const std::string& DefaultPlacementConfigJson();
PlacementConfig DefaultPlacementConfig();

// Forearm orientation in the head frame: fingers up with the back of the hand
// forward, then frontal (towards the cuer's left), pitch and twist.
Eigen::Matrix3d ForearmOrientation(double frontal_rad, double pitch_rad, double twist_rad);
// Target point of a placement in the head frame (neutral face).
Eigen::Vector3d PlacementTarget(const PlacementDef& def, const VirtualFace& face);

}  // namespace csw
