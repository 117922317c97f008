#include "datasets/virtual_cuer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "core/build_paths.h"
#include "core/error.h"
#include "core/markerset.h"
#include "io/c3d/c3d.h"
#include "io/formats/textgrid.h"
#include "io/formats/wav.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

namespace fs = std::filesystem;
constexpr double kDeg = M_PI / 180.0;

std::string ReadBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

Utterance PhonesOnly(const std::string& text) {
  PhonetiseOptions po;
  po.synthesize_audio = false;
  po.rate_wpm = SimulateOptions().speech_rate_wpm;
  return Phonetise(text, po);
}

const std::vector<std::string>& Sentences() {
  static const std::vector<std::string> s = ShippedSentences();
  return s;
}

const SimulationResult& DefaultSentence() {
  static const SimulationResult r = [] {
    VirtualCuer cuer{SimulateOptions()};
    return cuer.SimulateSentence("sentence_test", Sentences().at(0));
  }();
  return r;
}

const SimulationResult& ShapesTake() {
  static const SimulationResult r = [] {
    VirtualCuer cuer{SimulateOptions()};
    return cuer.SimulateShapes("shapes_test", AllShapeTransitions());
  }();
  return r;
}

Eigen::Isometry3d FromPose(const Eigen::MatrixXd& m, int64_t row) {
  Eigen::Isometry3d x = Eigen::Isometry3d::Identity();
  Eigen::Vector3d r = m.block<1, 3>(row, 0).transpose();
  if (r.norm() > 0) x.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix();
  x.translation() = m.block<1, 3>(row, 3).transpose();
  return x;
}

// The head frame at a frame of a take (reference pose times head motion).
Eigen::Isometry3d HeadAt(const SimulationResult& r, int64_t f) {
  HeadMotion m;
  m.rotation = r.head_motion.block<1, 3>(f, 0).transpose();
  m.translation = r.head_motion.block<1, 3>(f, 3).transpose();
  return r.head_reference * m.Weighted(1.0);
}

int64_t FrameAt(const SimulationResult& r, double t) {
  return std::clamp<int64_t>(std::llround(t * r.take.rate_hz), 0, r.frames() - 1);
}

TEST(VirtualCuer, OptionsAreChecked) {
  SimulateOptions o;
  EXPECT_EQ(o.Check(), "");
  o.rate_hz = 0;
  EXPECT_NE(o.Check(), "");
  o = SimulateOptions();
  o.min_cameras = 9;
  EXPECT_NE(o.Check(), "");
  EXPECT_THROW(VirtualCuer{o}, InvalidInput);
  o = SimulateOptions();
  o.phasing.placement_cv.start_sd_s = -1;
  EXPECT_NE(o.Check(), "");
  CorpusKind k;
  EXPECT_TRUE(ParseCorpusKind("visemes", &k));
  EXPECT_EQ(k, CorpusKind::kVisemes);
  EXPECT_FALSE(ParseCorpusKind("words", &k));
}

TEST(VirtualCuer, MarkerSetDescribesEverySimulatedMarker) {
  VirtualCuer cuer{SimulateOptions()};
  MarkerSet set = ParseMarkerSet(MarkerSetToJson(cuer.MakeMarkerSet()), "markerset.json");
  EXPECT_EQ(set.AllMarkers().size(), 113u);
  EXPECT_EQ(set.throat.size(), 18u);
  EXPECT_EQ(set.hand_segments.size(), 16u);
  // Every corpus kind's set keeps each marker in one role (ParseMarkerSet refuses overlaps): the
  // shapes corpus has the head cluster + 7 forearm + 8 palm + 35 finger markers, the visemes corpus no hand.
  EXPECT_EQ(ParseMarkerSet(MarkerSetToJson(cuer.MakeMarkerSet(CorpusKind::kShapes)), "shapes.json").AllMarkers().size(),
            set.head_cluster.size() + 50u);
  EXPECT_TRUE(
      ParseMarkerSet(MarkerSetToJson(cuer.MakeMarkerSet(CorpusKind::kVisemes)), "visemes.json").hand_segments.empty());
  const SimulationResult& r = DefaultSentence();
  MarkerBinding b = BindMarkerSet(set, r.take.marker_names, true, r.take.name);
  EXPECT_TRUE(b.missing.empty());
  const auto itip = std::find(r.take.marker_names.begin(), r.take.marker_names.end(), "ITIP");
  ASSERT_NE(itip, r.take.marker_names.end());
  EXPECT_EQ(b.At("ITIP"), static_cast<int>(itip - r.take.marker_names.begin()));
}

TEST(VirtualCuer, AllShapeTransitionsVisitsEveryOrderedPairOnce) {
  std::vector<int> s = AllShapeTransitions();
  ASSERT_EQ(s.size(), 57u);
  std::map<std::pair<int, int>, int> seen;
  for (size_t i = 1; i < s.size(); ++i) ++seen[{s[i - 1], s[i]}];
  EXPECT_EQ(seen.size(), 56u);
  for (const auto& [pair, n] : seen) {
    EXPECT_NE(pair.first, pair.second);
    EXPECT_EQ(n, 1);
  }
}

TEST(VirtualCuer, ShippedSentencesCoverEverySuccessionOfPlacementsAndShapes) {
  ASSERT_GE(Sentences().size(), 40u);
  std::set<std::pair<int, int>> placements, shapes;
  for (const std::string& s : Sentences()) {
    std::vector<Key> keys = CueKeys(PhonesOnly(s).phones);
    for (size_t k = 2; k + 1 < keys.size(); ++k) {
      placements.insert({keys[k - 1].placement, keys[k].placement});
      shapes.insert({keys[k - 1].shape, keys[k].shape});
    }
  }
  for (int a = 1; a <= 5; ++a)
    for (int b = 1; b <= 5; ++b) EXPECT_TRUE(placements.count({a, b})) << "placement " << a << " -> " << b;
  for (int a = 1; a <= 8; ++a)
    for (int b = 1; b <= 8; ++b) EXPECT_TRUE(shapes.count({a, b})) << "shape " << a << " -> " << b;
}

TEST(VirtualCuer, PhoneTimesMatchTheAudioLength) {
  const SimulationResult& r = DefaultSentence();
  ASSERT_FALSE(r.take.audio.samples.empty());
  const SimulateOptions o;
  // espeak-ng's phones end where its audio ends; the capture pads lead_in_s of silence before.
  EXPECT_NEAR(r.utterance.phones.back().end_s, r.take.audio.duration_s(), 1.0 / r.take.audio.rate_hz + 1e-9);
  EXPECT_NEAR(r.utterance.phones.front().start_s, o.lead_in_s, 1e-9);
  testing::TempDir dir;
  WriteTakeFiles(r, o, dir.path().string());
  Audio wav = ReadWav((dir / "sentence_test.wav").string());
  EXPECT_EQ(wav.frames(), r.take.audio.frames());
  EXPECT_NEAR(wav.duration_s(), r.utterance.phones.back().end_s, 1.0 / wav.rate_hz + 1e-9);
}

// Realism: the key timings drawn for 100 sentences reproduce the configured
// phasing means within 10 ms (keys only, no audio).
TEST(VirtualCuer, KeyTimingsReproduceThePhasingMeansOver100Sentences) {
  VirtualCuer cuer{SimulateOptions()};
  const PhasingModel& m = cuer.options().phasing;
  std::vector<std::vector<Key>> keys;
  for (const auto& s : Sentences()) keys.push_back(CueKeys(PhonesOnly(s).phones));
  struct Acc {
    double sum = 0;
    int n = 0;
    void Add(double v) {
      sum += v;
      ++n;
    }
    double Mean() const { return sum / n; }
  };
  Acc pcv_start, pcv_target, pv_start, pv_target, scv_start, scv_target;
  for (int i = 0; i < 100; ++i) {
    std::mt19937_64 rng(1000 + i);
    const std::vector<Key>& k = keys[static_cast<size_t>(i) % keys.size()];
    std::vector<KeyTiming> t = cuer.DrawTiming(k, rng);
    ASSERT_EQ(t.size(), k.size());
    for (size_t j = 1; j < k.size(); ++j) {
      const double a1 = k[j].a1_s;
      if (k[j].type == KeyType::kCV) {
        pcv_start.Add(t[j].placement_start_s - a1);
        pcv_target.Add(t[j].placement_target_s - a1);
        if (k[j].shape != k[j - 1].shape && k[j].placement != k[j - 1].placement) {
          scv_start.Add(t[j].shape_start_s - a1);
          scv_target.Add(t[j].shape_target_s - a1);
        }
      } else if (k[j].type == KeyType::kVowelAlone) {
        pv_start.Add(t[j].placement_start_s - a1);
        pv_target.Add(t[j].placement_target_s - a1);
      }
    }
  }
  ASSERT_GT(pcv_start.n, 300);
  ASSERT_GT(pv_start.n, 30);
  ASSERT_GT(scv_start.n, 200);
  EXPECT_NEAR(pcv_start.Mean(), m.placement_cv.start_mean_s, 0.010);
  EXPECT_NEAR(pcv_target.Mean(), m.placement_cv.target_mean_s, 0.010);
  EXPECT_NEAR(pv_start.Mean(), m.placement_v.start_mean_s, 0.010);
  EXPECT_NEAR(pv_target.Mean(), m.placement_v.target_mean_s, 0.010);
  EXPECT_NEAR(scv_start.Mean(), m.shape_cv.start_mean_s, 0.010);
  EXPECT_NEAR(scv_target.Mean(), m.shape_cv.target_mean_s, 0.010);
  RecordProperty("cv_keys", pcv_start.n);
  RecordProperty("placement_cv_start_ms", std::to_string(pcv_start.Mean() * 1e3));
  RecordProperty("placement_cv_target_ms", std::to_string(pcv_target.Mean() * 1e3));
}

// Every key's posture and placement are reached at its target time when the
// next movements have not started yet (no-overlap timing); with the default
// overlapping gestures the hand passes close to each target.
TEST(VirtualCuer, KeysReachTheirPostureAndPlacementAtTheirTargetTimes) {
  for (bool overlap : {false, true}) {
    SimulateOptions o;
    o.overlap_gestures = overlap;
    o.occlusions = false;
    VirtualCuer cuer(o);
    std::vector<double> angle_err, tip_err;
    int checked = 0, keys_total = 0;
    for (int s = 0; s < 6; ++s) {
      SimulationResult r =
          cuer.SimulateUtterance("reach_" + std::to_string(s), PhonesOnly(Sentences().at(static_cast<size_t>(s))));
      for (size_t k = 1; k + 1 < r.keys.size(); ++k) {
        ++keys_total;
        const GestureTruth& g = r.keys[k];
        const double t = std::max(g.timing.shape_target_s, g.timing.placement_target_s);
        const KeyTiming& next = r.keys[k + 1].timing;
        if (!overlap && std::min(next.shape_start_s, next.placement_start_s) < t) continue;
        const int64_t f = FrameAt(r, t);  // both movements have reached their targets at t
        const HandPosture& posture = cuer.hand().config().Posture(g.key.shape);
        Eigen::VectorXd q = r.joint_angles.row(f).transpose();
        angle_err.push_back((q - g.posture).cwiseAbs().maxCoeff());
        Eigen::Vector3d tip = cuer.hand().TipInForearm(
            q, posture.reference_finger == "index" ? VirtualHand::kIndex : VirtualHand::kMiddle);
        Eigen::Vector3d in_head = HeadAt(r, f).inverse() * (FromPose(r.forearm_pose, f) * tip);
        tip_err.push_back((in_head - g.placement_point).norm());
        // The key's own target is the configured one up to the per-key variability (2.5 sd).
        EXPECT_LE((g.posture - posture.angles).cwiseAbs().maxCoeff(), 2.5 * o.posture_sd_deg * kDeg + 1e-9);
        EXPECT_LE((g.placement_point - PlacementTarget(cuer.placements().At(g.key.placement), cuer.face()))
                      .cwiseAbs()
                      .maxCoeff(),
                  2.5 * o.placement_sd_mm + 1e-9);
        ++checked;
      }
    }
    ASSERT_GT(checked, overlap ? 40 : 15);
    std::sort(angle_err.begin(), angle_err.end());
    std::sort(tip_err.begin(), tip_err.end());
    const double a_med = angle_err[angle_err.size() / 2] / kDeg, t_med = tip_err[tip_err.size() / 2];
    const double a_max = angle_err.back() / kDeg, t_max = tip_err.back();
    if (!overlap) {
      EXPECT_LT(a_max, 0.5) << "degrees";
      EXPECT_LT(t_max, 1.0) << "mm";
    } else {
      // Blending with the neighbouring gestures: most keys still land close to their targets.
      EXPECT_LT(a_med, 2.0) << "degrees";
      EXPECT_LT(t_med, 3.0) << "mm";
    }
    const std::string tag = overlap ? "overlap_" : "no_overlap_";
    RecordProperty(tag + "keys_checked", std::to_string(checked) + "/" + std::to_string(keys_total));
    RecordProperty(tag + "posture_error_deg_median_max", std::to_string(a_med) + " " + std::to_string(a_max));
    RecordProperty(tag + "placement_error_mm_median_max", std::to_string(t_med) + " " + std::to_string(t_max));
    RecordProperty(tag + "placement_error_mm_p90", std::to_string(tip_err[tip_err.size() * 9 / 10]));
  }
}

// Count of local maxima higher than 5 % of the profile's peak, separated by a dip of 5 %.
int CountPeaks(const std::vector<double>& v) {
  double peak = *std::max_element(v.begin(), v.end());
  int peaks = 0;
  bool rising = true;
  double last_max = 0, last_min = 0;
  for (size_t i = 1; i + 1 < v.size(); ++i) {
    if (rising && v[i] > v[i + 1] && v[i] >= v[i - 1] && v[i] > 0.05 * peak && v[i] - last_min > 0.05 * peak) {
      ++peaks;
      rising = false;
      last_max = v[i];
      last_min = v[i];
    } else if (!rising) {
      last_min = std::min(last_min, v[i]);
      if (v[i] - last_min > 0.05 * peak) rising = true;
    }
  }
  (void)last_max;
  return peaks;
}

// Realism: between two hand-shape targets in free space every fingertip that
// moves has a single-peaked speed profile (in the forearm frame, clean data).
TEST(VirtualCuer, FingertipSpeedBetweenKeysIsSinglePeaked) {
  const SimulationResult& r = ShapesTake();
  VirtualCuer cuer{SimulateOptions()};
  std::vector<int> tips;
  for (const auto& n : cuer.hand().fingertip_markers())
    tips.push_back(static_cast<int>(std::find(r.take.marker_names.begin(), r.take.marker_names.end(), n) -
                                    r.take.marker_names.begin()));
  int profiles = 0;
  for (size_t k = 2; k + 1 < r.keys.size(); ++k) {
    const int64_t f0 = FrameAt(r, r.keys[k - 1].timing.shape_target_s);
    const int64_t f1 = FrameAt(r, r.keys[k].timing.shape_target_s);
    for (int col : tips) {
      std::vector<double> speed;
      double travel = 0;
      Eigen::Vector3d prev = Eigen::Vector3d::Zero();
      for (int64_t f = f0; f <= f1; ++f) {
        const float* p = r.clean.at(f, col);
        Eigen::Vector3d x = FromPose(r.forearm_pose, f).inverse() * Eigen::Vector3d(p[0], p[1], p[2]);
        if (f > f0) {
          speed.push_back((x - prev).norm() * r.take.rate_hz);
          travel += (x - prev).norm();
        }
        prev = x;
      }
      if (travel < 5.0) continue;
      ++profiles;
      EXPECT_EQ(CountPeaks(speed), 1) << "key " << k << " (" << r.keys[k - 1].key.shape << " -> " << r.keys[k].key.shape
                                      << ") marker " << r.take.marker_names[static_cast<size_t>(col)];
    }
  }
  EXPECT_GT(profiles, 100);
  RecordProperty("speed_profiles", profiles);
}

TEST(VirtualCuer, PhalanxMarkerDistancesInASimulatedTakeVaryLessThanTwoMillimetres) {
  const SimulationResult& r = ShapesTake();
  VirtualCuer cuer{SimulateOptions()};
  auto col = [&](const std::string& n) {
    return std::find(r.take.marker_names.begin(), r.take.marker_names.end(), n) - r.take.marker_names.begin();
  };
  for (const auto& seg : cuer.hand().segments()) {
    if (seg.name == "palm") continue;
    const auto a = col(seg.markers[0]), b = col(seg.markers[1]);
    double lo = 1e9, hi = 0;
    for (int64_t f = 0; f < r.frames(); ++f) {
      const float* p = r.clean.at(f, a);
      const float* q = r.clean.at(f, b);
      double d = std::sqrt(std::pow(p[0] - q[0], 2) + std::pow(p[1] - q[1], 2) + std::pow(p[2] - q[2], 2));
      lo = std::min(lo, d);
      hi = std::max(hi, d);
    }
    EXPECT_LT(hi - lo, 2.0) << seg.name;
  }
}

// The hand is a smooth function of its joint angles: in the forearm frame, a
// linear regression of the 50 markers on [1, cos q, sin q] (the seed's hand model
// without its PCA step) learnt on the shapes take and four sentences fits them
// within the seed's 2 mm mean error (the seed's figure is on its training
// utterances), and predicts an unseen sentence within 3 mm.
TEST(VirtualCuer, HandMarkersAreReachableByARegressionOnCosAndSinOfTheAngles) {
  const SimulationResult& r = ShapesTake();
  const int nj = static_cast<int>(r.joint_angles.cols());
  const int nh = static_cast<int>(r.hand_columns.size());
  ASSERT_EQ(nh, 50);
  auto design = [&](const SimulationResult& t, Eigen::MatrixXd* xs, Eigen::MatrixXd* ys) {
    const Eigen::Index frames = t.frames();
    xs->resize(frames, 1 + 2 * nj);
    ys->resize(frames, 3 * nh);
    for (Eigen::Index f = 0; f < frames; ++f) {
      (*xs)(f, 0) = 1.0;
      for (int j = 0; j < nj; ++j) {
        (*xs)(f, 1 + j) = std::cos(t.joint_angles(f, j));
        (*xs)(f, 1 + nj + j) = std::sin(t.joint_angles(f, j));
      }
      const Eigen::Isometry3d lab_to_forearm = FromPose(t.forearm_pose, f).inverse();
      for (int m = 0; m < nh; ++m) {
        const float* p = t.clean.at(f, t.hand_columns[static_cast<size_t>(m)]);
        ys->block<1, 3>(f, 3 * m) = (lab_to_forearm * Eigen::Vector3d(p[0], p[1], p[2])).transpose();
      }
    }
  };
  Eigen::MatrixXd x, y;
  design(r, &x, &y);
  auto mean_error = [&](const Eigen::MatrixXd& res) {
    double sum = 0;
    for (Eigen::Index f = 0; f < res.rows(); ++f)
      for (int m = 0; m < nh; ++m) sum += res.block<1, 3>(f, 3 * m).norm();
    return sum / static_cast<double>(res.rows() * nh);
  };
  // Training data: the shapes take and four cued sentences (as the seed trained on corpus 3 too).
  {
    VirtualCuer cuer{SimulateOptions()};
    for (int s = 1; s <= 4; ++s) {
      SimulationResult t =
          cuer.SimulateUtterance("train_" + std::to_string(s), PhonesOnly(Sentences().at(static_cast<size_t>(s))));
      Eigen::MatrixXd xs, ys;
      design(t, &xs, &ys);
      Eigen::MatrixXd x2(x.rows() + xs.rows(), x.cols()), y2(y.rows() + ys.rows(), y.cols());
      x2 << x, xs;
      y2 << y, ys;
      x = std::move(x2);
      y = std::move(y2);
    }
  }
  Eigen::MatrixXd coef = x.colPivHouseholderQr().solve(y);
  const double train_mm = mean_error(x * coef - y);
  Eigen::MatrixXd xt, yt;
  design(DefaultSentence(), &xt, &yt);
  const double test_mm = mean_error(xt * coef - yt);
  EXPECT_LT(train_mm, 2.0);
  EXPECT_LT(test_mm, 3.0);
  RecordProperty("hand_regression_train_mean_error_mm", std::to_string(train_mm));
  RecordProperty("hand_regression_sentence_mean_error_mm", std::to_string(test_mm));
}

TEST(VirtualCuer, CaptureArtefactsFollowTheMaskAndTheNoiseLevel) {
  const SimulationResult& r = DefaultSentence();
  const int64_t nm = r.take.markers.markers();
  double sum = 0, sum2 = 0;
  int64_t n = 0, occluded_face = 0, occluded_hand = 0, dropped = 0;
  for (int64_t f = 0; f < r.frames(); ++f)
    for (int64_t m = 0; m < nm; ++m) {
      const uint8_t s = r.state[static_cast<size_t>(f * nm + m)];
      ASSERT_EQ(r.take.markers.Visible(f, m), s == kVisible);
      ASSERT_TRUE(r.clean.Visible(f, m));
      if (s == kOccluded) (m < 63 ? occluded_face : occluded_hand)++;
      if (s == kDropped) ++dropped;
      if (s != kVisible) continue;
      for (int c = 0; c < 3; ++c) {
        double e = r.take.markers.at(f, m)[c] - r.clean.at(f, m)[c];
        sum += e;
        sum2 += e * e;
        ++n;
      }
    }
  const double sd = std::sqrt(sum2 / n);
  EXPECT_NEAR(sum / n, 0.0, 0.01);
  EXPECT_NEAR(sd, SimulateOptions().noise_mm, 0.02);
  EXPECT_GT(occluded_face, 0) << "the hand never hides a face marker";
  EXPECT_GT(occluded_hand, 0) << "no hand marker is ever hidden";
  EXPECT_GT(dropped, 0);
  RecordProperty("occluded_face_samples", static_cast<int>(occluded_face));
  RecordProperty("occluded_hand_samples", static_cast<int>(occluded_hand));
  RecordProperty("noise_sd_mm", std::to_string(sd));
  // Without a hand (visemes) the lips face the cameras and are never occluded.
  SimulateOptions o;
  o.dropouts_per_s = 0;
  VirtualCuer cuer(o);
  SimulationResult v = cuer.SimulateUtterance("viseme_test", PhonesOnly("aba, ibi, oubou."), false);
  ASSERT_EQ(v.take.markers.markers(), 63);
  EXPECT_TRUE(v.hand_columns.empty());
  for (const char* lip : {"ULM", "LLM", "LCL", "LCR", "CHIN"}) {
    int m = cuer.face().MarkerIndex(lip);
    for (int64_t f = 0; f < v.frames(); ++f) ASSERT_TRUE(v.take.markers.Visible(f, m)) << lip << " frame " << f;
  }
}

TEST(VirtualCuer, LabelSwapsExchangeTwoColumnsForAWhile) {
  SimulateOptions o;
  o.label_swaps = true;
  o.noise_mm = 0;
  o.occlusions = false;
  o.dropouts_per_s = 0;
  VirtualCuer cuer(o);
  SimulationResult r = cuer.SimulateUtterance("swap_test", PhonesOnly(Sentences().at(1)));
  ASSERT_EQ(r.swaps.size(), 1u);
  const LabelSwap& s = r.swaps[0];
  ASSERT_LT(s.first_frame, s.end_frame);
  for (int64_t f = 0; f < r.frames(); ++f) {
    const bool in = f >= s.first_frame && f < s.end_frame;
    EXPECT_EQ(r.take.markers.at(f, s.marker_a)[0], r.clean.at(f, in ? s.marker_b : s.marker_a)[0]);
  }
}

TEST(VirtualCuer, FilesReadBackWithTheValuesWritten) {
  const SimulationResult& r = DefaultSentence();
  testing::TempDir dir;
  SimulateOptions o;
  o.write_clean = true;
  WriteTakeFiles(r, o, dir.path().string());
  Take back = ReadC3d((dir / "sentence_test.c3d").string());
  ASSERT_EQ(back.marker_names, r.take.marker_names);
  ASSERT_EQ(back.frames(), r.frames());
  EXPECT_DOUBLE_EQ(back.rate_hz, 120.0);
  for (int64_t f = 0; f < r.frames(); ++f)
    for (int64_t m = 0; m < r.take.markers.markers(); ++m) {
      ASSERT_EQ(back.markers.Visible(f, m), r.take.markers.Visible(f, m));
      if (!back.markers.Visible(f, m)) continue;
      for (int c = 0; c < 3; ++c) ASSERT_EQ(back.markers.at(f, m)[c], r.take.markers.at(f, m)[c]);
    }
  Take clean = ReadC3d((dir / "sentence_test.clean.c3d").string());
  EXPECT_EQ(clean.markers.CountVisible(), r.frames() * r.take.markers.markers());
  std::vector<LabelTier> tiers = ReadTextGrid((dir / "sentence_test.TextGrid").string());
  std::vector<std::string> names;
  for (const auto& t : tiers) names.push_back(t.name);
  EXPECT_EQ(names, (std::vector<std::string>{"words", "phones", "keys", "placement_targets", "shape_gestures",
                                             "placement_gestures"}));
  ASSERT_EQ(tiers[2].labels.size(), r.keys.size());
  for (size_t k = 0; k < r.keys.size(); ++k) {
    EXPECT_EQ(tiers[2].labels[k].text, r.keys[k].key.Code());
    EXPECT_GE(tiers[2].labels[k].start_s, r.keys[k].timing.shape_target_s);
    EXPECT_LT(tiers[2].labels[k].start_s, r.keys[k].timing.shape_target_s + 0.01);
  }
  // Ground truth JSON parses and holds the key times.
  const std::string truth = ReadBytes(dir / "sentence_test.truth.json");
  EXPECT_NE(truth.find("\"format\":\"csw-virtual-truth\""), std::string::npos);
  EXPECT_NE(truth.find("\"joint_angles\""), std::string::npos);
}

// The TextGrids open in Praat itself: Debian's praat reads each one and lists its
// tiers with their sizes, which match csw's own reader.
TEST(VirtualCuer, TextGridsOpenInPraat) {
  if (std::system("praat --version > /dev/null 2>&1") != 0) GTEST_SKIP() << "praat is not installed";
  testing::TempDir dir;
  const fs::path script = dir / "tiers.praat";
  {
    std::ofstream out(script);
    out << "form Read\n  sentence path x\nendform\n"
           "Read from file: path$\nn = Get number of tiers\n"
           "for i to n\n  name$ = Get tier name: i\n"
           "  if do (\"Is interval tier...\", i)\n    k = Get number of intervals: i\n"
           "  else\n    k = Get number of points: i\n  endif\n"
           "  appendInfoLine: name$, \" \", k\nendfor\n";
  }
  SimulateOptions o;
  WriteTakeFiles(DefaultSentence(), o, dir.path().string());
  WriteTakeFiles(ShapesTake(), o, dir.path().string());
  for (const char* take : {"sentence_test", "shapes_test"}) {
    const fs::path tg = dir / (std::string(take) + ".TextGrid");
    const fs::path out = dir / (std::string(take) + ".txt");
    const std::string cmd =
        "praat --run \"" + script.string() + "\" \"" + tg.string() + "\" > \"" + out.string() + "\" 2>&1";
    ASSERT_EQ(std::system(cmd.c_str()), 0) << ReadBytes(out);
    std::string expected;
    for (const LabelTier& t : ReadTextGrid(tg.string()))
      expected += t.name + " " + std::to_string(t.labels.size()) + "\n";
    std::string got;
    std::istringstream lines(ReadBytes(out));
    for (std::string line; std::getline(lines, line);)
      if (!line.empty()) got += line + "\n";
    EXPECT_EQ(got, expected) << take;
  }
}

// Determinism: the same command and seed, run twice in fresh processes, writes
// byte-identical files; another seed writes different ones. (espeak-ng carries
// state from one utterance to the next inside a process, so a corpus is
// reproducible as a whole, run by one command.)
TEST(VirtualCuer, SameSeedGivesByteIdenticalFiles) {
  testing::TempDir a, b, c;
  auto run = [](const fs::path& dir, int seed) {
    std::string cmd = std::string("\"") + CSW_BINARY + "\" -q simulate sentences -o \"" + dir.string() +
                      "\" --count 2 --seed " + std::to_string(seed) + " >/dev/null 2>&1";
    return std::system(cmd.c_str());
  };
  ASSERT_EQ(run(a.path(), 5), 0);
  ASSERT_EQ(run(b.path(), 5), 0);
  ASSERT_EQ(run(c.path(), 6), 0);
  for (const char* take : {"sentence_001", "sentence_002"})
    for (const char* ext : {".c3d", ".TextGrid", ".wav", ".truth.json"}) {
      const std::string name = std::string(take) + ext;
      const std::string fa = ReadBytes(a / name);
      ASSERT_FALSE(fa.empty()) << name;
      EXPECT_TRUE(fa == ReadBytes(b / name)) << name << " differs between two runs";
    }
  EXPECT_TRUE(ReadBytes(a / "markerset.json") == ReadBytes(b / "markerset.json"));
  EXPECT_TRUE(ReadBytes(a / "sentence_001.c3d") != ReadBytes(c / "sentence_001.c3d"));
  EXPECT_TRUE(ReadBytes(a / "sentence_001.TextGrid") != ReadBytes(c / "sentence_001.TextGrid"));
  // The files describe the same take as an in-process simulation would: same markers and frame rate.
  Take t = ReadC3d((a / "sentence_001.c3d").string());
  EXPECT_EQ(t.marker_names.size(), 113u);
  EXPECT_DOUBLE_EQ(t.rate_hz, 120.0);
}

}  // namespace
}  // namespace csw
