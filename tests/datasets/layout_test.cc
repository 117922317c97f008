// The virtual cuer's second marker layout ("lab2", SimulateOptions::layout):
// its marker set, the marker counts of a simulated take, and the throat law
// (full head translation, part of the head rotation) checked against the
// simulator's own ground truth.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "core/error.h"
#include "core/markerset.h"
#include "datasets/virtual_cuer.h"
#include "synth/phonetics.h"

namespace csw {
namespace {

SimulateOptions Lab2Options() {
  SimulateOptions o;
  o.layout = "lab2";
  o.audio = false;
  return o;
}

const SimulationResult& Lab2Sentence() {
  static const SimulationResult r = [] {
    VirtualCuer cuer{Lab2Options()};
    PhonetiseOptions po;
    po.synthesize_audio = false;
    po.rate_wpm = SimulateOptions().speech_rate_wpm;
    return cuer.SimulateUtterance("lab2_test", Phonetise("La petite fille regarde la mer.", po));
  }();
  return r;
}

TEST(SimulatorLayout, UnknownLayoutIsRefusedNamingTheKnownOnes) {
  SimulateOptions o;
  o.layout = "lab3";
  EXPECT_NE(o.Check().find("default, lab2"), std::string::npos) << o.Check();
  EXPECT_THROW(VirtualCuer{o}, InvalidInput);
  EXPECT_THROW(VirtualFace("lab3"), InvalidInput);
}

TEST(SimulatorLayout, Lab2MarkerSetValidatesWithOtherNamesAndCounts) {
  VirtualCuer lab2{Lab2Options()};
  VirtualCuer standard{SimulateOptions()};
  // ParseMarkerSet checks roles are disjoint, segments well formed, sticks known.
  const MarkerSet set = ParseMarkerSet(MarkerSetToJson(lab2.MakeMarkerSet()), "lab2.json");
  const MarkerSet def = standard.MakeMarkerSet();
  EXPECT_EQ(set.head_cluster.size(), 5u);
  EXPECT_EQ(set.face.size(), 20u);
  EXPECT_EQ(set.throat.size(), 3u);
  EXPECT_EQ(set.forearm_cluster.size(), 6u);
  EXPECT_EQ(set.hand_segments.size(), 16u);
  EXPECT_EQ(set.AllMarkers().size(), 28u + 43u);
  // Every phalanx has two markers (the default distal phalanges have three).
  for (const auto& s : set.hand_segments) {
    if (s.name == "palm") continue;
    EXPECT_EQ(s.markers.size(), 2u) << s.name;
  }
  // No marker name in common with the default layout.
  const std::vector<std::string> a = set.AllMarkers(), b = def.AllMarkers();
  const std::set<std::string> other(b.begin(), b.end());
  for (const auto& n : a) EXPECT_EQ(other.count(n), 0u) << n;
  // Throat markers carry no head weight: their law is not a weighted blend.
  for (const auto& t : set.throat) EXPECT_FALSE(t.head_weight.has_value()) << t.marker;
  // The hand is 8 % smaller: a fingertip's distance from the wrist centre scales.
  const HandConfig config = DefaultHandConfig();
  const Eigen::VectorXd rest = config.Posture(0).angles;
  EXPECT_NEAR(lab2.hand().TipInForearm(rest, VirtualHand::kMiddle).norm(),
              kLab2HandScale * standard.hand().TipInForearm(rest, VirtualHand::kMiddle).norm(), 1e-9);
}

// SimulateOptions::hand_scale: another cuer's hand, every segment scaled (a
// fingertip 0.8 times as far from the wrist centre, on either layout);
// out-of-range sizes refused.
TEST(SimulatorLayout, HandScaleScalesTheHand) {
  const HandConfig config = DefaultHandConfig();
  const Eigen::VectorXd rest = config.Posture(0).angles;
  for (const std::string layout : {"default", "lab2"}) {
    SimulateOptions o;
    o.layout = layout;
    const VirtualCuer base(o);
    o.hand_scale = 0.8;
    const VirtualCuer small(o);
    EXPECT_NEAR(small.hand().TipInForearm(rest, VirtualHand::kIndex).norm(),
                0.8 * base.hand().TipInForearm(rest, VirtualHand::kIndex).norm(), 1e-9)
        << layout;
  }
  SimulateOptions bad;
  bad.hand_scale = 0.3;
  EXPECT_EQ(bad.Check(), "hand_scale must be in [0.5, 2]");
  EXPECT_THROW(VirtualCuer{bad}, InvalidInput);
  EXPECT_THROW(VirtualHand(DefaultHandConfig(), "default", 3.0), InvalidInput);
}

TEST(SimulatorLayout, Lab2TakeHasTheStatedMarkerCounts) {
  const SimulationResult& r = Lab2Sentence();
  EXPECT_EQ(r.take.marker_names.size(), 28u + 43u);
  EXPECT_EQ(r.face_columns.size(), 28u);
  EXPECT_EQ(r.hand_columns.size(), 43u);
  VirtualCuer cuer{Lab2Options()};
  const MarkerSet set = cuer.MakeMarkerSet();
  const MarkerBinding b = BindMarkerSet(set, r.take.marker_names, true, r.take.name);
  EXPECT_TRUE(b.missing.empty());
  EXPECT_GT(r.frames(), 100);
}

// The throat law, from the simulator's ground truth: in the reference head
// frame, a throat marker's clean position is Exp(0.4 r) p + t, where (r, t) is
// the head motion of the frame and p its position before head motion; a face
// marker's is Exp(r) p + t. p comes from the articulation truth.
TEST(SimulatorLayout, Lab2ThroatFollowsHeadTranslationFullyAndRotationPartly) {
  const SimulationResult& r = Lab2Sentence();
  VirtualCuer cuer{Lab2Options()};
  const VirtualFace& face = cuer.face();
  ASSERT_EQ(face.throat_markers().size(), 3u);
  double worst_throat = 0, worst_blend = 0, largest_rotation = 0;
  for (int64_t f = 0; f < r.frames(); f += 7) {
    HeadMotion m;
    m.rotation = r.head_motion.block<1, 3>(f, 0).transpose();
    m.translation = r.head_motion.block<1, 3>(f, 3).transpose();
    largest_rotation = std::max(largest_rotation, m.rotation.norm());
    const ArticulatoryVector p = r.articulation.row(f).transpose();
    const Eigen::Matrix3Xd in_head = face.MarkersInHead(p);
    for (const auto& name : face.throat_markers()) {
      const int i = face.MarkerIndex(name);
      const float* c = r.clean.at(f, i);
      const Eigen::Vector3d lab(c[0], c[1], c[2]);
      const Eigen::Vector3d x = r.head_reference.inverse() * lab;
      const Eigen::Vector3d p0 = in_head.col(i);
      const double angle = kLab2ThroatRotationWeight * m.rotation.norm();
      Eigen::Matrix3d rot = Eigen::Matrix3d::Identity();
      if (angle > 0) rot = Eigen::AngleAxisd(angle, m.rotation.normalized()).toRotationMatrix();
      worst_throat = std::max(worst_throat, (x - (rot * p0 + m.translation)).norm());
      // The weighted blend a face model assumes (any weight w: here the
      // rotation's, 0.4) misses the translation by 0.6 t.
      const Eigen::Vector3d blend = m.Weighted(kLab2ThroatRotationWeight) * p0;
      worst_blend = std::max(worst_blend, (x - blend).norm());
    }
  }
  EXPECT_GT(largest_rotation, 0.5 * M_PI / 180.0);  // the head does turn
  EXPECT_LT(worst_throat, 1e-3);                    // float storage of the clean positions
  EXPECT_GT(worst_blend, 0.5);
}

}  // namespace
}  // namespace csw
