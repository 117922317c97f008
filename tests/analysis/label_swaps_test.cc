#include "analysis/cleaning/label_swaps.h"

#include <gtest/gtest.h>

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <string>

#include "core/error.h"
#include "datasets/virtual_cuer.h"
#include "synth/phonetics.h"
#include "tests/testing/testing.h"

namespace csw::cleaning {
namespace {

// Five markers on smooth, distinct curves (mm, 120 Hz), 25-40 mm apart.
MarkerArray HandMade(int64_t frames) {
  MarkerArray m(frames, 5);
  for (int64_t f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) / 120.0;
    for (int k = 0; k < 5; ++k) {
      float* p = m.at(f, k);
      p[0] = static_cast<float>(30.0 * k + 40.0 * std::sin(2.0 * t + 0.3 * k));
      p[1] = static_cast<float>(10.0 * k + 30.0 * std::cos(1.5 * t));
      p[2] = static_cast<float>(500.0 + 20.0 * std::sin(3.0 * t + k));
    }
  }
  return m;
}

void Exchange(MarkerArray* m, int a, int b, int64_t first, int64_t end) {
  for (int64_t f = first; f < end; ++f)
    for (int c = 0; c < 3; ++c) std::swap(m->at(f, a)[c], m->at(f, b)[c]);
}

double MaxError(const MarkerArray& x, const MarkerArray& truth) {
  double worst = 0.0;
  for (int64_t f = 0; f < x.frames(); ++f)
    for (int64_t k = 0; k < x.markers(); ++k) {
      if (!x.Visible(f, k)) continue;
      for (int c = 0; c < 3; ++c) worst = std::max(worst, std::abs(double(x.at(f, k)[c]) - truth.at(f, k)[c]));
    }
  return worst;
}

TEST(LabelSwaps, HandMadeSwapIsFoundExactlyAndFixed) {
  const MarkerArray clean = HandMade(400);
  MarkerArray m = clean;
  Exchange(&m, 1, 2, 120, 185);
  SwapReport r = DetectLabelSwaps(m, 120.0);
  ASSERT_EQ(r.swaps.size(), 1u);
  EXPECT_EQ(r.swaps[0].marker_a, 1);
  EXPECT_EQ(r.swaps[0].marker_b, 2);
  EXPECT_EQ(r.swaps[0].first_frame, 120);
  EXPECT_EQ(r.swaps[0].end_frame, 185);
  EXPECT_FALSE(r.swaps[0].open_ended);
  EXPECT_GT(r.swaps[0].confidence, 0.9);
  FixLabelSwaps(r.swaps, &m);
  EXPECT_EQ(MaxError(m, clean), 0.0);
  // Without a swap nothing is reported.
  EXPECT_TRUE(DetectLabelSwaps(clean, 120.0).swaps.empty());
}

TEST(LabelSwaps, SwapStartingInsideAGapIsFoundAtTheOtherMarkersJump) {
  const MarkerArray clean = HandMade(400);
  MarkerArray m = clean;
  for (int64_t f = 110; f < 130; ++f) m.SetMissing(f, 1);  // marker 1 hidden over the swap start
  MarkerArray masked = m;
  Exchange(&m, 1, 2, 120, 200);
  SwapReport r = DetectLabelSwaps(m, 120.0);
  ASSERT_EQ(r.swaps.size(), 1u);
  EXPECT_EQ(r.swaps[0].first_frame, 120);  // marker 2 jumps there
  EXPECT_EQ(r.swaps[0].end_frame, 200);
  FixLabelSwaps(r.swaps, &m);
  EXPECT_EQ(MaxError(m, masked), 0.0);
  for (int64_t f = 0; f < 400; ++f) EXPECT_EQ(m.Visible(f, 1), masked.Visible(f, 1)) << f;
}

TEST(LabelSwaps, SwapHiddenInBothMarkersIsFoundWhereOneReappears) {
  const MarkerArray clean = HandMade(400);
  MarkerArray m = clean;
  for (int64_t f = 110; f < 140; ++f) m.SetMissing(f, 1);
  for (int64_t f = 115; f < 135; ++f) m.SetMissing(f, 2);
  MarkerArray masked = m;
  Exchange(&m, 1, 2, 125, 250);
  SwapReport r = DetectLabelSwaps(m, 120.0);
  ASSERT_EQ(r.swaps.size(), 1u);
  EXPECT_EQ(r.swaps[0].first_frame, 135);  // first frame where a swapped sample is seen
  EXPECT_EQ(r.swaps[0].end_frame, 250);
  FixLabelSwaps(r.swaps, &m);
  EXPECT_EQ(MaxError(m, masked), 0.0);
}

TEST(LabelSwaps, OpenEndedSwapAndExplicitPairs) {
  const MarkerArray clean = HandMade(400);
  MarkerArray m = clean;
  Exchange(&m, 3, 4, 300, 400);
  SwapOptions o;
  o.pairs = {{4, 3}};
  SwapReport r = DetectLabelSwaps(m, 120.0, o);
  ASSERT_EQ(r.candidate_pairs.size(), 1u);
  ASSERT_EQ(r.swaps.size(), 1u);
  EXPECT_EQ(r.swaps[0].first_frame, 300);
  EXPECT_EQ(r.swaps[0].end_frame, 400);
  EXPECT_TRUE(r.swaps[0].open_ended);
  FixLabelSwaps(r.swaps, &m);
  EXPECT_EQ(MaxError(m, clean), 0.0);
}

TEST(LabelSwaps, ExchangeBackWithinFewFramesIsNotReported) {
  MarkerArray m = HandMade(400);
  Exchange(&m, 1, 2, 120, 123);  // 3 frames < min_frames (4)
  EXPECT_TRUE(DetectLabelSwaps(m, 120.0).swaps.empty());
  SwapOptions o;
  o.min_frames = 3;
  SwapReport r = DetectLabelSwaps(m, 120.0, o);
  ASSERT_EQ(r.swaps.size(), 1u);
  EXPECT_EQ(r.swaps[0].first_frame, 120);
  EXPECT_EQ(r.swaps[0].end_frame, 123);
}

TEST(LabelSwaps, NeighboursAreRankedByHowCloseTheyCome) {
  // Marker 0 at the origin, marker 1 always 50 mm away on x, marker 2 200 mm
  // away on x except in 20 of 100 frames, where it is 10 mm away: by the 10th
  // percentile of distance marker 2 is the nearest of both (10 and 40 mm; by
  // median it would be 200 and 150 mm).
  MarkerArray m(100, 3);
  for (int64_t f = 0; f < 100; ++f) {
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) m.at(f, k)[c] = 0.0f;
    m.at(f, 1)[0] = 50.0f;
    m.at(f, 2)[0] = f % 5 == 0 ? 10.0f : 200.0f;
  }
  const std::vector<std::pair<int, int>> expected = {{0, 2}, {1, 2}};
  EXPECT_EQ(NeighbourPairs(m, 1, 500.0), expected);
}

TEST(LabelSwaps, RejectsBadInput) {
  MarkerArray m = HandMade(50);
  EXPECT_THROW(DetectLabelSwaps(m, 0.0), InvalidInput);
  SwapOptions o;
  o.pairs = {{0, 7}};
  EXPECT_THROW(DetectLabelSwaps(m, 120.0, o), InvalidInput);
  DetectedSwap s;
  s.marker_a = 0;
  s.marker_b = 1;
  s.end_frame = 51;
  EXPECT_THROW(FixLabelSwaps({s}, &m), InvalidInput);
}

// Virtual-cuer takes (issue 12's acceptance): short shape takes (three hand
// shapes, ~3.5 s, 60 markers) and cued sentences (113 markers) alternate.
// A detected start/end counts when at most this many frames between it and the
// injected one have a sample of either marker.
constexpr int kFrameTolerance = 2;

struct Tally {
  int takes = 0, injected = 0, found = 0, false_alarms = 0, max_start_error = 0, max_end_error = 0;
  double max_fix_error_mm = 0.0;
};

SimulationResult CuerTake(const VirtualCuer& cuer, int t) {
  const std::string name = "swaps_" + std::to_string(t);
  if (t % 2 == 0) return cuer.SimulateShapes(name, {1 + t % 8, 1 + (t * 3 + 1) % 8, 1 + (t * 5 + 2) % 8});
  PhonetiseOptions po;
  po.synthesize_audio = false;
  po.rate_wpm = cuer.options().speech_rate_wpm;
  static const std::vector<std::string> sentences = ShippedSentences();
  return cuer.SimulateUtterance(name, Phonetise(sentences.at(static_cast<size_t>(t % 7)), po));
}

// Frames between two boundaries where label a or b has a sample: the samples a
// wrong boundary exchanges wrongly (frames missing in both change nothing).
int SeenBetween(const MarkerArray& m, int a, int b, int64_t x, int64_t y) {
  int n = 0;
  for (int64_t f = std::min(x, y); f < std::max(x, y); ++f) n += (m.Visible(f, a) || m.Visible(f, b)) ? 1 : 0;
  return n;
}

// The corpus seed (1 by default); CSW_SWAP_EVAL_SEED=N reruns the evaluation on
// other takes, as docs/cleaning-swaps.md reports for seeds 2-15.
uint64_t EvalSeed() {
  const char* s = std::getenv("CSW_SWAP_EVAL_SEED");
  return s != nullptr && std::atoi(s) > 0 ? static_cast<uint64_t>(std::atoi(s)) : 1;
}

Tally RunCuer(bool swaps, int takes, int first_take) {
  SimulateOptions o;
  o.label_swaps = swaps;
  o.seed = EvalSeed();
  VirtualCuer cuer(o);
  Tally tally;
  for (int t = first_take; t < first_take + takes; ++t) {
    SimulationResult r = CuerTake(cuer, t);
    ++tally.takes;
    SwapReport rep = DetectLabelSwaps(r.take.markers, r.take.rate_hz);
    std::vector<bool> used(rep.swaps.size(), false);
    std::vector<LabelSwap> found;
    for (const LabelSwap& s : r.swaps) {
      ++tally.injected;
      const int a = std::min(s.marker_a, s.marker_b), b = std::max(s.marker_a, s.marker_b);
      for (size_t i = 0; i < rep.swaps.size(); ++i) {
        const DetectedSwap& d = rep.swaps[i];
        if (used[i] || d.marker_a != a || d.marker_b != b) continue;
        const int start_error = SeenBetween(r.take.markers, a, b, d.first_frame, s.first_frame);
        const int end_error = SeenBetween(r.take.markers, a, b, d.end_frame, s.end_frame);
        if (start_error > kFrameTolerance || end_error > kFrameTolerance) continue;
        used[i] = true;
        ++tally.found;
        found.push_back(s);
        tally.max_start_error = std::max(tally.max_start_error, start_error);
        tally.max_end_error = std::max(tally.max_end_error, end_error);
        break;
      }
    }
    for (size_t i = 0; i < rep.swaps.size(); ++i) {
      if (used[i]) continue;
      ++tally.false_alarms;
      const DetectedSwap& d = rep.swaps[i];
      std::cout << "take " << t << ": false alarm " << r.take.marker_names[static_cast<size_t>(d.marker_a)] << "-"
                << r.take.marker_names[static_cast<size_t>(d.marker_b)] << " [" << d.first_frame << ", " << d.end_frame
                << ") confidence " << d.confidence << " evidence " << d.evidence << "\n";
    }
    // The fix restores the clean labelling inside every interval found.
    MarkerArray fixed = r.take.markers;
    FixLabelSwaps(rep.swaps, &fixed);
    for (const LabelSwap& s : r.swaps)
      if (std::find_if(found.begin(), found.end(),
                       [&](const LabelSwap& x) { return x.first_frame == s.first_frame; }) == found.end())
        std::cout << "take " << t << ": missed " << r.take.marker_names[static_cast<size_t>(s.marker_a)] << "-"
                  << r.take.marker_names[static_cast<size_t>(s.marker_b)] << " [" << s.first_frame << ", "
                  << s.end_frame << ")\n";
    for (const LabelSwap& s : found)
      for (int64_t f = s.first_frame; f < s.end_frame; ++f)
        for (int k : {s.marker_a, s.marker_b}) {
          if (!fixed.Visible(f, k)) continue;
          const Eigen::Vector3f x(fixed.at(f, k)), c(r.clean.at(f, k));
          tally.max_fix_error_mm = std::max(tally.max_fix_error_mm, double((x - c).norm()));
        }
  }
  return tally;
}

TEST(LabelSwaps, VirtualCuerSwapsOverThirtyTakesAreFoundAndFixed) {
  const int takes = testing::kSanitized ? 6 : 30;  // a subset under the sanitizers (testing.h)
  const Tally t = RunCuer(true, takes, 0);
  RecordProperty("injected", t.injected);
  RecordProperty("found", t.found);
  RecordProperty("false_alarms", t.false_alarms);
  RecordProperty("max_start_error_frames", t.max_start_error);
  RecordProperty("max_end_error_frames", t.max_end_error);
  RecordProperty("max_fix_error_mm", std::to_string(t.max_fix_error_mm));
  std::cout << "takes " << t.takes << " injected " << t.injected << " found " << t.found << " false alarms "
            << t.false_alarms << " start/end error " << t.max_start_error << "/" << t.max_end_error << " fix error "
            << t.max_fix_error_mm << " mm\n";
  ASSERT_EQ(t.injected, takes);
  EXPECT_GE(t.found, takes - takes / 20 - (takes < 20 ? 1 : 0));  // ≥ 95 % of 30 (measured: 30 of 30)
  EXPECT_LE(t.false_alarms, (takes + 9) / 10);                    // at most one per 10 takes (measured: 0)
  EXPECT_LE(t.max_start_error, kFrameTolerance);
  EXPECT_LE(t.max_end_error, kFrameTolerance);
  EXPECT_LE(t.max_fix_error_mm, 2.0);  // every sample of a found swap back on its marker (noise 0.2 mm)
}

TEST(LabelSwaps, VirtualCuerTakesWithoutSwapsReportNone) {
  const Tally t = RunCuer(false, testing::kSanitized ? 3 : 10, 100);
  RecordProperty("false_alarms", t.false_alarms);
  EXPECT_EQ(t.injected, 0);
  // At most one per 10 takes (issue 12); measured: 0 on seed 1 (docs/cleaning-swaps.md).
  EXPECT_LE(t.false_alarms, 1);
}

}  // namespace
}  // namespace csw::cleaning
