// The virtual signer's ground truth checked against its own output: the
// skeleton's forward kinematics (hand-derived T-pose), phase boundaries at the
// speed minima of the true motion, transition durations equal to the law
// recomputed from the take's joint positions and orientations, tiers.
#include "datasets/virtual_signer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>

#include "core/error.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

const LabelTier& Tier(const Take& take, const std::string& name) {
  for (const LabelTier& t : take.tiers)
    if (t.name == name) return t;
  throw InvalidInput("no tier " + name);
}

// Pose of one frame of a take from its stored markers (clean) and orientations.
SkeletonPose FramePose(const MarkerArray& markers, const OrientationArray& orientations, int64_t frame) {
  SkeletonPose p;
  p.positions.resize(3, markers.markers());
  for (int64_t j = 0; j < markers.markers(); ++j) {
    for (int c = 0; c < 3; ++c) p.positions(c, j) = markers.at(frame, j)[c];
    const float* q = orientations.at(frame, j);
    p.orientations.emplace_back(q[0], q[1], q[2], q[3]);
  }
  return p;
}

// Unfiltered central-difference speed of one marker (mm/s).
std::vector<double> Speed(const MarkerArray& m, int64_t marker, double rate) {
  std::vector<double> s(static_cast<size_t>(m.frames()), std::nan(""));
  for (int64_t f = 1; f + 1 < m.frames(); ++f) {
    double d2 = 0;
    for (int c = 0; c < 3; ++c) {
      const double d = m.at(f + 1, marker)[c] - m.at(f - 1, marker)[c];
      d2 += d * d;
    }
    s[static_cast<size_t>(f)] = std::sqrt(d2) * rate / 2;
  }
  return s;
}

TEST(VirtualSigner, SkeletonIsABvhHierarchyWithTPoseAtZero) {
  const VirtualSigner signer(SignerOptions{});
  const auto& sk = signer.skeleton();
  ASSERT_EQ(sk.size(), 28u);  // 5 torso joints + head end, 2 × (8 arm/hand joints + 3 end sites)
  EXPECT_EQ(sk[0].channels.size(), 6u);
  EXPECT_EQ(sk[0].channels[0], "Xposition");
  int ends = 0;
  for (size_t j = 0; j < sk.size(); ++j) {
    EXPECT_LT(sk[j].parent, static_cast<int>(j));
    if (sk[j].end_site) {
      ++ends;
      EXPECT_TRUE(sk[j].channels.empty());
    } else if (j > 0) {
      EXPECT_EQ(sk[j].channels, (std::vector<std::string>{"Zrotation", "Xrotation", "Yrotation"}));
    }
  }
  EXPECT_EQ(ends, 7);
  // All channels zero: the T-pose; the right wrist is at the sum of its chain's
  // offsets: x = -(40 + 150 + 280 + 250), y = 1000 + 120 + 250 + 170.
  Eigen::VectorXd zero = Eigen::VectorXd::Zero(6 + 3 * (28 - 7 - 1));
  const SkeletonPose pose = ForwardKinematics(sk, zero);
  EXPECT_NEAR(pose.positions(0, signer.right_wrist()), -720.0, 1e-9);
  EXPECT_NEAR(pose.positions(1, signer.right_wrist()), 1540.0, 1e-9);
  EXPECT_NEAR(pose.positions(2, signer.right_wrist()), 0.0, 1e-9);
  EXPECT_NEAR(pose.positions(0, signer.left_wrist()), 720.0, 1e-9);
  // A shoulder rotation of +90 degrees about z hangs the right arm down: the
  // wrist is 280 + 250 mm below the shoulder (x = -190, y = 1540).
  const int shoulder = signer.right_wrist() - 2;
  Eigen::VectorXd down = zero;
  int channel = 6;  // joint `shoulder`'s first channel (Zrotation)
  for (int j = 1; j < shoulder; ++j) channel += static_cast<int>(sk[static_cast<size_t>(j)].channels.size());
  down[channel] = 90.0;
  const SkeletonPose hang = ForwardKinematics(sk, down);
  EXPECT_NEAR(hang.positions(0, signer.right_wrist()), -190.0, 1e-9);
  EXPECT_NEAR(hang.positions(1, signer.right_wrist()), 1540.0 - 530.0, 1e-9);
}

TEST(VirtualSigner, TakesCarryTheSkeletonOrientationsAndTiers) {
  const SignerOptions o;
  const VirtualSigner signer(o);
  const SignerTake t = signer.SimulateTake(3);
  const Take& take = t.take;
  EXPECT_EQ(take.rate_hz, 100.0);
  ASSERT_EQ(take.marker_names.size(), take.skeleton.size());
  for (size_t j = 0; j < take.skeleton.size(); ++j) EXPECT_EQ(take.marker_names[j], take.skeleton[j].name);
  ASSERT_EQ(take.orientations.frames(), take.frames());
  // End sites carry the parent's orientation; quaternions are unit.
  for (int64_t f = 0; f < take.frames(); f += 37)
    for (size_t j = 0; j < take.skeleton.size(); ++j) {
      const float* q = take.orientations.at(f, static_cast<int64_t>(j));
      EXPECT_NEAR(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3], 1.0, 1e-5);
      if (take.skeleton[j].end_site) {
        const float* p = take.orientations.at(f, take.skeleton[j].parent);
        for (int c = 0; c < 4; ++c) EXPECT_EQ(q[c], p[c]);
      }
    }
  // Tiers: the glosses in order on `signs` and `right_hand`, the types on `sign_types`.
  std::vector<std::string> glosses, right, types;
  for (const Label& l : Tier(take, kSignsTier).labels)
    if (l.text != "rest" && l.text != "preparation" && l.text != "transition" && l.text != "retraction")
      glosses.push_back(l.text);
  for (const Label& l : Tier(take, kRightHandTier).labels)
    if (l.text != "rest" && l.text != "preparation" && l.text != "transition" && l.text != "retraction")
      right.push_back(l.text);
  for (const Label& l : Tier(take, kSignTypesTier).labels)
    if (!l.text.empty()) types.push_back(l.text);
  ASSERT_EQ(glosses.size(), t.signs.size());
  EXPECT_EQ(right, glosses);
  for (size_t k = 0; k < t.signs.size(); ++k) {
    EXPECT_EQ(glosses[k], t.signs[k].gloss);
    EXPECT_EQ(types[k], SignTypeName(t.signs[k].type));
    EXPECT_EQ(SignerLexicon()[static_cast<size_t>(t.signs[k].lexicon)].gloss, t.signs[k].gloss);
  }
  // Tiers are contiguous over the take.
  for (const LabelTier& tier : take.tiers) {
    ASSERT_FALSE(tier.labels.empty());
    EXPECT_EQ(tier.labels.front().start_s, 0.0);
    EXPECT_NEAR(tier.labels.back().end_s, take.duration_s(), 1e-12);
    for (size_t i = 1; i < tier.labels.size(); ++i) EXPECT_EQ(tier.labels[i].start_s, tier.labels[i - 1].end_s);
  }
}

TEST(VirtualSigner, SameSeedSameTakesOtherSeedOtherTakes) {
  SignerOptions o;
  const SignerTake a = VirtualSigner(o).SimulateTake(5), b = VirtualSigner(o).SimulateTake(5);
  EXPECT_EQ(a.take.markers.data(), b.take.markers.data());
  o.seed = 2;
  const SignerTake c = VirtualSigner(o).SimulateTake(5);
  EXPECT_NE(a.take.markers.data(), c.take.markers.data());
}

// Each hand's phase changes (the truth tiers' boundaries) are where the true
// (noise-free) wrist speed has its minimum: within ±6 frames, the lowest speed
// is reached within one frame of the boundary.
TEST(VirtualSigner, PhaseChangesAreAtSpeedMinima) {
  const SignerOptions o;
  const VirtualSigner signer(o);
  const int takes = testing::kSanitized ? 3 : 20;
  int checked = 0;
  for (int i = 0; i < takes; ++i) {
    const SignerTake t = signer.SimulateTake(i);
    for (int h = 0; h < 2; ++h) {
      const std::vector<double> s = Speed(t.clean, h == 0 ? signer.right_wrist() : signer.left_wrist(), o.rate_hz);
      for (const BoundaryTruth& b : t.boundaries) {
        const double truth = h == 0 ? b.right_s : b.left_s;
        if (!std::isfinite(truth)) continue;
        const auto f = static_cast<int64_t>(std::llround(truth * o.rate_hz));
        ASSERT_NEAR(static_cast<double>(f), truth * o.rate_hz, 1e-9) << "boundaries lie on frames";
        double window_min = INFINITY, near_min = INFINITY;
        for (int64_t g = std::max<int64_t>(1, f - 6); g <= std::min<int64_t>(t.take.frames() - 2, f + 6); ++g) {
          window_min = std::min(window_min, s[static_cast<size_t>(g)]);
          if (std::abs(g - f) <= 1) near_min = std::min(near_min, s[static_cast<size_t>(g)]);
        }
        EXPECT_LE(near_min, window_min + 1e-9) << t.take.name << " hand " << h << " boundary " << truth;
        ++checked;
      }
    }
  }
  EXPECT_GT(checked, takes * 10);
}

// With synchronous hands the bounding postures of every movement are whole
// skeleton frames: G and E recomputed from the take's orientations and clean
// positions match the record, and the duration is the SURFACE plane with the
// seed's θ, rounded to whole frames.
TEST(VirtualSigner, TransitionDurationsFollowTheSurfaceLaw) {
  SignerOptions o;
  o.hand_offset_max_s = 0.0;
  const VirtualSigner signer(o);
  const double theta[3] = {0.148777, 0.663958, 0.275229};  // the seed's eq. 4 result
  int transitions = 0;
  double min_d = 1e9, max_d = 0;
  for (int i = 0; i < (testing::kSanitized ? 2 : 10); ++i) {
    const SignerTake t = signer.SimulateTake(i);
    for (const TransitionTruth& x : t.transitions) {
      const auto f0 = static_cast<int64_t>(std::llround(x.start_s * o.rate_hz));
      const auto f1 = static_cast<int64_t>(std::llround(x.end_s * o.rate_hz));
      const SkeletonPose a = FramePose(t.clean, t.take.orientations, f0);
      const SkeletonPose b = FramePose(t.clean, t.take.orientations, f1);
      const double g = MeanGeodesicDistance(a, b), e = MeanEuclideanDistance(a, b, 1000.0);
      EXPECT_NEAR(g, x.geodesic, 2e-5);
      EXPECT_NEAR(e, x.euclidean, 2e-5);
      const double law = theta[0] + theta[1] * g + theta[2] * e;
      EXPECT_NEAR(x.law_s, law, 1e-4);
      EXPECT_NEAR(x.duration_s, law, 0.5 / o.rate_hz + 1e-4);
      EXPECT_NEAR(x.end_s - x.start_s, x.duration_s, 1e-9);
      min_d = std::min(min_d, x.duration_s);
      max_d = std::max(max_d, x.duration_s);
      ++transitions;
    }
  }
  EXPECT_GT(transitions, 10);
  // The seed's transitions last 0.1-0.5 s (mean 0.303 s).
  EXPECT_GE(min_d, 0.15);
  EXPECT_LE(max_d, 0.6);
}

// SIMPLE (the seed's eq. 3) on one-movement signs: each stroke's mean speeds
// from its first and last frames, recomputed here.
TEST(VirtualSigner, SimpleLawUsesTheStrokeSpeeds) {
  SignerOptions o;
  o.hand_offset_max_s = 0.0;
  o.law = DurationLaw::kSimple;
  o.simple_alpha = 0.3;
  const VirtualSigner signer(o);
  // MUSEUM, OPEN, HOUR, WHERE: one movement each.
  const SignerTake t = signer.SimulateSequence("simple", {0, 10, 5, 2});
  auto pose = [&](double s) {
    return FramePose(t.clean, t.take.orientations, static_cast<int64_t>(std::llround(s * o.rate_hz)));
  };
  std::vector<double> v, w;
  for (const SignOccurrence& s : t.signs) {
    const double d = s.end_s - s.start_s;
    v.push_back(MeanEuclideanDistance(pose(s.start_s), pose(s.end_s), 1000.0) / d);
    w.push_back(MeanGeodesicDistance(pose(s.start_s), pose(s.end_s)) / d);
  }
  ASSERT_EQ(t.transitions.size(), 5u);
  for (size_t m = 0; m < t.transitions.size(); ++m) {
    const TransitionTruth& x = t.transitions[m];
    double vm = 0, wm = 0;
    if (m == 0) {
      vm = v[0], wm = w[0];
    } else if (m == 4) {
      vm = v[3], wm = w[3];
    } else {
      vm = (v[m - 1] + v[m]) / 2, wm = (w[m - 1] + w[m]) / 2;
    }
    const double law = 0.3 * x.euclidean / vm + 0.7 * x.geodesic / wm;
    EXPECT_NEAR(x.law_s, law, 1e-3 * law);
    EXPECT_NEAR(x.duration_s, std::clamp(law, 0.05, 2.0), 0.5 / o.rate_hz + 1e-3 * law);
  }
}

TEST(VirtualSigner, JitteredTierKeepsLabelsAndOrder) {
  const SignerTake t = VirtualSigner(SignerOptions{}).SimulateTake(1);
  const LabelTier& signs = Tier(t.take, kSignsTier);
  std::vector<double> offsets;
  const LabelTier m = JitterBoundaries(signs, "manual", 0.1, 100.0, 7, &offsets);
  ASSERT_EQ(m.labels.size(), signs.labels.size());
  ASSERT_EQ(offsets.size(), signs.labels.size() - 1);
  double largest = 0;
  for (size_t i = 0; i < m.labels.size(); ++i) {
    EXPECT_EQ(m.labels[i].text, signs.labels[i].text);
    EXPECT_GE(m.labels[i].end_s - m.labels[i].start_s, 0.01 - 1e-9);
    if (i + 1 < m.labels.size()) {
      EXPECT_NEAR(m.labels[i].end_s - signs.labels[i].end_s, offsets[i], 1e-12);
      EXPECT_LE(std::abs(offsets[i]), 0.1 + 1e-12);
      largest = std::max(largest, std::abs(offsets[i]));
    }
  }
  EXPECT_GT(largest, 0.03);  // really moved
}

TEST(VirtualSigner, OptionsAreChecked) {
  SignerOptions o;
  EXPECT_EQ(o.Check(), "");
  o.naming = "vicon";
  EXPECT_NE(o.Check().find("naming"), std::string::npos);
  EXPECT_THROW(VirtualSigner{o}, InvalidInput);
  o = SignerOptions{};
  o.max_signs = 0;
  EXPECT_NE(o.Check(), "");
  o = SignerOptions{};
  o.distance_unit_mm = 0;
  EXPECT_NE(o.Check(), "");
  DurationLaw law;
  EXPECT_TRUE(ParseDurationLaw("simple", &law));
  EXPECT_EQ(law, DurationLaw::kSimple);
  EXPECT_FALSE(ParseDurationLaw("linear", &law));
}

}  // namespace
}  // namespace csw
