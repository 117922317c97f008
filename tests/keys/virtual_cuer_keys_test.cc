// Key recognition on the virtual cuer (issue 11 "Done when"): default options
// (overlapping gestures, noise, occlusions, dropouts), raw takes (missing
// markers marginalised), trained on the labelled targets of the first third of
// the sentences, scored on the rest.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <numeric>
#include <random>

#include "analysis/cleaning/dct_fill.h"
#include "analysis/cleaning/fill.h"
#include "analysis/cleaning/spline_fill.h"
#include "analysis/keys/hand_features.h"
#include "analysis/keys/key_decoding.h"
#include "analysis/keys/key_model.h"
#include "analysis/keys/key_timing.h"
#include "core/error.h"
#include "core/labels.h"
#include "datasets/motion.h"
#include "datasets/virtual_cuer.h"
#include "models/gaussian_fill.h"
#include "models/rigid_motion.h"
#include "tests/testing/testing.h"

namespace csw::keys {
namespace {

SimulateOptions Defaults() {
  SimulateOptions o;
  o.audio = false;  // motion only: the audio does not change the markers
  return o;
}

TEST(HandLayout, DerivedFromSegmentChainsNotNames) {
  const VirtualCuer cuer(Defaults());
  const SimulationResult r = cuer.SimulateShapes("shapes", {1, 5, 8});
  MarkerSet set = cuer.MakeMarkerSet(CorpusKind::kShapes);
  const MarkerBinding binding = BindMarkerSet(set, r.take.marker_names, false);
  const HandLayout layout = DeriveHandLayout(set, r.take.markers, binding, "shapes");
  // Known answer from the virtual hand's definition (datasets/virtual_cuer.cc):
  // proximal phalanx markers "?1P", tip markers "?TIP".
  EXPECT_EQ(layout.proximal, (std::array<std::string, 5>{"T1P", "I1P", "M1P", "R1P", "L1P"}));
  EXPECT_EQ(layout.distal, (std::array<std::string, 5>{"TTIP", "ITIP", "MTIP", "RTIP", "LTIP"}));
  EXPECT_EQ(layout.palm, set.palm);
  EXPECT_EQ(layout.head, set.head_cluster);
  EXPECT_EQ(layout.thumb_palm, "KNL");  // the little finger's knuckle

  // Segment names and order carry no meaning: renamed and shuffled, same layout.
  MarkerSet renamed = set;
  std::map<std::string, std::string> new_name;
  for (size_t i = 0; i < renamed.hand_segments.size(); ++i)
    new_name[renamed.hand_segments[i].name] = "seg" + std::to_string((i * 7) % 16);
  for (auto& s : renamed.hand_segments) {
    s.name = new_name[s.name];
    if (!s.parent.empty()) s.parent = new_name[s.parent];
  }
  std::reverse(renamed.hand_segments.begin() + 1, renamed.hand_segments.end());
  EXPECT_EQ(DeriveHandLayout(renamed, r.take.markers, binding, "shapes"), layout);

  // The explicit section names the same markers; errors name the place.
  const auto json = HandLayoutToJson(layout);
  EXPECT_EQ(ParseHandLayout(json, set, "lab.json: hand_layout"), layout);
  auto bad = json;
  bad["fingers"]["pinky"] = {"A", "B"};
  try {
    ParseHandLayout(bad, set, "lab.json: hand_layout");
    FAIL() << "unknown finger accepted";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("lab.json: hand_layout: unknown finger \"pinky\""), std::string::npos)
        << e.what();
  }
}

// The virtual cuer without marker noise, occlusions or dropouts.
SimulateOptions Noiseless() {
  SimulateOptions o = Defaults();
  o.noise_mm = 0;
  o.occlusions = false;
  o.dropouts_per_s = 0;
  return o;
}

TEST(HandFeatures, DistancesSeparateTheShapesAndMissingMarkersGiveNaN) {
  const VirtualCuer cuer(Noiseless());
  const SimulationResult r = cuer.SimulateShapes("shapes", {1, 6, 2, 8});
  const MarkerSet set = cuer.MakeMarkerSet(CorpusKind::kShapes);
  const MarkerBinding binding = BindMarkerSet(set, r.take.marker_names, false);
  const HandLayout layout = DeriveHandLayout(set, r.take.markers, binding);
  const Eigen::Matrix3Xd head = HeadReference(r.take.markers, binding, layout);
  const HandFeatures f = ComputeHandFeatures(r.take.markers, binding, layout, head);
  ASSERT_EQ(f.frames(), r.take.frames());
  // At each key's shape target the features show the posture: shape 1 (index
  // only) vs 6 (index + thumb): thumb-palm distance larger for 6; 2 vs 8: the
  // index-middle tip distance larger for 8 (spread); index extended in all four
  // and middle extended only in 2 and 8.
  std::map<int, Eigen::RowVectorXd> at;
  for (const auto& k : r.keys)
    if (k.key.shape != 0) at[k.key.shape] = f.distances.row(std::llround(k.timing.shape_target_s * r.take.rate_hz));
  ASSERT_EQ(at.size(), 4u);
  EXPECT_GT(at[6](6), at[1](6) + 20);  // thumb tip to the palm's ulnar edge (mm): 154 vs 118 at rest pose
  EXPECT_GT(at[8](5), at[2](5) + 10);  // index-middle tips
  EXPECT_GT(at[2](2), at[1](2) + 20);  // middle extension
  EXPECT_GT(at[1](1), at[1](2) + 20);  // index extended, middle folded

  // A hidden thumb tip: thumb extension and thumb-palm distance NaN, the rest kept.
  MarkerArray hidden = r.take.markers;
  const int64_t t = r.take.frames() / 2;
  hidden.SetMissing(t, binding.At("TTIP"));
  const HandFeatures g = ComputeHandFeatures(hidden, binding, layout, head);
  EXPECT_TRUE(std::isnan(g.distances(t, 0)));
  EXPECT_TRUE(std::isnan(g.distances(t, 6)));
  EXPECT_NEAR(g.distances(t, 1), f.distances(t, 1), 1e-9);
  EXPECT_NEAR(g.index_tip(t, 2), f.index_tip(t, 2), 1e-9);
}

// The fingertips in the palm's frame (shape movements are timed on them,
// key_timing.h): distances between them are the world distances, a rigid
// motion of the whole capture leaves them unchanged, a finger moving in the
// palm moves its own tip only, and a hidden tip or too few palm markers give
// NaN.
TEST(HandFeatures, TipsInThePalmFrameFollowTheFingersNotTheHand) {
  const VirtualCuer cuer(Noiseless());
  const SimulationResult r = cuer.SimulateShapes("shapes", {1, 5});
  const MarkerSet set = cuer.MakeMarkerSet(CorpusKind::kShapes);
  const MarkerBinding binding = BindMarkerSet(set, r.take.marker_names, false);
  const HandLayout layout = DeriveHandLayout(set, r.take.markers, binding);
  const Eigen::Matrix3Xd head = HeadReference(r.take.markers, binding, layout);
  const HandFeatures f = ComputeHandFeatures(r.take.markers, binding, layout, head);
  ASSERT_EQ(f.tips_in_palm.rows(), r.take.frames());
  ASSERT_EQ(f.tips_in_palm.cols(), 15);
  for (int64_t t = 0; t < r.take.frames(); t += 7) {
    const Eigen::Vector3d index = f.tips_in_palm.block<1, 3>(t, 3).transpose();
    const Eigen::Vector3d middle = f.tips_in_palm.block<1, 3>(t, 6).transpose();
    EXPECT_NEAR((index - middle).norm(), f.distances(t, 5), 1e-6) << "frame " << t;
  }
  // The whole capture turned by 40 degrees and moved by half a metre.
  RigidTransform motion;
  motion.rotation = Eigen::AngleAxisd(0.7, Eigen::Vector3d(0.3, -0.5, 0.8).normalized()).toRotationMatrix();
  motion.translation = Eigen::Vector3d(500.0, -200.0, 120.0);
  MarkerArray moved = r.take.markers;
  for (int64_t t = 0; t < moved.frames(); ++t)
    for (int64_t i = 0; i < moved.markers(); ++i) {
      float* v = moved.at(t, i);
      if (!std::isfinite(v[0])) continue;
      const Eigen::Vector3d p = motion.Apply(Eigen::Vector3d(v[0], v[1], v[2]));
      for (int c = 0; c < 3; ++c) v[c] = static_cast<float>(p[c]);
    }
  const HandFeatures g = ComputeHandFeatures(moved, binding, layout, HeadReference(moved, binding, layout));
  // (The palm frame's axes are those of its first complete frame, so compare
  // what does not depend on them: how far each tip moved in the palm between
  // two frames.)
  const int64_t last = r.take.frames() - 1;
  for (int64_t t = 0; t < last; t += 11)
    for (int finger = 0; finger < 5; ++finger) {
      const double before =
          (f.tips_in_palm.block<1, 3>(t, 3 * finger) - f.tips_in_palm.block<1, 3>(last, 3 * finger)).norm();
      const double after =
          (g.tips_in_palm.block<1, 3>(t, 3 * finger) - g.tips_in_palm.block<1, 3>(last, 3 * finger)).norm();
      EXPECT_NEAR(after, before, 0.01) << "frame " << t << " finger " << finger;  // mm (float storage)
    }
  // Shape 1 -> 5 (index only -> the flat hand): the middle, ring and little
  // tips travel tens of millimetres in the palm; the index tip, extended in
  // both, far less.
  const auto frame = [&](double s) { return std::llround(s * r.take.rate_hz); };
  const int64_t a = frame(r.keys[1].timing.shape_target_s), b = frame(r.keys[2].timing.shape_target_s);
  const Eigen::RowVectorXd travel = f.tips_in_palm.row(b) - f.tips_in_palm.row(a);
  for (int finger : {2, 3, 4}) EXPECT_GT(travel.segment<3>(3 * finger).norm(), 30.0) << "finger " << finger;
  EXPECT_LT(travel.segment<3>(3).norm(), 15.0);
  // A hidden index tip: its three columns NaN, the others kept; two palm
  // markers left: the whole row NaN.
  MarkerArray hidden = r.take.markers;
  const int64_t t = r.take.frames() / 2;
  hidden.SetMissing(t, binding.At(layout.distal[1]));
  for (size_t i = 0; i + 2 < layout.palm.size(); ++i) hidden.SetMissing(t + 1, binding.At(layout.palm[i]));
  const HandFeatures h = ComputeHandFeatures(hidden, binding, layout, head);
  EXPECT_TRUE((h.tips_in_palm.block<1, 3>(t, 3).array().isNaN().all()));
  EXPECT_NEAR(h.tips_in_palm(t, 6), f.tips_in_palm(t, 6), 1e-4);
  EXPECT_TRUE(h.tips_in_palm.row(t + 1).array().isNaN().all());
  EXPECT_NEAR(h.tips_in_palm(t + 2, 0), f.tips_in_palm(t + 2, 0), 1e-4);
}

// The "model fill" of the hand: the hand markers in the palm frame (rigid fit
// of the palm markers) as one Gaussian vector (models/gaussian_fill.h, EM on
// the training takes' incomplete frames); missing hand markers of a frame are
// its conditional mean given the seen ones. Frames with < 3 palm markers stay.
struct PalmFrames {
  std::vector<int> palm_cols, hand_cols;
  Eigen::Matrix3Xd reference;
  // frames × 3·hand markers in the palm frame, NaN when missing; transforms per frame.
  Eigen::MatrixXd Local(const MarkerArray& m, std::vector<RigidTransform>* pose, std::vector<uint8_t>* ok) const {
    Eigen::MatrixXd out = Eigen::MatrixXd::Constant(m.frames(), 3 * static_cast<Eigen::Index>(hand_cols.size()),
                                                    std::numeric_limits<double>::quiet_NaN());
    pose->assign(static_cast<size_t>(m.frames()), RigidTransform{});
    ok->assign(static_cast<size_t>(m.frames()), 0);
    Eigen::Matrix3Xd obs(3, static_cast<Eigen::Index>(palm_cols.size()));
    for (int64_t t = 0; t < m.frames(); ++t) {
      for (size_t i = 0; i < palm_cols.size(); ++i) {
        const float* v = m.at(t, palm_cols[i]);
        obs.col(static_cast<Eigen::Index>(i)) = Eigen::Vector3d(v[0], v[1], v[2]);
      }
      const RigidFit fit = EstimateRigidKabsch(reference, obs);
      if (!fit.valid) continue;
      (*pose)[static_cast<size_t>(t)] = fit.transform;
      (*ok)[static_cast<size_t>(t)] = 1;
      const RigidTransform inv = fit.transform.Inverse();
      for (size_t j = 0; j < hand_cols.size(); ++j) {
        const float* v = m.at(t, hand_cols[j]);
        if (!std::isfinite(v[0])) continue;
        out.block<1, 3>(t, 3 * static_cast<Eigen::Index>(j)) = inv.Apply(Eigen::Vector3d(v[0], v[1], v[2])).transpose();
      }
    }
    return out;
  }
};

MarkerArray ModelFill(const PalmFrames& pf, const GaussianFill& fill, const MarkerArray& in) {
  std::vector<RigidTransform> pose;
  std::vector<uint8_t> ok;
  const Eigen::MatrixXd local = pf.Local(in, &pose, &ok);
  MarkerArray out = in;
  GaussianFiller filler(fill);
  for (int64_t t = 0; t < in.frames(); ++t) {
    if (!ok[static_cast<size_t>(t)]) continue;
    Eigen::Matrix3Xd x = Eigen::Map<const Eigen::Matrix3Xd>(local.row(t).eval().data(), 3,
                                                            static_cast<Eigen::Index>(pf.hand_cols.size()));
    if (filler.Fill(&x) == 0) continue;
    for (size_t j = 0; j < pf.hand_cols.size(); ++j) {
      if (in.Visible(t, pf.hand_cols[j])) continue;
      const Eigen::Vector3d p = pose[static_cast<size_t>(t)].Apply(x.col(static_cast<Eigen::Index>(j)));
      for (int c = 0; c < 3; ++c) out.at(t, pf.hand_cols[j])[c] = static_cast<float>(p[c]);
    }
  }
  return out;
}

// A key's component counts as only approached when, at its target time, the
// hand has already made more than this share of the component's next change.
constexpr double kApproachedShare = 0.1;

// The share of the next change of a component (shape or placement) made by
// the key's target time: s((t_k - start_j) / (target_j - start_j)) for the
// next key j whose component differs (0 when none does).
double NextMoveShareAtTarget(const std::vector<GestureTruth>& truth, size_t k, bool shape) {
  const double t = shape ? truth[k].timing.shape_target_s : truth[k].timing.placement_target_s;
  for (size_t j = k + 1; j < truth.size(); ++j) {
    const bool differs =
        shape ? truth[j].key.shape != truth[k].key.shape : truth[j].key.placement != truth[k].key.placement;
    if (!differs) continue;
    const double start = shape ? truth[j].timing.shape_start_s : truth[j].timing.placement_start_s;
    const double target = shape ? truth[j].timing.shape_target_s : truth[j].timing.placement_target_s;
    return target > start ? MinimumJerk((t - start) / (target - start)) : (t >= target ? 1.0 : 0.0);
  }
  return 0.0;
}

struct Scored {
  SimulationResult r;
  std::array<HandFeatures, 3> features;  // spline/DCT-filled take, clean markers, model-filled take
  KeyLabels labels;
};

struct Tally {
  Confusion shape{kNumShapes}, placement{kNumPlacements};
  Confusion shape_reached{kNumShapes}, shape_approached{kNumShapes};
  Confusion placement_reached{kNumPlacements}, placement_approached{kNumPlacements};
  int free_expected = 0, free_matches = 0, free_insertions = 0, free_deletions = 0, free_substitutions = 0;
  int free_reached = 0, free_reached_matches = 0;  // keys whose components are both reached
  int aligned_keys = 0, aligned_correct = 0;
  // Aligned keys whose target time is nearer their own true target than the
  // neighbouring keys' (the alignment put the key on its own gesture).
  int aligned_own = 0, aligned_own_reached = 0, aligned_reached = 0;
  std::vector<double> aligned_error_ms, aligned_shape_error_ms, aligned_placement_error_ms;
  std::vector<double> aligned_error_reached_ms, aligned_error_approached_ms;
  // The same keys' errors without the speech anchors (A1 left unknown).
  std::vector<double> unanchored_error_ms, unanchored_error_reached_ms;
  int speech_timed_repeats = 0, speech_replaced_targets = 0;
  double free_rate = 0, aligned_rate = 0;
  int approached_keys = 0, strict_approached = 0;  // a component approached; any overlap at all
};

double Mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}

double Sd(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double m = Mean(v);
  double s = 0.0;
  for (double x : v) s += (x - m) * (x - m);
  return std::sqrt(s / static_cast<double>(v.size() - 1));
}

double Worst(const std::vector<double>& v) { return v.empty() ? 0.0 : *std::max_element(v.begin(), v.end()); }

// The accuracy bars on the reached keys (shape and placement at their
// labelled frames, free decoding), held wherever the layout, timing, rate or
// hand size differ from the defaults.
void ExpectReachedAccuracies(const Tally& t) {
  EXPECT_GE(t.shape_reached.Accuracy(), 0.97);
  EXPECT_GE(t.placement_reached.Accuracy(), 0.95);
  EXPECT_GE(static_cast<double>(t.free_reached_matches) / t.free_reached, 0.90);
}

// Trains on takes [0, train) and scores the others, with feature set `variant`
// (0 = filled take, 1 = markers without artefacts).
Tally Evaluate(const std::vector<Scored>& takes, int train, int variant, const HandLayout& layout,
               const Eigen::Matrix3Xd& head, const std::string& name) {
  KeyModelOptions mo;
  KeyTrainingSet ts;
  for (int i = 0; i < train; ++i) ts.Add(takes[i].features[variant], takes[i].labels, mo);
  const KeyModel model = TrainKeyModel(ts, layout, head, mo);
  Tally tally;

  // Missing feature share at the held-out targets (raw takes).
  int64_t incomplete = 0, targets = 0;
  std::array<int64_t, kNumDistances + 1> missing_dim{};
  for (int i = train; i < static_cast<int>(takes.size()); ++i) {
    const Scored& s = takes[i];
    const double rate = s.r.take.rate_hz;
    const KeyPosteriors post = ScoreFrames(model, s.features[variant]);
    // Approached keys: the gestures are superposed minimum-jerk movements, so
    // when the next change of a component starts before this key's target,
    // the hand turns away early. At the target time it is then the share of
    // the next movement already made away from the key's posture; a key whose
    // share exceeds kApproachedShare (the hand stays more than a tenth of the
    // next movement away) is only approached. Counted from the simulator's
    // truth alone. Also counted: any overlap at all (the strict count).
    const auto& truth = s.r.keys;
    std::vector<bool> shape_approached(truth.size(), false), placement_approached(truth.size(), false);
    for (size_t k = 0; k + 1 < truth.size(); ++k) {
      shape_approached[k] = NextMoveShareAtTarget(truth, k, true) > kApproachedShare;
      placement_approached[k] = NextMoveShareAtTarget(truth, k, false) > kApproachedShare;
      tally.strict_approached += truth[k + 1].timing.shape_start_s < truth[k].timing.shape_target_s ||
                                 truth[k + 1].timing.placement_start_s < truth[k].timing.placement_target_s;
      tally.approached_keys += shape_approached[k] || placement_approached[k];
    }
    for (size_t k = 0; k < truth.size(); ++k) {
      const int64_t fs = std::clamp<int64_t>(std::llround(truth[k].timing.shape_target_s * rate), 0, s.r.frames() - 1);
      const int64_t fp =
          std::clamp<int64_t>(std::llround(truth[k].timing.placement_target_s * rate), 0, s.r.frames() - 1);
      ++targets;
      if (!s.features[variant].distances.row(fs).allFinite()) ++incomplete;
      for (int dd = 0; dd < kNumDistances; ++dd)
        missing_dim[dd] += std::isnan(s.features[variant].distances(fs, dd)) ? 1 : 0;
      missing_dim[7] += std::isnan(post.placement_features(fp, 0)) ? 1 : 0;
      const int ds = ArgMax(post.shape, fs), dp = ArgMax(post.placement, fp);
      tally.shape.Add(truth[k].key.shape, ds);
      tally.placement.Add(truth[k].key.placement, dp);
      (shape_approached[k] ? tally.shape_approached : tally.shape_reached).Add(truth[k].key.shape, ds);
      (placement_approached[k] ? tally.placement_approached : tally.placement_reached).Add(truth[k].key.placement, dp);
    }
    // Free decoding against the expected sequence.
    std::vector<std::string> expected;
    std::vector<ExpectedKey> expected_keys;
    for (const auto& k : truth) {
      expected.push_back(k.key.Code());
      ExpectedKey e{k.key.placement, k.key.shape};
      if (k.key.type != KeyType::kRest) {
        e.anchor_s = k.key.a1_s;
        e.vowel_anchor = k.key.type == KeyType::kVowelAlone;
      }
      expected_keys.push_back(e);
    }
    const auto free = DecodeFree(post, rate);
    std::vector<std::string> decoded;
    for (const auto& k : free) decoded.push_back(k.Code());
    const EditAlignment a = AlignSequences(decoded, expected);
    tally.free_expected += static_cast<int>(expected.size());
    tally.free_matches += a.matches;
    for (const auto& [d, x] : a.pairs) {
      if (x < 0 || shape_approached[x] || placement_approached[x]) continue;
      ++tally.free_reached;
      if (d >= 0 && decoded[d] == expected[x]) ++tally.free_reached_matches;
    }
    tally.free_insertions += a.insertions;
    tally.free_deletions += a.deletions;
    tally.free_substitutions += a.substitutions;
    // Aligned decoding: target frame vs the labelled (shape) target.
    const auto timed = DecodeAlignedTimed(model, s.features[variant], post, expected_keys, rate);
    KeyTimingOptions without_anchors;
    without_anchors.speech_anchors = false;
    const auto unanchored = DecodeAlignedTimed(model, s.features[variant], post, expected_keys, rate, without_anchors);
    std::vector<DecodedKey> aligned;
    for (const auto& t : timed) aligned.push_back(t.key);
    for (size_t k = 0; k < truth.size(); ++k) {
      // Components that change from the previous key have a target; the key's
      // error is the mean over them (the key target vs the shape target when
      // neither changes).
      const bool shape_changes = k == 0 || truth[k].key.shape != truth[k - 1].key.shape;
      const bool place_changes = k == 0 || truth[k].key.placement != truth[k - 1].key.placement;
      const double es = 1000.0 * std::abs(timed[k].shape.target_s - truth[k].timing.shape_target_s);
      const double ep = 1000.0 * std::abs(timed[k].placement.target_s - truth[k].timing.placement_target_s);
      auto key_error = [&](const TimedKey& t) {
        const double es = 1000.0 * std::abs(t.shape.target_s - truth[k].timing.shape_target_s);
        const double ep = 1000.0 * std::abs(t.placement.target_s - truth[k].timing.placement_target_s);
        return shape_changes && place_changes ? 0.5 * (es + ep)
               : shape_changes                ? es
               : place_changes                ? ep
                                              : 1000.0 * std::abs(t.target_s - truth[k].timing.shape_target_s);
      };
      const double err = key_error(timed[k]);
      tally.unanchored_error_ms.push_back(key_error(unanchored[k]));
      if (!shape_approached[k] && !placement_approached[k])
        tally.unanchored_error_reached_ms.push_back(key_error(unanchored[k]));
      tally.speech_timed_repeats += timed[k].target_from_speech ? 1 : 0;
      tally.speech_replaced_targets += (timed[k].shape.changes && timed[k].shape.from_speech ? 1 : 0) +
                                       (timed[k].placement.changes && timed[k].placement.from_speech ? 1 : 0);
      tally.aligned_error_ms.push_back(err);
      (shape_approached[k] || placement_approached[k] ? tally.aligned_error_approached_ms
                                                      : tally.aligned_error_reached_ms)
          .push_back(err);
      if (shape_changes) tally.aligned_shape_error_ms.push_back(es);
      if (place_changes) tally.aligned_placement_error_ms.push_back(ep);
      ++tally.aligned_keys;
      if (std::getenv("CSW_KEYS_DEBUG") != nullptr && variant == std::atoi(std::getenv("CSW_KEYS_DEBUG")))
        std::cout << truth[k].key.Code() << " joint " << aligned[k].start_frame << "-" << aligned[k].end_frame
                  << " shape truth " << std::llround(truth[k].timing.shape_start_s * rate) << "-"
                  << std::llround(truth[k].timing.shape_target_s * rate) << " seg " << timed[k].shape.segment_start
                  << "-" << timed[k].shape.segment_end << " rough " << timed[k].shape.rough_frame << " fit "
                  << timed[k].shape.onset_s * rate << "-" << timed[k].shape.target_s * rate
                  << (shape_changes ? "" : " (held)") << " | placement truth "
                  << std::llround(truth[k].timing.placement_start_s * rate) << "-"
                  << std::llround(truth[k].timing.placement_target_s * rate) << " seg "
                  << timed[k].placement.segment_start << "-" << timed[k].placement.segment_end << " rough "
                  << timed[k].placement.rough_frame << " fit " << timed[k].placement.onset_s * rate << "-"
                  << timed[k].placement.target_s * rate << (place_changes ? "" : " (held)") << " key "
                  << timed[k].target_s * rate << " err " << err << " cat " << (shape_changes ? "S" : "-")
                  << (place_changes ? "P" : "-")
                  << (shape_approached[k] || placement_approached[k] ? " approached" : " reached") << " unanchored "
                  << unanchored[k].shape.target_s * rate << "/" << unanchored[k].placement.target_s * rate << " err "
                  << key_error(unanchored[k]) << (timed[k].shape.from_speech ? " S<-A1" : "")
                  << (timed[k].placement.from_speech ? " P<-A1" : "") << "\n";
      if (err <= 40.0) ++tally.aligned_correct;
      {
        // On its own gesture: each changing component's target is nearer its
        // own true target than the true targets of that component's previous
        // and next changes (a repeated key: its target against the shape
        // targets of its neighbours).
        auto nearer_own = [&](bool shape_component, double t) {
          auto changes_at = [&](size_t j) {
            return j == 0 || (shape_component ? truth[j].key.shape != truth[j - 1].key.shape
                                              : truth[j].key.placement != truth[j - 1].key.placement);
          };
          auto target_of = [&](size_t j) {
            return shape_component ? truth[j].timing.shape_target_s : truth[j].timing.placement_target_s;
          };
          const double d = std::abs(t - target_of(k));
          for (size_t j = k; j-- > 0;)
            if (changes_at(j)) {
              if (std::abs(t - target_of(j)) <= d) return false;
              break;
            }
          for (size_t j = k + 1; j < truth.size(); ++j)
            if (changes_at(j)) {
              if (std::abs(t - target_of(j)) <= d) return false;
              break;
            }
          return true;
        };
        bool own = true;
        if (shape_changes) own = own && nearer_own(true, timed[k].shape.target_s);
        if (place_changes) own = own && nearer_own(false, timed[k].placement.target_s);
        if (!shape_changes && !place_changes) {
          const double d = std::abs(timed[k].target_s - truth[k].timing.shape_target_s);
          own = (k == 0 || d < std::abs(timed[k].target_s - truth[k - 1].timing.shape_target_s)) &&
                (k + 1 == truth.size() || d < std::abs(timed[k].target_s - truth[k + 1].timing.shape_target_s));
        }
        const bool reached = !shape_approached[k] && !placement_approached[k];
        tally.aligned_own += own ? 1 : 0;
        tally.aligned_reached += reached ? 1 : 0;
        tally.aligned_own_reached += own && reached ? 1 : 0;
      }
    }
  }
  tally.free_rate = static_cast<double>(tally.free_matches) / tally.free_expected;
  tally.aligned_rate = static_cast<double>(tally.aligned_correct) / tally.aligned_keys;
  std::cout << name << ": held-out takes " << static_cast<int>(takes.size()) - train << ", targets " << targets << " ("
            << tally.approached_keys << " with a component approached; " << tally.strict_approached
            << " overlap their next gesture at all)"
            << " (features incomplete at " << incomplete << "; missing per distance, then placement:";
  for (auto m : missing_dim) std::cout << " " << m;
  std::cout << ")\n"
            << "shape accuracy " << tally.shape.Accuracy() << " of " << tally.shape.Total() << " (reached "
            << tally.shape_reached.Accuracy() << " of " << tally.shape_reached.Total() << ", approached "
            << tally.shape_approached.Accuracy() << " of " << tally.shape_approached.Total() << ")\n"
            << "placement accuracy " << tally.placement.Accuracy() << " of " << tally.placement.Total() << " (reached "
            << tally.placement_reached.Accuracy() << " of " << tally.placement_reached.Total() << ", approached "
            << tally.placement_approached.Accuracy() << " of " << tally.placement_approached.Total() << ")\n"
            << "free decoding " << tally.free_matches << " / " << tally.free_expected << " = " << tally.free_rate
            << " (subs " << tally.free_substitutions << ", ins " << tally.free_insertions << ", del "
            << tally.free_deletions << "); reached keys " << tally.free_reached_matches << " / " << tally.free_reached
            << "\n"
            << "aligned " << tally.aligned_correct << " / " << tally.aligned_keys << " = " << tally.aligned_rate
            << ", key target error mean " << Mean(tally.aligned_error_ms) << " ms (sd " << Sd(tally.aligned_error_ms)
            << ", max " << Worst(tally.aligned_error_ms) << "); shape target " << Mean(tally.aligned_shape_error_ms)
            << " ms, placement target " << Mean(tally.aligned_placement_error_ms) << " ms; reached keys "
            << Mean(tally.aligned_error_reached_ms) << " ms ("
            << std::count_if(tally.aligned_error_reached_ms.begin(), tally.aligned_error_reached_ms.end(),
                             [](double e) { return e <= 40.0; })
            << " / " << tally.aligned_error_reached_ms.size() << " within 40 ms), approached "
            << Mean(tally.aligned_error_approached_ms) << " ms (" << tally.aligned_error_approached_ms.size() << ")\n"
            << "aligned keys on their own gesture (each changing component's target nearer its true target than "
               "the neighbouring changes') "
            << tally.aligned_own << " / " << tally.aligned_keys << ", reached keys " << tally.aligned_own_reached
            << " / " << tally.aligned_reached << "\n"
            << "speech anchors: " << tally.speech_timed_repeats << " repeated keys timed from A1, "
            << tally.speech_replaced_targets << " outlying targets replaced; without them "
            << Mean(tally.unanchored_error_ms) << " ms, reached keys " << Mean(tally.unanchored_error_reached_ms)
            << " ms\n"
            << "shape confusion (rows truth)\n"
            << tally.shape.counts << "\nplacement confusion\n"
            << tally.placement.counts << "\n";
  return tally;
}

// `sentences` simulated takes with their labels and the features of the
// spline/DCT-filled take (variant 0) and of the clean markers (variants 1 and
// 2); the hand layout and head reference derived from the first take.
std::vector<Scored> SimulateScored(const VirtualCuer& cuer, int sentences, const std::string& prefix,
                                   HandLayout& layout, Eigen::Matrix3Xd& head) {
  const MarkerSet set = cuer.MakeMarkerSet();
  const std::vector<std::string> texts = ShippedSentences();
  std::vector<Scored> takes;
  for (int i = 0; i < sentences; ++i) {
    Scored s;
    s.r = cuer.SimulateSentence(prefix + std::to_string(i), texts[static_cast<size_t>(i)]);
    const MarkerBinding binding = BindMarkerSet(set, s.r.take.marker_names, false);
    if (i == 0) {
      layout = DeriveHandLayout(set, s.r.take.markers, binding, s.r.take.name);
      head = HeadReference(s.r.take.markers, binding, layout);
    }
    const cleaning::SplineFiller spline{cleaning::SplineFillOptions{}};
    const cleaning::DctFiller dct{cleaning::DctFillOptions{}};
    MarkerArray filled;
    cleaning::FillGaps(s.r.take.markers, {&spline, &dct}, static_cast<int64_t>(0.5 * s.r.take.rate_hz), &filled);
    s.features[0] = ComputeHandFeatures(filled, binding, layout, head);
    s.features[1] = ComputeHandFeatures(s.r.clean, binding, layout, head);
    s.features[2] = s.features[1];
    const KeyTargets targets = ReadKeyTargets(s.r.take, s.r.take.name);
    EXPECT_TRUE(targets.placement_from_own_tier);
    s.labels = LabelsFromTargets(targets, s.r.take.rate_hz, s.r.take.frames(), s.r.take.name);
    takes.push_back(std::move(s));
  }
  return takes;
}

TEST(VirtualCuerKeys, TrainOnAThirdScoreTheRest) {
  const int sentences = testing::kSanitized ? 6 : 30;
  const VirtualCuer cuer(Defaults());
  const MarkerSet set = cuer.MakeMarkerSet();
  ASSERT_GE(static_cast<int>(ShippedSentences().size()), sentences);
  HandLayout layout;
  Eigen::Matrix3Xd head;
  // The filled takes (spline, then DCT, gaps up to 0.5 s, as `csw clean
  // --fill`; what stays missing is marginalised) and the markers without
  // artefacts, to separate the recogniser from the capture.
  std::vector<Scored> takes = SimulateScored(cuer, sentences, "s", layout, head);
  const int train = sentences / 3;
  {
    // Model-filled takes (variant 2): the palm-frame Gaussian fill trained on
    // the training takes' raw markers.
    PalmFrames pf;
    const MarkerBinding b0 = BindMarkerSet(set, takes[0].r.take.marker_names, false);
    for (const auto& m : layout.palm) pf.palm_cols.push_back(b0.At(m));
    for (const auto& seg : set.hand_segments)
      for (const auto& m : seg.markers)
        if (std::find(pf.hand_cols.begin(), pf.hand_cols.end(), b0.At(m)) == pf.hand_cols.end())
          pf.hand_cols.push_back(b0.At(m));
    pf.reference = ClusterReference(takes[0].r.take.markers, pf.palm_cols);
    std::vector<Eigen::MatrixXd> blocks;
    Eigen::Index rows = 0;
    for (int i = 0; i < train; ++i) {
      std::vector<RigidTransform> pose;
      std::vector<uint8_t> ok;
      blocks.push_back(pf.Local(takes[i].r.take.markers, &pose, &ok));
      rows += blocks.back().rows();
    }
    Eigen::MatrixXd data(rows, blocks[0].cols());
    rows = 0;
    for (const auto& b : blocks) {
      data.middleRows(rows, b.rows()) = b;
      rows += b.rows();
    }
    GaussianFillOptions fo;
    if (testing::kSanitized) fo.max_iterations = 20;
    const GaussianFill fill = FitGaussianFill(data, fo);
    for (auto& s : takes) {
      const MarkerBinding binding = BindMarkerSet(set, s.r.take.marker_names, false);
      s.features[2] = ComputeHandFeatures(ModelFill(pf, fill, s.r.take.markers), binding, layout, head);
    }
  }
  const Tally filled = Evaluate(takes, train, 0, layout, head, "filled takes");
  const Tally clean = Evaluate(takes, train, 1, layout, head, "clean markers");
  const Tally model = Evaluate(takes, train, 2, layout, head, "model-filled takes");
  RecordProperty("shape_accuracy", std::to_string(model.shape.Accuracy()));
  RecordProperty("placement_accuracy", std::to_string(model.placement.Accuracy()));
  RecordProperty("free_rate", std::to_string(model.free_rate));
  RecordProperty("aligned_rate", std::to_string(model.aligned_rate));
  RecordProperty("aligned_error_ms", std::to_string(Mean(model.aligned_error_ms)));
  if (testing::kSanitized) {
    // 6 sentences, 2 for training: too few for the statistics; the rest keys
    // (00, two per take, far from everything) must still be found.
    EXPECT_GE(clean.shape.counts(0, 0), clean.shape.counts.row(0).sum() - 1);
    return;
  }
  // Issue 11's bars are shape and placement >= 0.97, free >= 0.90, aligned
  // >= 0.98 within 40 ms, mean target error <= 25 ms. NOT MET (docs/analysis.md).
  // Measured on the filled takes (seed 1, 30 sentences, 236 held-out keys):
  // shape 0.754, placement 0.839, free 190/236 = 0.805 (148 insertions),
  // aligned (kinematic target times, analysis/keys/key_timing.h) 161/236 =
  // 0.682 within 40 ms, mean target error 47.8 ms (sd 68.7, max 368). Clean
  // markers: shape 0.903 (reached keys 1.000, approached 0.566), placement
  // 0.903 (reached 0.985, approached 0.792), free 0.873, aligned 0.792,
  // 35.1 ms (sd 61.0, max 512).
  // Model-filled takes (palm-frame Gaussian fill trained on the training
  // takes): shape 0.915 (reached 1.000, approached 0.623), placement 0.907
  // (reached 0.985, approached 0.802), free 204/236 = 0.864, aligned 0.763,
  // 35.8 ms (sd 53.7, max 326; reached keys 24.9 ms). (2026-12-03, with
  // repeated keys interpolated, three refits and a 100 ms segment margin;
  // before: aligned 0.712,
  // 46.0 ms, sd 79.6, max 533; clean 0.767, 43.4 ms; filled 0.665, 55.7 ms.
  // Before the kinematic target times: aligned 0.10-0.14, 93-104 ms.)
  // Reached and approached (2026-12-03): a key counts as approached when the
  // hand has made more than kApproachedShare of a component's next change by
  // that component's target (before, any overlap at all counted). 73 of the
  // 236 keys (31 %) are approached, against 108 (46 %) that overlap their next
  // gesture at all; the issue expected about 10 %. On the 163 reached keys,
  // model-filled: shape 199/199 = 1.000, placement 182/184 = 0.989, free
  // decoding 153/163 = 0.939, aligned 139/163 within 40 ms, mean 28.0 ms
  // (median shape error 2 frames, 17 ms; the mean is the tail's: 15 shape and
  // 16 placement targets more than 10 frames off).
  // Speech anchors (2026-12-03, key_timing.h: the keys' A1 from the
  // simulated phones; outlying targets and repeated keys timed at A1 + the
  // take's own lag): model-filled 35.8 -> 29.6 ms (reached keys 28.0 -> 25.8,
  // 138/163 within 40 ms), clean 35.1 -> 27.2 ms (reached 24.2), filled
  // 47.8 -> 35.2 ms.
  // Aligned floor (2026-12-04, DecodeOptions::aligned_floor 1e-6 -> 3e-3: a
  // frame's evidence against a whole key capped, so that a few confidently
  // wrong transition frames no longer pull a key off its hold): model-filled
  // 29.6 -> 27.6 ms (reached keys 25.8 -> 22.7, 140/163 within 40 ms; 221/236
  // keys on their own gesture, reached 158/163), clean 27.2 -> 25.8 (reached
  // 22.3), filled 35.2 -> 33.2.
  // A target more than 80 ms from its own A1 + lag and nearer a neighbouring
  // key's replaced too (2026-12-05, KeyTimingOptions::anchor_nearest):
  // model-filled 27.6 -> 27.4 ms (reached keys 22.7 -> 22.0; 224/236 on their
  // own gesture), clean 25.8 -> 25.8, spline/DCT-filled 33.2 -> 29.2 ms and its
  // worst key 290 -> 152 ms.
  // Fitted targets combined with A1 + lag by inverse variance (2026-12-05,
  // KeyTimingOptions::anchor_fit_sd_factor 4): model-filled 27.4 -> 27.0 ms,
  // worst key 210 -> 169 ms (226/236 on their own gesture, reached 160/163),
  // clean 25.8 -> 25.5 ms, worst 150 -> 126, spline/DCT-filled 29.2 -> 28.8
  // ms, worst 152 -> 144.
  // Shape movements fitted on the fingertips in the palm's frame instead of
  // the seven distances, fit windows at most 0.8 s back, targets kept within
  // their tolerance, the initial hold not left before the first frame
  // (2026-12-05, key_timing.h): model-filled 27.0 -> 22.1 ms (reached keys
  // 21.5 -> 18.0, 140/163 within 40 ms; on their own gesture 229/236, reached
  // 161/163), worst 169 -> 157 ms; clean 25.5 -> 20.9 ms (reached 16.1,
  // 143/163), worst 126 -> 124; spline/DCT-filled 28.8 -> 30.5 ms, worst 144
  // -> 167 (its fingertips are missing longest).
  // A fitted target beyond the speech anchors' gate kept when the hand holds
  // the key's own class there, within 0.2 s of A1 + lag (anchor_keep_in_class,
  // 2026-12-05): model-filled 22.1 -> 21.4 ms (reached 18.0 -> 17.1, 140 ->
  // 143/163 within 40 ms); clean 20.9 -> 20.0 ms (reached 15.0, 145/163);
  // spline/DCT-filled 30.5 -> 29.1 ms, worst 167 -> 131. A component's last
  // movement fitted without a made-up next gesture (2026-12-05):
  // model-filled 21.4 -> 20.3 ms (reached 17.1 -> 15.5, 145/163); clean 20.0
  // -> 18.7 ms (reached 13.1, 151/163); spline/DCT-filled 29.1 -> 26.9 ms
  // (132/163).
  // The floors below guard those numbers against regressions; the reached
  // keys' mean is held under the 25 ms.
  EXPECT_GE(model.aligned_rate, 0.825);                                                     // 198/236 = 0.839
  EXPECT_GE(static_cast<double>(model.free_reached_matches) / model.free_reached, 0.92);    // 153/163 = 0.939
  EXPECT_LE(Mean(model.aligned_error_ms), 22.0);                                            // 20.3 ms
  EXPECT_LE(Mean(model.aligned_error_reached_ms), 16.5);                                    // 15.5 ms
  EXPECT_LE(Mean(model.aligned_error_ms), Mean(model.unanchored_error_ms) - 4.0);           // 20.3 vs 26.7 ms
  EXPECT_LE(Worst(model.aligned_error_ms), 175.0);                                          // 157 ms
  EXPECT_GE(static_cast<double>(model.aligned_own_reached) / model.aligned_reached, 0.97);  // 161/163 = 0.988
  EXPECT_GE(static_cast<double>(model.aligned_own) / model.aligned_keys, 0.95);             // 229/236 = 0.970
  EXPECT_GE(model.speech_timed_repeats, 5);               // the held-out takes' 8 repeated keys
  EXPECT_GE(clean.aligned_rate, 0.84);                    // 202/236 = 0.856
  EXPECT_LE(Mean(clean.aligned_error_ms), 20.5);          // 18.7 ms
  EXPECT_LE(Mean(clean.aligned_error_reached_ms), 14.5);  // 13.1 ms
  EXPECT_LE(Worst(clean.aligned_error_ms), 140.0);        // 124 ms
  EXPECT_GE(filled.aligned_rate, 0.72);                   // 174/236 = 0.737
  EXPECT_GE(model.shape_reached.Accuracy(), 0.99);
  EXPECT_GE(model.placement_reached.Accuracy(), 0.97);
  EXPECT_GE(model.shape.Accuracy(), 0.89);
  EXPECT_GE(model.placement.Accuracy(), 0.88);
  EXPECT_GE(model.free_rate, 0.84);
  EXPECT_GE(clean.shape_reached.Accuracy(), 0.99);
  EXPECT_GE(clean.placement_reached.Accuracy(), 0.97);
  EXPECT_GE(clean.shape.Accuracy(), 0.88);
  EXPECT_GE(clean.placement.Accuracy(), 0.88);
  EXPECT_GE(clean.free_rate, 0.85);
  EXPECT_GE(filled.shape.Accuracy(), 0.72);
  EXPECT_GE(filled.placement.Accuracy(), 0.80);
  EXPECT_GE(filled.free_rate, 0.78);
  // 30.5 ms (35.2 before the aligned floor, 33.2 before anchor_nearest, 29.2
  // before the fits were combined with the speech, 28.8 before the shape fits
  // on the fingertips, 29.1 since anchor_keep_in_class, 26.9 since the last
  // movements are fitted alone)
  EXPECT_LE(Mean(filled.aligned_error_ms), 29.0);
  EXPECT_LE(Worst(filled.aligned_error_ms), 150.0);  // 131 ms (290)
}

// Another lab: the virtual cuer's second layout (other marker names and
// counts, 2-marker phalanges, a hand 8 % smaller) and every gesture 70 ms
// later relative to the speech than Attina's laws. Nothing in the recogniser
// may depend on the default layout or timing: the hand layout comes from the
// segment chains, the Gaussians and target times from the labelled takes.
TEST(VirtualCuerKeys, OtherLabLayoutAndShiftedTiming) {
  const int sentences = testing::kSanitized ? 4 : 15;
  SimulateOptions o = Defaults();
  o.layout = "lab2";
  for (MovementTiming* m : {&o.phasing.placement_cv, &o.phasing.shape_cv, &o.phasing.placement_v, &o.phasing.shape_v,
                            &o.phasing.placement_c, &o.phasing.shape_c}) {
    m->start_mean_s += 0.07;
    m->target_mean_s += 0.07;
  }
  const VirtualCuer cuer(o);
  HandLayout layout;
  Eigen::Matrix3Xd head;
  const std::vector<Scored> takes = SimulateScored(cuer, sentences, "lab2_", layout, head);
  // Known answer (datasets/hand_model.cc, the lab2 layout renames every hand
  // marker "RH_<default name>" and keeps two markers per phalanx): the same
  // fingers' proximal and tip markers under the other names.
  const std::array<std::string, 5> proximal = {"RH_T1P", "RH_I1P", "RH_M1P", "RH_R1P", "RH_L1P"};
  const std::array<std::string, 5> distal = {"RH_TTIP", "RH_ITIP", "RH_MTIP", "RH_RTIP", "RH_LTIP"};
  EXPECT_EQ(layout.proximal, proximal);
  EXPECT_EQ(layout.distal, distal);
  const Tally clean = Evaluate(takes, sentences / 3, 1, layout, head, "lab2, shifted timing, clean markers");
  const Tally filled = Evaluate(takes, sentences / 3, 0, layout, head, "lab2, shifted timing, filled takes");
  if (testing::kSanitized) {
    EXPECT_GE(clean.shape.counts(0, 0), clean.shape.counts.row(0).sum() - 1);  // rest keys
    return;
  }
  // Measured (seed 1, 15 sentences, 10 scored, 134 keys; docs/analysis.md):
  // clean markers shape 0.888 (reached 103/103; with the approached share
  // of 2026-12-03, 113/113), placement 0.828 (reached 62/62; now 95/99),
  // free 113/134 (reached keys 59/61; now 85/90), aligned 101/134 = 0.754
  // within 40 ms, mean 36.1 ms (sd 63.1; reached keys 19.2 ms; before the
  // repeated keys were interpolated: 97/134, 43.4-43.8 ms); spline/DCT-filled
  // raw takes shape 0.657, placement 0.769 (2-marker phalanges: a hidden tip
  // hides a whole finger's distance), aligned 97/134, 41.4 ms (was 46.2).
  // With the speech anchors (the lag learnt per take, so the shifted timing
  // needs nothing): clean 106/134 = 0.791, 25.8 ms (was 36.1; reached keys
  // 19.6 ms), filled 34.7 ms (was 41.4). With the aligned floor (2026-12-04):
  // clean 25.8 ms (reached keys 19.6), filled 32.1 ms (reached 28.9). With
  // anchor_nearest (2026-12-05): clean 23.5 ms (reached 16.6), filled 31.7.
  // With the fits combined with the speech (anchor_fit_sd_factor 4,
  // 2026-12-05): clean 23.7 ms (reached 16.5), filled 29.6 ms, its worst key
  // 195 -> 166 ms. With the shape fits on the fingertips in the palm frame
  // (2026-12-05): clean 23.7 -> 19.2 ms (reached 16.5 -> 11.8, 85/90 within
  // 40 ms), worst 117 -> 130; filled 29.6 -> 22.6 ms, worst 166 -> 167. The
  // anchors now gain less on clean markers (24.8 ms without them). With
  // anchor_keep_in_class (2026-12-05): clean 19.2 -> 18.0 ms (86/90), worst
  // 130 (unchanged); filled 22.6 -> 22.3 ms. Last movements fitted alone
  // (2026-12-05): clean 18.0 -> 17.2 ms (87/90), filled 22.3 -> 20.8 ms.
  ExpectReachedAccuracies(clean);
  EXPECT_GE(clean.aligned_rate, 0.86);                                             // 118/134 = 0.881
  EXPECT_LE(Mean(clean.aligned_error_ms), 19.0);                                   // 17.2 ms
  EXPECT_LE(Mean(clean.aligned_error_ms), Mean(clean.unanchored_error_ms) - 5.0);  // 17.2 vs 23.8 ms
  EXPECT_LE(Mean(filled.aligned_error_ms), 22.5);                                  // 20.8 ms
  EXPECT_LE(Worst(filled.aligned_error_ms), 185.0);                                // 167 ms
  EXPECT_GE(filled.shape.Accuracy(), 0.62);
  EXPECT_GE(filled.placement.Accuracy(), 0.72);
}

// Another lab's capture rate, another cuer's hand and speaking rate: nothing
// in the recogniser, the decoding or the key timing may count in frames of the
// virtual cuer's 120 Hz, in millimetres of its hand or on its slow speech. The same sentences
// captured at 60 and 240 Hz, with a hand 0.75 and 1.25 times the size, and
// spoken at 110 and 140 words per minute (noise, occlusions and dropouts as
// the defaults), trained on a third, scored on the rest.
TEST(VirtualCuerKeys, OtherRatesHandSizesAndSpeakingRates) {
  // Bounds per case: the mean and the worst aligned key error on clean
  // markers and on the spline/DCT-filled takes (ms).
  struct Case {
    double rate, hand_scale;
    int wpm;
    double clean_ms, filled_ms, clean_worst_ms, filled_worst_ms;
  };
  for (const Case& c :
       {Case{60.0, 1.0, 80, 25.0, 40.0, 215.0, 225.0}, Case{240.0, 1.0, 80, 21.0, 28.0, 175.0, 170.0},
        Case{120.0, 0.75, 80, 20.0, 30.0, 155.0, 215.0}, Case{120.0, 1.25, 80, 21.0, 34.0, 160.0, 190.0},
        Case{120.0, 1.0, 110, 25.0, 32.0, 140.0, 165.0}, Case{120.0, 1.0, 140, 35.0, 44.0, 160.0, 170.0}}) {
    const double rate = c.rate;
    if (testing::kSanitized && (rate > 100.0 || c.hand_scale != 1.0)) continue;  // slow under the sanitizers
    const std::string label = std::to_string(static_cast<int>(rate)) + " Hz, hand x" +
                              std::to_string(c.hand_scale).substr(0, 4) + ", " + std::to_string(c.wpm) + " wpm";
    SCOPED_TRACE(label);
    const int sentences = testing::kSanitized ? 4 : 15;
    SimulateOptions o = Defaults();
    o.rate_hz = rate;
    o.hand_scale = c.hand_scale;
    o.speech_rate_wpm = c.wpm;
    const VirtualCuer cuer(o);
    HandLayout layout;
    Eigen::Matrix3Xd head;
    const std::vector<Scored> takes =
        SimulateScored(cuer, sentences, "r" + std::to_string(static_cast<int>(rate)) + "_", layout, head);
    ASSERT_EQ(takes[0].r.take.rate_hz, rate);
    const Tally clean = Evaluate(takes, sentences / 3, 1, layout, head, label + ", clean markers");
    const Tally filled = Evaluate(takes, sentences / 3, 0, layout, head, label + ", filled takes");
    if (testing::kSanitized) {
      EXPECT_GE(clean.shape.counts(0, 0), clean.shape.counts.row(0).sum() - 1);  // rest keys
      continue;
    }
    // Measured (seed 1, 15 sentences, 10 scored, 134 keys, 2026-12-05), mean
    // aligned key error (reached keys within 40 ms): 60 Hz clean 22.5 ms
    // (81/88), filled 36.4 ms (66/88); 240 Hz clean 17.6 ms (89/92), filled
    // 23.9 ms (80/92); the same sentences at 120 Hz: clean 16.9 ms (91/97),
    // filled 27.3 ms (81/97). The simulated timing differs a little with the
    // rate (46, 37 and 42 keys approached), and the dropouts are drawn in
    // frames (1-6), so at 60 Hz the gaps last twice as long as at 120 Hz:
    // the filled takes lose most there. A hand 0.75 times the size: clean
    // 16.8 ms (90/97), filled 24.1 ms (85/97); 1.25 times: clean 18.1 ms
    // (90/97), filled 28.7 ms (81/97); 60 Hz filled now 36.6 ms (below). A
    // faster cuer (espeak-ng at 110 and 140 words per minute instead of 80):
    // clean 22.1 ms (75/80 reached keys; 54 of 134 approached), filled 28.6
    // ms; 140 wpm clean 31.6 ms (57/62; 72 approached), filled 39.9 ms. The
    // means grow with the approached keys; the reached keys' bars hold.
    ExpectReachedAccuracies(clean);
    const auto within_40 = std::count_if(clean.aligned_error_reached_ms.begin(), clean.aligned_error_reached_ms.end(),
                                         [](double e) { return e <= 40.0; });
    EXPECT_GE(static_cast<double>(within_40) / static_cast<double>(clean.aligned_error_reached_ms.size()), 0.88);
    EXPECT_LE(Mean(clean.aligned_error_ms), c.clean_ms);
    EXPECT_LE(Mean(filled.aligned_error_ms), c.filled_ms);
    // Worst keys (2026-12-05): 60 Hz clean 190 / filled 201 ms, 240 Hz 155 /
    // 148, hand x0.75 136 / 190, x1.25 139 / 168, 110 wpm 118 / 144, 140 wpm
    // 137 / 145. The filled takes' worst
    // were 273 and 257 ms until a fit on the final return to rest counted as
    // nearer a neighbour (AnchorToSpeech; the filled means 25.0 -> 24.1 and
    // 29.4 -> 28.7 ms).
    EXPECT_LE(Worst(clean.aligned_error_ms), c.clean_worst_ms);
    EXPECT_LE(Worst(filled.aligned_error_ms), c.filled_worst_ms);
  }
}

}  // namespace
}  // namespace csw::keys
