#include "analysis/cleaning/spikes.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <utility>

#include "core/error.h"
#include "datasets/capture.h"
#include "datasets/virtual_cuer.h"

namespace csw::cleaning {
namespace {

// Three markers on smooth curves at 120 Hz with Gaussian noise σ = 0.2 mm.
MarkerArray Smooth(int64_t frames, double noise_mm, uint64_t seed) {
  std::mt19937_64 rng(seed);
  MarkerArray m(frames, 3);
  for (int64_t f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) / 120.0;
    for (int k = 0; k < 3; ++k) {
      float* p = m.at(f, k);
      p[0] = static_cast<float>(50.0 * k + 40.0 * std::sin(2.0 * t + k) + noise_mm * StandardNormal(rng));
      p[1] = static_cast<float>(30.0 * std::cos(1.3 * t) + noise_mm * StandardNormal(rng));
      p[2] = static_cast<float>(800.0 + 25.0 * std::sin(3.0 * t) + noise_mm * StandardNormal(rng));
    }
  }
  return m;
}

TEST(Spikes, InjectedSpikesAreFoundAtTheirFramesAndNoNeighbourIsFlagged) {
  MarkerArray m = Smooth(1200, 0.2, 7);
  // Spikes of 3-10 mm (offsets along varied directions).
  const std::set<std::pair<int, int64_t>> injected = {{0, 100}, {0, 101 + 300}, {1, 250}, {2, 600}, {2, 1000}};
  double size = 3.0;
  for (auto [k, f] : injected) {
    float* p = m.at(f, k);
    p[0] += static_cast<float>(size);
    p[2] -= static_cast<float>(0.5 * size);
    size += 1.7;
  }
  SpikeReport r = DetectSpikes(m, 120.0);
  std::set<std::pair<int, int64_t>> found;
  for (const Spike& s : r.spikes) found.insert({s.marker, s.frame});
  EXPECT_EQ(found, injected);  // the right frames, and no neighbour or noise sample
  // Automatic threshold: 8 × the robust scale (σ of the acceleration noise is
  // √6 × 0.2 mm × 120² = 7,055 mm/s²), above the 30 m/s² floor.
  EXPECT_NEAR(r.scale_mm_s2, std::sqrt(6.0) * 0.2 * 14400.0, 0.05 * 7055.0);
  EXPECT_NEAR(r.threshold_mm_s2, 8.0 * r.scale_mm_s2, 1e-9);
  // The first spike: offset 3.35 mm from the neighbours' midpoint, ±1 mm of noise.
  ASSERT_FALSE(r.spikes.empty());
  EXPECT_EQ(r.spikes[0].frame, 100);
  EXPECT_NEAR(r.spikes[0].offset_mm, std::hypot(3.0, 1.5), 1.0);
  EXPECT_NEAR(r.spikes[0].acceleration_mm_s2, 2.0 * r.spikes[0].offset_mm * 14400.0, 1e-6);
  // The fix marks exactly those samples missing.
  const int64_t before = m.CountVisible();
  EXPECT_EQ(RemoveSpikes(r.spikes, &m), 5);
  EXPECT_EQ(m.CountVisible(), before - 5);
  for (auto [k, f] : injected) EXPECT_FALSE(m.Visible(f, k));
  EXPECT_TRUE(DetectSpikes(m, 120.0).spikes.empty());
}

TEST(Spikes, AStepIsNotASpike) {
  MarkerArray m = Smooth(600, 0.2, 11);
  for (int64_t f = 300; f < 600; ++f) m.at(f, 1)[1] += 15.0f;  // a 15 mm jump between frames 299 and 300
  SpikeReport r = DetectSpikes(m, 120.0);
  EXPECT_TRUE(r.spikes.empty()) << r.spikes.size() << " spikes, first at frame " << r.spikes[0].frame;
}

TEST(Spikes, NoiseFreeDataUsesTheFloorAndAFixedThresholdWins) {
  MarkerArray m = Smooth(600, 0.0, 1);
  m.at(200, 2)[0] += 2.0f;  // 2 mm: 57,600 mm/s² at the sample, 28,800 at its neighbours
  SpikeReport r = DetectSpikes(m, 120.0);
  EXPECT_DOUBLE_EQ(r.threshold_mm_s2, 30000.0);
  ASSERT_EQ(r.spikes.size(), 1u);
  EXPECT_EQ(r.spikes[0].marker, 2);
  EXPECT_EQ(r.spikes[0].frame, 200);
  EXPECT_NEAR(r.spikes[0].offset_mm, 2.0, 0.01);
  SpikeOptions o;
  o.threshold_mm_s2 = 60000.0;
  EXPECT_TRUE(DetectSpikes(m, 120.0, o).spikes.empty());
  o.threshold_mm_s2 = 0.0;
  o.columns = {0, 1};
  EXPECT_TRUE(DetectSpikes(m, 120.0, o).spikes.empty());
}

TEST(Spikes, SamplesNextToGapsAreNotJudged) {
  MarkerArray m = Smooth(300, 0.0, 1);
  m.at(100, 0)[0] += 10.0f;
  m.SetMissing(102, 0);  // f+2 missing: the spike at 100 and its neighbour 101 cannot be told apart
  EXPECT_TRUE(DetectSpikes(m, 120.0).spikes.empty());
}

TEST(Spikes, VirtualCuerTakeHasNoSpikesAndInjectedOnesAreFound) {
  SimulateOptions o;
  VirtualCuer cuer(o);
  SimulationResult r = cuer.SimulateShapes("spikes", {2, 5});
  // The clean capture's largest acceleration sets the floor's margin.
  double peak = 0.0;
  for (int64_t k = 0; k < r.clean.markers(); ++k)
    for (int64_t f = 1; f + 1 < r.clean.frames(); ++f) {
      double a2 = 0.0;
      for (int c = 0; c < 3; ++c) {
        const double d = r.clean.at(f - 1, k)[c] - 2.0 * r.clean.at(f, k)[c] + r.clean.at(f + 1, k)[c];
        a2 += d * d;
      }
      peak = std::max(peak, std::sqrt(a2) * 14400.0);
    }
  RecordProperty("clean_peak_acceleration_mm_s2", std::to_string(peak));
  EXPECT_LT(peak, 30000.0);  // the floor is above the cueing hand's accelerations
  SpikeReport clean = DetectSpikes(r.take.markers, r.take.rate_hz);
  EXPECT_TRUE(clean.spikes.empty()) << clean.spikes.size();
  // 20 spikes of 5 mm on visible samples with visible neighbours.
  MarkerArray m = r.take.markers;
  std::set<std::pair<int, int64_t>> injected;
  for (int i = 0; i < 20; ++i) {
    const int k = (7 * i) % static_cast<int>(m.markers());
    const int64_t f = 20 + 17 * i;
    if (!m.Visible(f - 1, k) || !m.Visible(f, k) || !m.Visible(f + 1, k)) continue;
    m.at(f, k)[1] += 5.0f;
    injected.insert({k, f});
  }
  ASSERT_GE(injected.size(), 15u);
  std::set<std::pair<int, int64_t>> found;
  for (const Spike& s : DetectSpikes(m, r.take.rate_hz).spikes) found.insert({s.marker, s.frame});
  EXPECT_EQ(found, injected);
}

TEST(Spikes, RejectsBadInput) {
  MarkerArray m = Smooth(10, 0.0, 1);
  EXPECT_THROW(DetectSpikes(m, 0.0), InvalidInput);
  SpikeOptions o;
  o.columns = {3};
  EXPECT_THROW(DetectSpikes(m, 120.0, o), InvalidInput);
  Spike s;
  s.frame = 10;
  EXPECT_THROW(RemoveSpikes({s}, &m), InvalidInput);
}

}  // namespace
}  // namespace csw::cleaning
