// Transition synthesis (analysis/signing/transition_synthesis.h): the ends
// and middles of interpolated and blended transitions against hand-computed
// postures, frame counts, retrieval of the nearest occurrence.
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/signing/transition_synthesis.h"
#include "analysis/signing/transitions.h"
#include "core/error.h"

namespace csw::signing {
namespace {

// One joint still at x = x0 with orientation angle a0 about z, for `frames` frames,
// moving by dx mm and da rad per frame.
Clip Ramp(int64_t frames, double x0, double dx, double a0, double da, int joints = 1) {
  Clip c;
  c.rate_hz = 100;
  c.frames = frames;
  c.joints = joints;
  for (int64_t f = 0; f < frames; ++f) {
    for (int j = 0; j < joints; ++j) {
      c.positions.emplace_back(x0 + dx * static_cast<double>(f), 10.0 * j, 0);
      c.orientations.emplace_back(Eigen::AngleAxisd(a0 + da * static_cast<double>(f), Eigen::Vector3d::UnitZ()));
    }
  }
  return c;
}

double AngleZ(const Eigen::Quaterniond& q) { return 2 * std::atan2(q.z(), q.w()); }

TEST(SigningSynthesis, InterpolationRunsLinearlyAndBySlerpBetweenTheBoundingPostures) {
  const Clip a = Ramp(5, 0, 10, 0.0, 0.0);        // last posture x = 40, angle 0
  const Clip b = Ramp(5, 140, 0, 1.0, 0.0);       // first posture x = 140, angle 1 rad
  const Clip t = InterpolateTransition(a, b, 9);  // u = 0.1 .. 0.9
  ASSERT_EQ(t.frames, 9);
  EXPECT_NEAR(t.position(0, 0).x(), 50.0, 1e-12);
  EXPECT_NEAR(t.position(4, 0).x(), 90.0, 1e-12);
  EXPECT_NEAR(t.position(8, 0).x(), 130.0, 1e-12);
  EXPECT_NEAR(AngleZ(t.orientation(4, 0)), 0.5, 1e-12);  // slerp: constant angular speed
  EXPECT_NEAR(AngleZ(t.orientation(0, 0)), 0.1, 1e-12);
  EXPECT_EQ(InterpolateTransition(a, b, 0).frames, 0);
  EXPECT_THROW(InterpolateTransition(a, Ramp(5, 0, 0, 0, 0, 2), 3), InvalidInput);
}

TEST(SigningSynthesis, BlendingStartsOnTheRetractionAndEndsOnThePreparation) {
  const Clip retraction = Ramp(11, 0, 1, 0.0, 0.02);     // x 0 → 10, angle 0 → 0.2
  const Clip preparation = Ramp(21, 100, 1, 1.0, 0.01);  // x 100 → 120, angle 1 → 1.2
  const Clip t = BlendTransition(retraction, preparation, 11);
  ASSERT_EQ(t.frames, 11);
  EXPECT_NEAR(t.position(0, 0).x(), 0.0, 1e-12);     // w = 0: the retraction's first frame
  EXPECT_NEAR(t.position(10, 0).x(), 120.0, 1e-12);  // w = 1: the preparation's last frame
  // u = 0.5: retraction at x 5, preparation at x 110, w = 0.5 → 57.5.
  EXPECT_NEAR(t.position(5, 0).x(), 57.5, 1e-12);
  EXPECT_NEAR(AngleZ(t.orientation(5, 0)), 0.5 * (0.1 + 1.1), 1e-12);
  // Smooth weights: the same ends, and the middle (w(0.5) = 0.5) too.
  const Clip s = BlendTransition(retraction, preparation, 11, true);
  EXPECT_NEAR(s.position(5, 0).x(), 57.5, 1e-12);
  // u = 0.2: w = 0.104 instead of 0.2.
  EXPECT_NEAR(s.position(2, 0).x(), (1 - 0.104) * 2.0 + 0.104 * 104.0, 1e-9);
}

TEST(SigningSynthesis, FrameCountsConcatenationAndClipsFromTakes) {
  EXPECT_EQ(TransitionFrames(0.3, 100), 29);  // 0.3 s between two posture frames
  EXPECT_EQ(TransitionFrames(0.0, 100), 0);
  const Clip a = Ramp(3, 0, 1, 0, 0), b = Ramp(4, 5, 1, 0, 0);
  const Clip c = Concatenate(a, b);
  ASSERT_EQ(c.frames, 7);
  EXPECT_NEAR(c.position(3, 0).x(), 5.0, 1e-12);
  Take take;
  take.name = "signer";
  take.rate_hz = 100;
  take.marker_names = {"wrist"};
  take.markers.Resize(10, 1);
  take.orientations.Resize(10, 1);
  for (int64_t f = 0; f < 10; ++f) {
    float* p = take.markers.at(f, 0);
    p[0] = static_cast<float>(f);
    p[1] = p[2] = 0;
    float* q = take.orientations.at(f, 0);
    q[0] = 1;
    q[1] = q[2] = q[3] = 0;
  }
  const Clip x = ExtractClip(take, 2, 5);
  EXPECT_EQ(x.frames, 5);
  EXPECT_NEAR(x.position(0, 0).x(), 2.0, 1e-6);
  EXPECT_THROW(ExtractClip(take, 8, 5), InvalidInput);
  take.markers.SetMissing(4, 0);
  try {
    ExtractClip(take, 2, 5);
    FAIL() << "a clip with a missing sample was accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("frame 4"), std::string::npos) << e.what();
  }
}

TEST(SigningSynthesis, RetrievalPicksTheOccurrenceClosestToItsNeighbours) {
  const Clip previous = Ramp(5, 0, 10, 0.0, 0.0);               // ends at x = 40, angle 0
  const Clip next = Ramp(5, 200, 0, 0.3, 0.0);                  // starts at x = 200, angle 0.3
  std::vector<Clip> candidates = {Ramp(10, 300, 10, 0.0, 0.0),  // far from previous
                                  Ramp(10, 50, 15, 0.0, 0.03),  // 50 → 185, 0 → 0.27: close to both
                                  Ramp(10, 45, 0, 0.0, 0.0)};   // close to previous, far from next
  EXPECT_EQ(RetrieveOccurrence(candidates, &previous, &next), 1u);
  EXPECT_EQ(RetrieveOccurrence(candidates, &previous, nullptr), 2u);
  EXPECT_THROW(RetrieveOccurrence({}, &previous, &next), InvalidInput);
  double e = 0, g = 0;
  CompareClips(candidates[0], candidates[0], &e, &g);
  EXPECT_EQ(e, 0.0);
  CompareClips(Ramp(3, 0, 0, 0, 0), Ramp(3, 3, 0, 0.2, 0), &e, &g);
  EXPECT_NEAR(e, 3.0, 1e-12);
  EXPECT_NEAR(g, 0.1, 1e-12);
}

}  // namespace
}  // namespace csw::signing

namespace csw::signing {
namespace {

TEST(SigningSynthesis, SequenceRetrievalMinimisesTheSummedBoundaryDistances) {
  // Sign 1: occurrences ending at x 0 or 100; sign 2: starting at 90 (ending 10) or at 5 (ending 500);
  // sign 3: starting at 20 or 480. Greedy from sign 1's first occurrence picks 0 → 5 → 480 (5 + 20 = 25 mm);
  // the best chain is 100 → 90 → 20 (10 + 10 = 20 mm).
  auto still = [](double x0, double x1) {
    Clip c;
    c.rate_hz = 100;
    c.frames = 2;
    c.joints = 1;
    c.positions = {Eigen::Vector3d(x0, 0, 0), Eigen::Vector3d(x1, 0, 0)};
    c.orientations = {Eigen::Quaterniond::Identity(), Eigen::Quaterniond::Identity()};
    return c;
  };
  const std::vector<std::vector<Clip>> candidates = {
      {still(-50, 0), still(-50, 100)}, {still(90, 10), still(5, 500)}, {still(20, 0), still(480, 0)}};
  EXPECT_EQ(RetrieveSequence(candidates), (std::vector<size_t>{1, 0, 0}));
  EXPECT_THROW(RetrieveSequence({{still(0, 0)}, {}}), InvalidInput);
  const Transition t = MeasureBetween(still(0, 100), still(400, 0), {}, 1000.0);
  EXPECT_NEAR(t.euclidean, 0.3, 1e-12);
  EXPECT_NEAR(t.geodesic, 0.0, 1e-12);
  EXPECT_NEAR(t.from_speed, 10.0, 1e-9);  // 100 mm in one frame at 100 Hz = 10 m/s
}

}  // namespace
}  // namespace csw::signing
