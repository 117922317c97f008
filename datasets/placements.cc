#include "datasets/placements.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "core/error.h"
#include "core/file_util.h"
#include "core/json_util.h"
#include "datasets/face_model.h"

namespace csw {

namespace {
using nlohmann::json;
constexpr double kDeg = M_PI / 180.0;
}  // namespace

const PlacementDef& PlacementConfig::At(int placement) const {
  if (placement < 0 || placement >= static_cast<int>(placements.size()))
    throw InvalidInput("placement configuration has no placement " + std::to_string(placement));
  return placements[static_cast<size_t>(placement)];
}

PlacementConfig ParsePlacementConfig(const std::string& json_text, const std::string& file, const VirtualFace* face) {
  const std::string where = file.empty() ? std::string("<placement config>") : file;
  json j = ParseJsonText(json_text, where);
  auto fail = [&](const std::string& what) -> void {
    throw InvalidInput(where + ": placement configuration: " + what);
  };
  if (!j.is_object() || !j.contains("placements") || !j["placements"].is_array()) fail("needs a \"placements\" array");
  PlacementConfig config;
  config.placements.resize(kFreeSpacePlacement + 1);
  std::vector<bool> seen(kFreeSpacePlacement + 1, false);
  try {
    for (const json& jp : j["placements"]) {
      PlacementDef d;
      d.placement = jp.at("placement").get<int>();
      if (d.placement < 0 || d.placement > kFreeSpacePlacement)
        fail("placement " + std::to_string(d.placement) + " is not in 0-" + std::to_string(kFreeSpacePlacement));
      if (seen[static_cast<size_t>(d.placement)])
        fail("placement " + std::to_string(d.placement) + " is defined twice");
      seen[static_cast<size_t>(d.placement)] = true;
      d.name = jp.value("name", "");
      d.anchor = jp.at("anchor").get<std::vector<std::string>>();
      if (d.anchor.empty()) fail("placement " + std::to_string(d.placement) + " needs at least one anchor marker");
      if (face) {
        for (const auto& a : d.anchor)
          if (face->MarkerIndex(a) < 0)
            fail("placement " + std::to_string(d.placement) + " anchors on unknown face marker \"" + a + "\"");
      }
      auto off = jp.at("offset").get<std::vector<double>>();
      if (off.size() != 3) fail("placement " + std::to_string(d.placement) + ": offset needs 3 numbers");
      d.offset = Eigen::Vector3d(off[0], off[1], off[2]);
      d.frontal_rad = jp.value("frontal_deg", 0.0) * kDeg;
      d.pitch_rad = jp.value("pitch_deg", 0.0) * kDeg;
      d.twist_rad = jp.value("twist_deg", 0.0) * kDeg;
      d.contact = jp.value("contact", 0.0);
      if (!(d.contact >= 0.0 && d.contact <= 1.0))
        fail("placement " + std::to_string(d.placement) + ": contact must be in [0, 1]");
      config.placements[static_cast<size_t>(d.placement)] = d;
    }
  } catch (const json::exception& e) {
    fail(std::string("malformed entry: ") + e.what());
  }
  for (int p = 0; p <= kFreeSpacePlacement; ++p)
    if (!seen[static_cast<size_t>(p)]) fail("no definition for placement " + std::to_string(p));
  return config;
}

PlacementConfig LoadPlacementConfig(const std::string& path, const VirtualFace* face) {
  return ParsePlacementConfig(ReadTextFile(path), path, face);
}

PlacementConfig DefaultPlacementConfig() {
  static const VirtualFace face;
  return ParsePlacementConfig(DefaultPlacementConfigJson(), "datasets/config/placements.json", &face);
}

Eigen::Matrix3d ForearmOrientation(double frontal_rad, double pitch_rad, double twist_rad) {
  Eigen::Matrix3d r0;
  r0.col(0) = Eigen::Vector3d(-1.0, 0.0, 0.0);  // ulnar side towards the cuer's right
  r0.col(1) = Eigen::Vector3d(0.0, 0.0, 1.0);   // fingers up
  r0.col(2) = Eigen::Vector3d(0.0, 1.0, 0.0);   // back of the hand forward
  return Eigen::AngleAxisd(frontal_rad, Eigen::Vector3d::UnitY()).toRotationMatrix() * r0 *
         Eigen::AngleAxisd(pitch_rad, Eigen::Vector3d::UnitX()).toRotationMatrix() *
         Eigen::AngleAxisd(twist_rad, Eigen::Vector3d::UnitY()).toRotationMatrix();
}

Eigen::Vector3d PlacementTarget(const PlacementDef& def, const VirtualFace& face) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (const auto& a : def.anchor) {
    int i = face.MarkerIndex(a);
    if (i < 0) throw InvalidInput("placement \"" + def.name + "\" anchors on unknown face marker \"" + a + "\"");
    sum += face.neutral().col(i);
  }
  return sum / static_cast<double>(def.anchor.size()) + def.offset;
}

}  // namespace csw
