#include "models/frame_selection.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <random>

#include "core/error.h"

namespace csw {
namespace {

void Set(MarkerArray* m, int64_t f, int64_t c, double x, double y, double z) {
  float* p = m->at(f, c);
  p[0] = static_cast<float>(x);
  p[1] = static_cast<float>(y);
  p[2] = static_cast<float>(z);
}

// Marker 0 moves along x by the steps below; marker 1 stays still except where
// noted. Distance = max over markers of the 3D distance; kept when >= 2 mm from
// every kept frame.
TEST(FrameSelection, HandComputedSequence) {
  const double x0[] = {0.0, 1.0, 1.9, 2.0, 3.5, 4.1, 0.5, 0.0, 10.0, 6.0, 6.0};
  MarkerArray m(11, 3);
  for (int f = 0; f < 11; ++f) {
    Set(&m, f, 0, x0[f], 0, 0);
    Set(&m, f, 1, 100, 0, 0);
    Set(&m, f, 2, 0, 0, 0);  // not chosen; missing below does not matter
  }
  Set(&m, 7, 1, 100, 3, 0);  // frame 7: marker 0 back at 0, but marker 1 moved 3 mm
  m.SetMissing(9, 1);        // frame 9: chosen marker missing -> excluded
  m.SetMissing(4, 2);        // unchosen marker missing -> still a candidate
  // By hand: 0 kept (first). 1: 1.0 from 0 -> drop. 2: 1.9 -> drop. 3: 2.0 from 0 -> keep (>=).
  // 4: 3.5 from 0, 1.5 from 3 -> drop. 5: 4.1 / 2.1 -> keep. 6: 0.5 from 0 -> drop.
  // 7: marker 1 is 3 mm from all kept -> keep. 8: 10 -> keep. 9: excluded.
  // 10: x = 6 is 1.9 from 5 (4.1) -> drop.
  const FrameSelection sel = SelectTrainingFrames(m, {0, 1}, 2.0);
  EXPECT_EQ(sel.frames, (std::vector<int64_t>{0, 3, 5, 7, 8}));
  EXPECT_EQ(sel.complete_frames, 10);
  EXPECT_EQ(sel.incomplete_frames, 1);
  // Larger threshold: 0 kept, 3 (2.0) drop, 4 (3.5) keep, 5 (0.6 from 4) drop, 7 (3 mm) keep,
  // 8 keep, 10 (6 vs 3.5: 2.5) drop.
  EXPECT_EQ(SelectTrainingFrames(m, {0, 1}, 3.0).frames, (std::vector<int64_t>{0, 4, 7, 8}));
  // Diagonal displacement: sqrt(1.5^2 * 3) = 2.6 mm >= 2 although each axis < 2.
  MarkerArray d(2, 1);
  Set(&d, 0, 0, 0, 0, 0);
  Set(&d, 1, 0, 1.5, 1.5, 1.5);
  EXPECT_EQ(SelectTrainingFrames(d, {0}).frames, (std::vector<int64_t>{0, 1}));
}

TEST(FrameSelection, LargeTakeMatchesBruteForce) {
  // 70k frames, 10 markers, random walk. Greedy in time order means the choice
  // among the first `checked` frames does not depend on later frames, so the
  // grid result restricted to them equals a brute-force greedy pass over them.
  const int64_t frames = 70000;
  const int markers = 10;
  MarkerArray m(frames, markers);
  std::mt19937 rng(11);
  std::normal_distribution<double> step(0.0, 0.3);
  std::vector<double> pos(markers * 3, 0.0);
  for (int64_t f = 0; f < frames; ++f) {
    for (int i = 0; i < markers * 3; ++i) pos[i] = 0.995 * pos[i] + step(rng);
    for (int c = 0; c < markers; ++c) Set(&m, f, c, 50 * c + pos[c * 3], pos[c * 3 + 1], pos[c * 3 + 2]);
    if (f % 97 == 0) m.SetMissing(f, f % markers);
  }
  std::vector<int> cols(markers);
  for (int c = 0; c < markers; ++c) cols[c] = c;
  const auto t0 = std::chrono::steady_clock::now();
  const FrameSelection sel = SelectTrainingFrames(m, cols, 2.0);
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  RecordProperty("kept", std::to_string(sel.frames.size()));
  RecordProperty("seconds", std::to_string(seconds));
  EXPECT_EQ(sel.incomplete_frames, (frames + 96) / 97);

  const int64_t checked = 8000;
  std::vector<int64_t> brute;
  for (int64_t f = 0; f < checked; ++f) {
    if (f % 97 == 0) continue;
    bool keep = true;
    for (int64_t k : brute) {
      double worst = 0.0;
      for (int c = 0; c < markers; ++c) {
        double s = 0.0;
        for (int j = 0; j < 3; ++j) {
          const double diff = double(m.at(f, c)[j]) - m.at(k, c)[j];
          s += diff * diff;
        }
        worst = std::max(worst, std::sqrt(s));
      }
      if (worst < 2.0) {
        keep = false;
        break;
      }
    }
    if (keep) brute.push_back(f);
  }
  std::vector<int64_t> prefix;
  for (int64_t f : sel.frames) {
    if (f < checked) prefix.push_back(f);
  }
  EXPECT_EQ(prefix, brute);
  EXPECT_GT(brute.size(), 100u);
  EXPECT_GT(sel.frames.size(), 100u);
}

TEST(FrameSelection, RejectsBadInput) {
  MarkerArray m(3, 2);
  EXPECT_THROW(SelectTrainingFrames(m, {}, 2.0), InvalidInput);
  EXPECT_THROW(SelectTrainingFrames(m, {2}, 2.0), InvalidInput);
  EXPECT_THROW(SelectTrainingFrames(m, {0}, 0.0), InvalidInput);
  const FrameSelection none = SelectTrainingFrames(m, {0, 1}, 2.0);  // all missing
  EXPECT_TRUE(none.frames.empty());
  EXPECT_EQ(none.incomplete_frames, 3);
  // Hostile values: huge and infinite coordinates, a tiny threshold.
  MarkerArray h(4, 1);
  Set(&h, 0, 0, 3e38, -3e38, 0);
  Set(&h, 1, 0, 3e38, -3e38, 0);                                 // same as frame 0: dropped
  Set(&h, 2, 0, std::numeric_limits<double>::infinity(), 0, 0);  // not finite: excluded
  Set(&h, 3, 0, 0, 0, 1e-300);
  const FrameSelection hs = SelectTrainingFrames(h, {0}, 1e-300);
  EXPECT_EQ(hs.frames, (std::vector<int64_t>{0, 3}));
  EXPECT_EQ(hs.incomplete_frames, 1);
}

}  // namespace
}  // namespace csw
