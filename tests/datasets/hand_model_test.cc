#include "datasets/hand_model.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/error.h"
#include "datasets/placements.h"

namespace csw {
namespace {

constexpr double kDeg = M_PI / 180.0;

TEST(HandConfig, ShippedConfigHasNinePosturesWithinTheJointLimits) {
  HandConfig c = DefaultHandConfig();
  ASSERT_EQ(c.joints.size(), 22u);
  ASSERT_EQ(c.postures.size(), 9u);
  for (int s = 0; s <= 8; ++s) {
    EXPECT_EQ(c.Posture(s).shape, s);
    EXPECT_TRUE(c.WithinLimits(c.Posture(s).angles)) << "shape " << s;
  }
  // The seed's reference finger: index for shapes 1 and 6, middle otherwise.
  EXPECT_EQ(c.Posture(1).reference_finger, "index");
  EXPECT_EQ(c.Posture(6).reference_finger, "index");
  EXPECT_EQ(c.Posture(2).reference_finger, "middle");
  EXPECT_NEAR(c.Posture(8).angles[c.JointIndex("index_mcp_abd")], 14.0 * kDeg, 1e-12);
}

TEST(HandConfig, RejectsBadDefinitionsNamingTheRule) {
  std::string good = DefaultHandConfigJson();
  // A posture beyond its joint limit.
  std::string bad = good;
  bad.replace(bad.find("\"index_pip\": 100"), 16, "\"index_pip\": 170");
  try {
    ParseHandConfig(bad, "h.json");
    FAIL() << "no exception";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("h.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("index_pip"), std::string::npos);
  }
  // Malformed JSON: ParseError with the line.
  try {
    ParseHandConfig("{\n\"joints\": [\n,]}", "h.json");
    FAIL() << "no exception";
  } catch (const ParseError& e) {
    ASSERT_TRUE(e.where().line.has_value());
    EXPECT_EQ(*e.where().line, 3);
  }
  // Unknown joint in a posture.
  bad = good;
  bad.replace(bad.find("\"wrist_flex\": 15"), 16, "\"wrist_twist\": 1");
  EXPECT_THROW(ParseHandConfig(bad), InvalidInput);
}

// The config files are read whole (core ReadTextFile): a file holding the
// shipped JSON loads to the shipped configuration; a missing file is an
// IoError naming it.
TEST(HandConfig, LoadFromFileEqualsTheShippedConfig) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("csw_hand_config_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string hand_path = (dir / "hand.json").string();
  std::ofstream(hand_path, std::ios::binary) << DefaultHandConfigJson();
  const HandConfig loaded = LoadHandConfig(hand_path);
  const HandConfig shipped = DefaultHandConfig();
  ASSERT_EQ(loaded.joints.size(), shipped.joints.size());
  for (size_t j = 0; j < shipped.joints.size(); ++j) {
    EXPECT_EQ(loaded.joints[j].name, shipped.joints[j].name);
    EXPECT_EQ(loaded.joints[j].min_rad, shipped.joints[j].min_rad);
    EXPECT_EQ(loaded.joints[j].max_rad, shipped.joints[j].max_rad);
  }
  ASSERT_EQ(loaded.postures.size(), shipped.postures.size());
  for (size_t p = 0; p < shipped.postures.size(); ++p) EXPECT_EQ(loaded.postures[p].angles, shipped.postures[p].angles);

  const std::string place_path = (dir / "placements.json").string();
  std::ofstream(place_path, std::ios::binary) << DefaultPlacementConfigJson();
  const PlacementConfig places = LoadPlacementConfig(place_path);
  const PlacementConfig shipped_places = DefaultPlacementConfig();
  ASSERT_EQ(places.placements.size(), shipped_places.placements.size());
  for (size_t p = 0; p < places.placements.size(); ++p) {
    EXPECT_EQ(places.placements[p].name, shipped_places.placements[p].name);
    EXPECT_EQ(places.placements[p].offset, shipped_places.placements[p].offset);
    EXPECT_EQ(places.placements[p].anchor, shipped_places.placements[p].anchor);
  }

  for (auto load :
       {+[](const std::string& f) { LoadHandConfig(f); }, +[](const std::string& f) { LoadPlacementConfig(f); }}) {
    try {
      load((dir / "absent.json").string());
      ADD_FAILURE() << "missing file accepted";
    } catch (const IoError& e) {
      EXPECT_NE(std::string(e.what()).find("absent.json"), std::string::npos) << e.what();
    }
  }
  std::filesystem::remove_all(dir);
}

TEST(VirtualHand, ForwardKinematicsKnownAnswers) {
  VirtualHand hand(DefaultHandConfig());
  Eigen::VectorXd q = Eigen::VectorXd::Zero(hand.num_joints());
  // Straight index: MCP at (-24, 86, 0), bones 42 + 25 + 20 mm fanned 4° towards the thumb.
  Eigen::Vector3d tip = hand.TipInForearm(q, VirtualHand::kIndex);
  EXPECT_NEAR(tip.x(), -24.0 - 87.0 * std::sin(4.0 * kDeg), 1e-9);
  EXPECT_NEAR(tip.y(), 86.0 + 87.0 * std::cos(4.0 * kDeg), 1e-9);
  EXPECT_NEAR(tip.z(), 0.0, 1e-9);
  // MCP flexed 90°: the whole straight finger points into the palm (−z).
  q[hand.config().JointIndex("index_mcp_flex")] = 90.0 * kDeg;
  tip = hand.TipInForearm(q, VirtualHand::kIndex);
  EXPECT_NEAR(tip.x(), -24.0, 1e-9);
  EXPECT_NEAR(tip.y(), 86.0, 1e-9);
  EXPECT_NEAR(tip.z(), -87.0, 1e-9);
  // Wrist flexed 90°: the palm frame turns about x, the middle MCP (-4, 88, 0) goes to (-4, 0, -88).
  q.setZero();
  q[hand.config().JointIndex("wrist_flex")] = 90.0 * kDeg;
  tip = hand.TipInForearm(q, VirtualHand::kMiddle);
  EXPECT_NEAR(tip.y(), 0.0, 1e-9);
  EXPECT_NEAR(tip.z(), -(88.0 + 46.0 + 29.0 + 21.0), 1e-9);
}

TEST(VirtualHand, FiftyMarkersWithTwoPerPhalanxAndARigidForearmCluster) {
  VirtualHand hand(DefaultHandConfig());
  EXPECT_EQ(hand.num_markers(), 50);
  EXPECT_GE(hand.forearm_markers().size(), 3u);
  int phalanges = 0;
  for (const auto& s : hand.segments()) {
    if (s.name == "palm") continue;
    ++phalanges;
    EXPECT_GE(s.markers.size(), 2u) << s.name;
  }
  EXPECT_EQ(phalanges, 15);
  EXPECT_EQ(hand.fingertip_markers().size(), 5u);
}

// Realism: soft tissue slides a fraction of a millimetre, so the distance
// between two markers of one phalanx varies by < 2 mm over the joint range.
TEST(VirtualHand, MarkerDistancesWithinAPhalanxVaryLessThanTwoMillimetres) {
  VirtualHand hand(DefaultHandConfig());
  std::mt19937_64 rng(7);
  std::map<std::string, int> col;
  for (int i = 0; i < hand.num_markers(); ++i) col[hand.marker_names()[static_cast<size_t>(i)]] = i;
  std::map<std::string, std::pair<double, double>> range;
  for (int trial = 0; trial < 400; ++trial) {
    Eigen::VectorXd q(hand.num_joints());
    for (int j = 0; j < hand.num_joints(); ++j) {
      const HandJoint& jt = hand.config().joints[static_cast<size_t>(j)];
      q[j] = jt.min_rad + (jt.max_rad - jt.min_rad) * static_cast<double>(rng() % 10001) / 10000.0;
    }
    Eigen::Matrix3Xd m = hand.MarkersInForearm(q);
    for (const auto& s : hand.segments()) {
      if (s.name == "palm") continue;
      for (size_t a = 0; a < s.markers.size(); ++a)
        for (size_t b = a + 1; b < s.markers.size(); ++b) {
          double d = (m.col(col[s.markers[a]]) - m.col(col[s.markers[b]])).norm();
          auto& r = range[s.markers[a] + "-" + s.markers[b]];
          if (trial == 0) r = {d, d};
          r.first = std::min(r.first, d);
          r.second = std::max(r.second, d);
        }
    }
  }
  ASSERT_GE(range.size(), 15u);
  double worst = 0.0;
  for (const auto& [pair, r] : range) {
    EXPECT_LT(r.second - r.first, 2.0) << pair;
    worst = std::max(worst, r.second - r.first);
  }
  RecordProperty("worst_phalanx_distance_range_mm", std::to_string(worst));
}

}  // namespace
}  // namespace csw
