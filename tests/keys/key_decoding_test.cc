#include "analysis/keys/key_decoding.h"

#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "core/error.h"
#include "core/labels.h"

namespace csw::keys {
namespace {

// Posteriors built from a frame-by-frame key script: each frame's key gets
// `high`, the rest share the remainder.
KeyPosteriors Script(const std::vector<std::pair<std::string, int>>& runs, double high = 0.9) {
  int64_t n = 0;
  for (const auto& r : runs) n += r.second;
  KeyPosteriors p;
  p.shape = Eigen::MatrixXd::Constant(n, kNumShapes, (1 - high) / (kNumShapes - 1));
  p.placement = Eigen::MatrixXd::Constant(n, kNumPlacements, (1 - high) / (kNumPlacements - 1));
  int64_t t = 0;
  for (const auto& [code, len] : runs) {
    ::csw::KeyCode key;
    EXPECT_TRUE(TryParseKeyCode(code, &key));
    const int pl = key.placement, sh = key.shape;
    for (int i = 0; i < len; ++i, ++t) {
      p.shape(t, sh) = high;
      p.placement(t, pl) = high;
    }
  }
  return p;
}

std::vector<std::string> Codes(const std::vector<DecodedKey>& keys) {
  std::vector<std::string> out;
  for (const auto& k : keys) out.push_back(k.Code());
  return out;
}

TEST(DecodeFree, RecoversKeysAndDropsBlipsShorterThanTheMinimumDuration) {
  // 100 Hz: min key 80 ms = 8 frames. A 3-frame blip of "33" inside "25" must go.
  const auto p = Script({{"00", 30}, {"25", 20}, {"33", 3}, {"25", 20}, {"41", 25}, {"00", 30}});
  const auto keys = DecodeFree(p, 100.0);
  EXPECT_EQ(Codes(keys), (std::vector<std::string>{"00", "25", "41", "00"}));
  ASSERT_EQ(keys.size(), 4u);
  EXPECT_EQ(keys[1].start_frame, 30);
  EXPECT_EQ(keys[1].end_frame, 73);
  EXPECT_EQ(keys[2].start_frame, 73);
  EXPECT_EQ(keys[2].end_frame, 98);
  EXPECT_EQ(keys[3].end_frame, 128);

  // A key held for 12 frames (>= 8) is kept.
  const auto q = Script({{"00", 30}, {"25", 20}, {"33", 12}, {"25", 20}, {"00", 30}});
  EXPECT_EQ(Codes(DecodeFree(q, 100.0)), (std::vector<std::string>{"00", "25", "33", "25", "00"}));
}

TEST(DecodeFree, JointDecodingMergesAShapeLeadIntoOneBoundary) {
  // The shape changes 3 frames before the placement (shape leads): the frames in
  // between score 15 (new shape, old placement), too short for a key.
  KeyPosteriors p = Script({{"11", 40}, {"35", 40}});
  for (int64_t t = 37; t < 40; ++t) {
    p.shape.row(t) = p.shape.row(45);
  }
  const auto keys = DecodeFree(p, 100.0);
  EXPECT_EQ(Codes(keys), (std::vector<std::string>{"11", "35"}));
}

TEST(DecodeFree, TargetFrameIsThePeakOfTheKeysJointPosterior) {
  KeyPosteriors p = Script({{"00", 20}, {"25", 30}, {"00", 20}}, 0.6);
  // Peak of 25 at frame 33 (both components).
  p.shape(33, 5) = 0.95;
  p.placement(33, 2) = 0.95;
  p.shape(40, 5) = 0.99;  // the shape alone peaks at 40
  const auto keys = DecodeFree(p, 100.0);
  ASSERT_EQ(keys.size(), 3u);
  EXPECT_EQ(keys[1].shape_target_frame, 40);
  EXPECT_EQ(keys[1].placement_target_frame, 33);
  // Joint: frame 33 (0.95 * 0.95 = 0.9025) vs frame 40 (0.99 * 0.6 = 0.594).
  EXPECT_EQ(keys[1].target_frame, 33);
}

TEST(DecodeAligned, PlacesTheExpectedSequenceOnThePosteriors) {
  // Expected 00 25 25 31 00: the two 25 keys share one run; the aligner must
  // split it, and the others fall on their runs exactly.
  const auto p = Script({{"00", 30}, {"25", 40}, {"31", 25}, {"00", 30}});
  const std::vector<ExpectedKey> expected = {{0, 0}, {2, 5}, {2, 5}, {3, 1}, {0, 0}};
  const auto keys = DecodeAligned(p, expected, 100.0);
  ASSERT_EQ(keys.size(), 5u);
  EXPECT_EQ(keys[0].start_frame, 0);
  EXPECT_EQ(keys[0].end_frame, 30);
  EXPECT_EQ(keys[1].start_frame, 30);
  EXPECT_EQ(keys[2].end_frame, 70);
  EXPECT_GE(keys[1].end_frame - keys[1].start_frame, 4);  // aligned_min_key_ms = 40 ms = 4 frames
  EXPECT_GE(keys[2].end_frame - keys[2].start_frame, 4);
  EXPECT_EQ(keys[3].start_frame, 70);
  EXPECT_EQ(keys[3].end_frame, 95);
  EXPECT_EQ(keys[4].end_frame, 125);
  // Target of key 31: the middle of its saturated plateau [70, 95).
  EXPECT_EQ(keys[3].target_frame, 82);

  // A key absent from the posteriors still gets its minimum segment.
  const std::vector<ExpectedKey> with_missing = {{0, 0}, {2, 5}, {4, 8}, {3, 1}, {0, 0}};
  const auto m = DecodeAligned(p, with_missing, 100.0);
  EXPECT_EQ(m[2].end_frame - m[2].start_frame, 4);
  EXPECT_THROW(DecodeAligned(p, {}, 100.0), InvalidInput);
  EXPECT_THROW(DecodeAligned(p, {{7, 0}}, 100.0), InvalidInput);
}

TEST(DecodeAligned, AFewConfidentlyWrongTransitionFramesDoNotPullAKeyOffItsHold) {
  // Keys 16 36 06 (shape 6 throughout; placements 1, 3, 0) at 100 Hz (shortest
  // segment 4 frames). Frames 0-20 hold 16; 20-60 hold 36, its placement
  // posterior ambiguous (3: 0.6, 1: 0.4, as placements 1 and 3 can be); 60-66
  // a transition where the Gaussians extrapolate: placement 1 at 0.99, 3 and
  // 0 at 1e-8; 66-90 hold 06.
  //   right: 36 over its hold, the 6 transition frames on 36 or 06: 6 log f;
  //   wrong: 16 over 36's hold (40 log(0.4/0.6) = -16.2), 36 squeezed into
  //   4 transition frames: -16.2 + 4 log f.
  // With f = 3e-3 (the default): 6 log f = -34.9 > -39.4, right. With the
  // floor of free decoding, 1e-6: -82.9 < -71.5, wrong.
  KeyPosteriors p;
  p.shape = Eigen::MatrixXd::Constant(90, kNumShapes, 0.0);
  p.shape.col(6).setOnes();
  p.placement = Eigen::MatrixXd::Constant(90, kNumPlacements, 0.0);
  p.placement.block(0, 1, 20, 1).setConstant(1.0);
  p.placement.block(20, 3, 40, 1).setConstant(0.6);
  p.placement.block(20, 1, 40, 1).setConstant(0.4);
  p.placement.block(60, 1, 6, 1).setConstant(0.99);
  p.placement.block(60, 3, 6, 1).setConstant(1e-8);
  p.placement.block(60, 0, 6, 1).setConstant(1e-8);
  p.placement.block(66, 0, 24, 1).setConstant(1.0);
  const std::vector<ExpectedKey> expected = {{1, 6}, {3, 6}, {0, 6}};
  const auto keys = DecodeAligned(p, expected, 100.0);
  ASSERT_EQ(keys.size(), 3u);
  EXPECT_EQ(keys[1].start_frame, 20);
  EXPECT_GE(keys[1].end_frame, 60);
  EXPECT_LE(keys[1].end_frame, 66);
  DecodeOptions strict;
  strict.aligned_floor = 1e-6;
  const auto pulled = DecodeAligned(p, expected, 100.0, strict);
  EXPECT_GE(pulled[1].start_frame, 60);
  strict.aligned_floor = 0.0;
  EXPECT_THROW(DecodeAligned(p, expected, 100.0, strict), InvalidInput);
}

TEST(AlignComponent, OneSegmentPerLabelAndWindowsPullSegmentsToTheirRange) {
  // Shape runs 0 (30 frames), 5 (40), 1 (25), 0 (30): the shape labels align
  // to their runs exactly.
  const auto p = Script({{"00", 30}, {"25", 40}, {"31", 25}, {"00", 30}});
  const auto s = AlignComponent(p.shape, {0, 5, 1, 0}, 100.0);
  ASSERT_EQ(s.size(), 4u);
  EXPECT_EQ(s[1].label, 5);
  EXPECT_EQ(s[1].start_frame, 30);
  EXPECT_EQ(s[2].start_frame, 70);
  EXPECT_EQ(s[3].start_frame, 95);
  EXPECT_EQ(s[3].end_frame, 125);
  // Shape 5 shows twice (20 frames, then 15): aligned as 0 5 0, label 5 takes
  // the longer run; a window around the second run moves it there.
  const auto q = Script({{"00", 30}, {"25", 20}, {"00", 20}, {"25", 15}, {"00", 30}});
  const auto longer = AlignComponent(q.shape, {0, 5, 0}, 100.0);
  EXPECT_EQ(longer[1].start_frame, 30);
  EXPECT_EQ(longer[1].end_frame, 50);
  const std::vector<std::pair<int64_t, int64_t>> windows = {{0, 115}, {60, 100}, {0, 115}};
  const auto held = AlignComponent(q.shape, {0, 5, 0}, 100.0, {}, windows);
  EXPECT_EQ(held[1].start_frame, 70);
  EXPECT_EQ(held[1].end_frame, 85);
  EXPECT_THROW(AlignComponent(p.shape, {}, 100.0), InvalidInput);
  EXPECT_THROW(AlignComponent(p.shape, {9}, 100.0), InvalidInput);
  EXPECT_THROW(AlignComponent(p.shape, {0, 5}, 100.0, {}, windows), InvalidInput);  // 3 windows, 2 labels
}

TEST(GestureExtents, RunsOfTheDominantClassAndKeysWithUnchangedComponentsExcluded) {
  const auto p = Script({{"00", 10}, {"25", 10}, {"35", 10}, {"00", 10}});
  const auto shape = GestureExtents(p.shape);
  ASSERT_EQ(shape.size(), 3u);  // 0, 5 (20 frames), 0
  EXPECT_EQ(shape[1].label, 5);
  EXPECT_EQ(shape[1].start_frame, 10);
  EXPECT_EQ(shape[1].end_frame, 30);
  const auto place = GestureExtents(p.placement);
  ASSERT_EQ(place.size(), 4u);

  const auto keys = DecodeAligned(p, {{0, 0}, {2, 5}, {3, 5}, {0, 0}}, 100.0);
  const auto ks = KeyExtents(shape, keys, Component::kShape);
  ASSERT_EQ(ks.size(), 4u);
  ASSERT_TRUE(ks[1].has_value());
  EXPECT_EQ(ks[1]->start_frame, 10);
  EXPECT_FALSE(ks[2].has_value());  // shape 5 follows shape 5: excluded
  const auto kp = KeyExtents(place, keys, Component::kPlacement);
  ASSERT_TRUE(kp[2].has_value());
  EXPECT_EQ(kp[2]->label, 3);
  EXPECT_EQ(kp[2]->start_frame, 20);
}

TEST(AlignSequences, CountsMatchesSubstitutionsInsertionsDeletions) {
  // expected: 00 25 31 43 00 ; decoded: 00 25 33 43 15 00 -> 31->33 substitution, 15 inserted.
  const auto a = AlignSequences({"00", "25", "33", "43", "15", "00"}, {"00", "25", "31", "43", "00"});
  EXPECT_EQ(a.matches, 4);
  EXPECT_EQ(a.substitutions, 1);
  EXPECT_EQ(a.insertions, 1);
  EXPECT_EQ(a.deletions, 0);
  const auto b = AlignSequences({"00", "00"}, {"00", "25", "31", "00"});
  EXPECT_EQ(b.matches, 2);
  EXPECT_EQ(b.deletions, 2);
  EXPECT_EQ(b.substitutions, 0);
  const auto c = AlignSequences({}, {"00"});
  EXPECT_EQ(c.deletions, 1);
  ASSERT_EQ(c.pairs.size(), 1u);
  EXPECT_EQ(c.pairs[0], (std::pair<int, int>{-1, 0}));
}

TEST(Confusion, AccuracyIsTheDiagonalShare) {
  Confusion c(3);
  c.Add(0, 0);
  c.Add(1, 1);
  c.Add(1, 2);
  c.Add(2, 2);
  EXPECT_EQ(c.Total(), 4);
  EXPECT_EQ(c.Correct(), 3);
  EXPECT_DOUBLE_EQ(c.Accuracy(), 0.75);
  EXPECT_EQ(c.counts(1, 2), 1);
}

}  // namespace
}  // namespace csw::keys
