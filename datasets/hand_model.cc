#include "datasets/hand_model.h"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"
#include "core/file_util.h"
#include "core/json_util.h"
#include "datasets/face_model.h"

namespace csw {

namespace {

using nlohmann::json;
constexpr double kDeg = M_PI / 180.0;

Eigen::Matrix3d Rx(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitX()).toRotationMatrix(); }
Eigen::Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }
Eigen::Matrix3d Rz(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()).toRotationMatrix(); }

Eigen::Isometry3d Make(const Eigen::Matrix3d& r, const Eigen::Vector3d& t) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  x.linear() = r;
  x.translation() = t;
  return x;
}

// Geometry of the hand (millimetres, degrees), in the palm frame (origin at the
// wrist centre, same axes as the forearm frame when the wrist is neutral).
struct FingerGeometry {
  const char* name;
  const char* letter;
  Eigen::Vector3d base;  // MCP (fingers) or CMC (thumb) joint centre in the palm frame
  double fan_deg;        // rest direction in the palm plane, positive towards the thumb
  double length[3];
  double radius[3];
};

const FingerGeometry kFingers[5] = {
    {"thumb", "T", {-20.0, 22.0, -12.0}, 50.0, {45.0, 32.0, 26.0}, {11.0, 9.0, 8.0}},
    {"index", "I", {-24.0, 86.0, 0.0}, 4.0, {42.0, 25.0, 20.0}, {9.0, 8.0, 7.0}},
    {"middle", "M", {-4.0, 88.0, 0.0}, 0.0, {46.0, 29.0, 21.0}, {9.0, 8.0, 7.0}},
    {"ring", "R", {14.0, 83.0, -2.0}, -4.0, {43.0, 27.0, 20.0}, {8.5, 7.5, 6.5}},
    {"little", "L", {30.0, 75.0, -5.0}, -9.0, {34.0, 20.0, 18.0}, {8.0, 7.0, 6.0}},
};
constexpr double kThumbPalmarTiltDeg = -25.0;  // metacarpal rest direction towards the palm
constexpr double kThumbTwistDeg = -55.0;       // thumb nail faces sideways

// Frame indices: 0 forearm, 1 palm, 2 + 3 * finger + phalanx.
int SegmentIndex(int finger, int phalanx) { return 2 + 3 * finger + phalanx; }

}  // namespace

// ---------------------------------------------------------------- config

int HandConfig::JointIndex(const std::string& name) const {
  for (size_t i = 0; i < joints.size(); ++i)
    if (joints[i].name == name) return static_cast<int>(i);
  return -1;
}

const HandPosture& HandConfig::Posture(int shape) const {
  if (shape < 0 || shape >= static_cast<int>(postures.size()))
    throw InvalidInput("hand configuration has no posture for shape " + std::to_string(shape));
  return postures[static_cast<size_t>(shape)];
}

Eigen::VectorXd HandConfig::Clamp(const Eigen::VectorXd& angles) const {
  Eigen::VectorXd out = angles;
  for (size_t i = 0; i < joints.size(); ++i)
    out[static_cast<Eigen::Index>(i)] =
        std::clamp(out[static_cast<Eigen::Index>(i)], joints[i].min_rad, joints[i].max_rad);
  return out;
}

bool HandConfig::WithinLimits(const Eigen::VectorXd& angles, double slack_rad) const {
  if (angles.size() != static_cast<Eigen::Index>(joints.size())) return false;
  for (size_t i = 0; i < joints.size(); ++i) {
    double a = angles[static_cast<Eigen::Index>(i)];
    if (a < joints[i].min_rad - slack_rad || a > joints[i].max_rad + slack_rad) return false;
  }
  return true;
}

HandConfig ParseHandConfig(const std::string& json_text, const std::string& file) {
  const std::string where = file.empty() ? std::string("<hand config>") : file;
  json j = ParseJsonText(json_text, where);
  auto fail = [&](const std::string& what) -> void { throw InvalidInput(where + ": hand configuration: " + what); };
  if (!j.is_object()) fail("must be a JSON object");
  if (!j.contains("joints") || !j["joints"].is_array()) fail("needs a \"joints\" array");
  if (!j.contains("postures") || !j["postures"].is_array()) fail("needs a \"postures\" array");
  HandConfig config;
  static const char* kRequired[] = {
      "wrist_flex",      "wrist_dev",      "thumb_cmc_flex", "thumb_cmc_abd", "thumb_mcp",       "thumb_ip",
      "index_mcp_flex",  "index_mcp_abd",  "index_pip",      "index_dip",     "middle_mcp_flex", "middle_mcp_abd",
      "middle_pip",      "middle_dip",     "ring_mcp_flex",  "ring_mcp_abd",  "ring_pip",        "ring_dip",
      "little_mcp_flex", "little_mcp_abd", "little_pip",     "little_dip"};
  try {
    for (const json& jj : j["joints"]) {
      HandJoint joint;
      joint.name = jj.at("name").get<std::string>();
      joint.min_rad = jj.at("min").get<double>() * kDeg;
      joint.max_rad = jj.at("max").get<double>() * kDeg;
      if (!(joint.min_rad < joint.max_rad)) fail("joint \"" + joint.name + "\" needs min < max");
      if (config.JointIndex(joint.name) >= 0) fail("joint \"" + joint.name + "\" is defined twice");
      config.joints.push_back(joint);
    }
    for (const char* name : kRequired)
      if (config.JointIndex(name) < 0) fail(std::string("joint \"") + name + "\" is missing");
    if (config.joints.size() != std::size(kRequired)) fail("unknown joint (the hand has exactly 22 joints)");
    config.postures.resize(9);
    std::vector<bool> seen(9, false);
    for (const json& jp : j["postures"]) {
      int shape = jp.at("shape").get<int>();
      if (shape < 0 || shape > 8) fail("posture shape " + std::to_string(shape) + " is not in 0-8");
      if (seen[static_cast<size_t>(shape)]) fail("posture for shape " + std::to_string(shape) + " is defined twice");
      seen[static_cast<size_t>(shape)] = true;
      HandPosture posture;
      posture.shape = shape;
      posture.name = jp.value("name", "");
      posture.reference_finger = jp.value("reference_finger", "middle");
      if (posture.reference_finger != "index" && posture.reference_finger != "middle")
        fail("posture " + std::to_string(shape) + ": reference_finger must be \"index\" or \"middle\"");
      posture.angles = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(config.joints.size()));
      if (jp.contains("angles")) {
        for (auto it = jp["angles"].begin(); it != jp["angles"].end(); ++it) {
          int k = config.JointIndex(it.key());
          if (k < 0) fail("posture " + std::to_string(shape) + " names unknown joint \"" + it.key() + "\"");
          posture.angles[k] = it.value().get<double>() * kDeg;
        }
      }
      if (!config.WithinLimits(posture.angles)) {
        for (size_t i = 0; i < config.joints.size(); ++i) {
          double a = posture.angles[static_cast<Eigen::Index>(i)];
          if (a < config.joints[i].min_rad || a > config.joints[i].max_rad)
            fail("posture " + std::to_string(shape) + ": joint \"" + config.joints[i].name +
                 "\" is outside its limits");
        }
      }
      config.postures[static_cast<size_t>(shape)] = posture;
    }
    for (int s = 0; s <= 8; ++s)
      if (!seen[static_cast<size_t>(s)]) fail("no posture for shape " + std::to_string(s));
  } catch (const json::exception& e) {
    fail(std::string("malformed entry: ") + e.what());
  }
  return config;
}

HandConfig LoadHandConfig(const std::string& path) { return ParseHandConfig(ReadTextFile(path), path); }

HandConfig DefaultHandConfig() { return ParseHandConfig(DefaultHandConfigJson(), "datasets/config/hand.json"); }

// ---------------------------------------------------------------- model

struct VirtualHand::Frames {
  Eigen::Isometry3d frame[17];
};

VirtualHand::VirtualHand(HandConfig config) : VirtualHand(std::move(config), "default") {}

VirtualHand::VirtualHand(HandConfig config, const std::string& layout) : VirtualHand(std::move(config), layout, 1.0) {}

VirtualHand::VirtualHand(HandConfig config, const std::string& layout, double size) : config_(std::move(config)) {
  if (layout != "default" && layout != "lab2") throw InvalidInput("unknown simulator layout \"" + layout + "\"");
  if (!(size >= 0.5 && size <= 2.0)) throw InvalidInput("hand size must be in [0.5, 2] times the layout's");
  const bool lab2 = layout == "lab2";
  scale_ = (lab2 ? kLab2HandScale : 1.0) * size;
  static const char* kSuffix[5][4] = {{"thumb_cmc_flex", "thumb_cmc_abd", "thumb_mcp", "thumb_ip"},
                                      {"index_mcp_flex", "index_mcp_abd", "index_pip", "index_dip"},
                                      {"middle_mcp_flex", "middle_mcp_abd", "middle_pip", "middle_dip"},
                                      {"ring_mcp_flex", "ring_mcp_abd", "ring_pip", "ring_dip"},
                                      {"little_mcp_flex", "little_mcp_abd", "little_pip", "little_dip"}};
  for (int f = 0; f < 5; ++f)
    for (int k = 0; k < 4; ++k) {
      finger_joints_[f][k] = config_.JointIndex(kSuffix[f][k]);
      if (finger_joints_[f][k] < 0) throw InvalidInput(std::string("hand configuration lacks joint ") + kSuffix[f][k]);
    }
  wrist_flex_ = config_.JointIndex("wrist_flex");
  wrist_dev_ = config_.JointIndex("wrist_dev");
  if (wrist_flex_ < 0 || wrist_dev_ < 0) throw InvalidInput("hand configuration lacks the wrist joints");

  auto add = [&](const std::string& name, int segment, Eigen::Vector3d local) {
    marker_names_.push_back(name);
    SkinMarker m;
    m.segment = segment;
    m.local = scale_ * local;
    markers_.push_back(m);
    return static_cast<int>(markers_.size()) - 1;
  };
  // Forearm: a rigid cluster of five plus the two styloid processes.
  const std::vector<std::pair<std::string, Eigen::Vector3d>> forearm = {
      {"FA1", {0.0, -80.0, 29.0}},  {"FA2", {-24.0, -140.0, 22.0}}, {"FA3", {24.0, -150.0, 20.0}},
      {"FA4", {2.0, -205.0, 30.0}}, {"FA5", {-30.0, -60.0, 6.0}},   {"WRR", {-31.0, -12.0, 2.0}},
      {"WRU", {29.0, -12.0, 8.0}}};
  for (const auto& [name, p] : forearm) {
    add(name, 0, p);
    forearm_markers_.push_back(name);
  }
  // Palm (dorsum): knuckles slide a little over the MCP heads.
  SegmentMarkers palm{"palm", "", {}};
  for (int f = 1; f < 5; ++f) {
    int i = add(std::string("KN") + kFingers[f].letter, 1, kFingers[f].base + Eigen::Vector3d(0.0, 0.0, 12.0));
    markers_[static_cast<size_t>(i)].slide_joint = finger_joints_[f][0];
    markers_[static_cast<size_t>(i)].slide_sin = Eigen::Vector3d(0.0, 0.6, 0.0);
    markers_[static_cast<size_t>(i)].slide_cos = Eigen::Vector3d(0.0, 0.0, -0.4);
    palm.markers.push_back(marker_names_.back());
  }
  for (const auto& [name, p] : std::vector<std::pair<std::string, Eigen::Vector3d>>{{"PD1", {-20.0, 45.0, 15.0}},
                                                                                    {"PD2", {0.0, 48.0, 16.0}},
                                                                                    {"PD3", {20.0, 42.0, 14.0}},
                                                                                    {"PTB", {-30.0, 18.0, 8.0}}}) {
    add(name, 1, p);
    palm.markers.push_back(name);
  }
  palm_markers_ = palm.markers;
  segments_.push_back(palm);
  // Two dorsal markers per phalanx and a nail marker on each finger tip.
  for (int f = 0; f < 5; ++f) {
    const FingerGeometry& g = kFingers[f];
    for (int p = 0; p < 3; ++p) {
      SegmentMarkers seg;
      seg.name = std::string(g.name) + std::to_string(p + 1);
      seg.parent = p == 0 ? "palm" : std::string(g.name) + std::to_string(p);
      const int segment = SegmentIndex(f, p);
      const double len = g.length[p], r = g.radius[p];
      const std::string stem = std::string(g.letter) + std::to_string(p + 1);
      // Proximal marker: dragged by the joint at the segment's base.
      int a = add(stem + "P", segment, Eigen::Vector3d(0.0, 0.3 * len, r));
      int base_joint = p == 0 ? finger_joints_[f][0] : finger_joints_[f][p + 1];
      markers_[static_cast<size_t>(a)].slide_joint = base_joint;
      markers_[static_cast<size_t>(a)].slide_sin = Eigen::Vector3d(0.0, -0.5, 0.0);
      markers_[static_cast<size_t>(a)].slide_cos = Eigen::Vector3d(0.0, 0.0, -0.3);
      // Distal marker: dragged by the next joint, if any.
      int b = add(stem + "D", segment, Eigen::Vector3d(0.0, 0.72 * len, r));
      if (p < 2) {
        markers_[static_cast<size_t>(b)].slide_joint = finger_joints_[f][p + 2];
        markers_[static_cast<size_t>(b)].slide_sin = Eigen::Vector3d(0.0, 0.4, 0.0);
        markers_[static_cast<size_t>(b)].slide_cos = Eigen::Vector3d(0.0, 0.0, -0.2);
      }
      seg.markers = {stem + "P", stem + "D"};
      if (p == 2) {
        std::string tip = std::string(g.letter) + "TIP";
        add(tip, segment, Eigen::Vector3d(0.0, len - 2.0, 0.6 * r));
        seg.markers.push_back(tip);
        fingertip_markers_.push_back(tip);
      }
      segments_.push_back(seg);
      if (p == 0) {
        sticks_.emplace_back(f == 0 ? "PTB" : std::string("KN") + g.letter, stem + "P");
      } else {
        sticks_.emplace_back(std::string(g.letter) + std::to_string(p) + "D", stem + "P");
      }
      sticks_.emplace_back(stem + "P", stem + "D");
      if (p == 2) sticks_.emplace_back(stem + "D", std::string(g.letter) + "TIP");
    }
  }
  for (const auto& [a, b] : std::vector<std::pair<std::string, std::string>>{{"FA1", "FA2"},
                                                                             {"FA1", "FA3"},
                                                                             {"FA2", "FA4"},
                                                                             {"FA3", "FA4"},
                                                                             {"FA5", "FA2"},
                                                                             {"WRR", "FA5"},
                                                                             {"WRU", "FA1"},
                                                                             {"WRR", "PTB"},
                                                                             {"WRU", "PD3"},
                                                                             {"PTB", "PD1"},
                                                                             {"PD1", "PD2"},
                                                                             {"PD2", "PD3"},
                                                                             {"KNI", "KNM"},
                                                                             {"KNM", "KNR"},
                                                                             {"KNR", "KNL"},
                                                                             {"PD1", "KNI"},
                                                                             {"PD2", "KNM"},
                                                                             {"PD3", "KNL"}})
    sticks_.emplace_back(a, b);
  if (lab2) ApplyLab2Layout();
}

void VirtualHand::ApplyLab2Layout() {
  // Markers dropped: FA5, PD2 and the proximal marker of each distal phalanx.
  auto dropped = [](const std::string& n) {
    return n == "FA5" || n == "PD2" || (n.size() == 3 && n[1] == '3' && n[2] == 'P');
  };
  auto rename = [](const std::string& n) { return "RH_" + n; };
  std::vector<std::string> names;
  std::vector<SkinMarker> markers;
  for (size_t i = 0; i < marker_names_.size(); ++i) {
    if (dropped(marker_names_[i])) continue;
    names.push_back(rename(marker_names_[i]));
    markers.push_back(markers_[i]);
  }
  marker_names_ = std::move(names);
  markers_ = std::move(markers);
  auto filter = [&](std::vector<std::string>& list) {
    std::vector<std::string> out;
    for (const auto& n : list)
      if (!dropped(n)) out.push_back(rename(n));
    list = std::move(out);
  };
  filter(forearm_markers_);
  filter(palm_markers_);
  filter(fingertip_markers_);
  for (SegmentMarkers& seg : segments_) filter(seg.markers);
  // Sticks: a dropped distal marker's two sticks become one.
  std::vector<std::pair<std::string, std::string>> sticks;
  for (const auto& [a, b] : sticks_) {
    if (dropped(a) && dropped(b)) continue;
    if (dropped(b)) {
      for (const auto& [c, d] : sticks_)
        if (c == b && !dropped(d)) sticks.emplace_back(rename(a), rename(d));
      continue;
    }
    if (dropped(a)) continue;
    sticks.emplace_back(rename(a), rename(b));
  }
  sticks_ = std::move(sticks);
}

VirtualHand::Frames VirtualHand::ComputeFrames(const Eigen::VectorXd& angles) const {
  Frames fr;
  fr.frame[0] = Eigen::Isometry3d::Identity();
  fr.frame[1] = Make(Rx(-angles[wrist_flex_]) * Rz(angles[wrist_dev_]), Eigen::Vector3d::Zero());
  for (int f = 0; f < 5; ++f) {
    const FingerGeometry& g = kFingers[f];
    const int* jt = finger_joints_[f];
    Eigen::Matrix3d base;
    if (f == 0) {
      base = Rz(g.fan_deg * kDeg) * Rx(kThumbPalmarTiltDeg * kDeg) * Rz(angles[jt[1]]) * Rx(-angles[jt[0]]) *
             Ry(kThumbTwistDeg * kDeg);
    } else {
      base = Rz(g.fan_deg * kDeg) * Rz(angles[jt[1]]) * Rx(-angles[jt[0]]);
    }
    Eigen::Isometry3d x = fr.frame[1] * Make(base, scale_ * g.base);
    fr.frame[SegmentIndex(f, 0)] = x;
    x = x * Make(Rx(-angles[jt[2]]), Eigen::Vector3d(0.0, scale_ * g.length[0], 0.0));
    fr.frame[SegmentIndex(f, 1)] = x;
    x = x * Make(Rx(-angles[jt[3]]), Eigen::Vector3d(0.0, scale_ * g.length[1], 0.0));
    fr.frame[SegmentIndex(f, 2)] = x;
  }
  return fr;
}

Eigen::Matrix3Xd VirtualHand::MarkersInForearm(const Eigen::VectorXd& angles) const {
  Frames fr = ComputeFrames(angles);
  Eigen::Matrix3Xd out(3, num_markers());
  for (size_t i = 0; i < markers_.size(); ++i) {
    const SkinMarker& m = markers_[i];
    Eigen::Vector3d local = m.local;
    if (m.slide_joint >= 0) {
      double a = angles[m.slide_joint];
      local += m.slide_sin * std::sin(a) + m.slide_cos * (1.0 - std::cos(a));
    }
    out.col(static_cast<Eigen::Index>(i)) = fr.frame[m.segment] * local;
  }
  return out;
}

Eigen::Vector3d VirtualHand::TipInForearm(const Eigen::VectorXd& angles, Finger finger) const {
  Frames fr = ComputeFrames(angles);
  return fr.frame[SegmentIndex(finger, 2)] * Eigen::Vector3d(0.0, scale_ * kFingers[finger].length[2], 0.0);
}

std::vector<Capsule> VirtualHand::CapsulesInForearm(const Eigen::VectorXd& angles) const {
  Frames fr = ComputeFrames(angles);
  std::vector<Capsule> out;
  const double k = scale_;
  out.push_back({"forearm", k * Eigen::Vector3d(0.0, -25.0, 0.0), k * Eigen::Vector3d(0.0, -260.0, -5.0), k * 30.0});
  const Eigen::Isometry3d& palm = fr.frame[1];
  out.push_back(
      {"palm", palm * (k * Eigen::Vector3d(-14.0, 12.0, 0.0)), palm * (k * Eigen::Vector3d(-20.0, 80.0, 0.0)), k * 12});
  out.push_back(
      {"palm", palm * (k * Eigen::Vector3d(0.0, 12.0, 0.0)), palm * (k * Eigen::Vector3d(-2.0, 82.0, 0.0)), k * 12});
  out.push_back(
      {"palm", palm * (k * Eigen::Vector3d(14.0, 12.0, -2.0)), palm * (k * Eigen::Vector3d(26.0, 72.0, -4.0)), k * 12});
  for (int f = 0; f < 5; ++f)
    for (int p = 0; p < 3; ++p) {
      const Eigen::Isometry3d& x = fr.frame[SegmentIndex(f, p)];
      out.push_back({std::string(kFingers[f].name) + std::to_string(p + 1), x.translation(),
                     x * Eigen::Vector3d(0.0, k * kFingers[f].length[p], 0.0), k * kFingers[f].radius[p] * 0.85});
    }
  return out;
}

}  // namespace csw
