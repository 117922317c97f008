// Phasing model: defaults from Attina (2005), JSON round trip, and the sampled
// timings reproducing the configured means.
#include "synth/phasing.h"

#include <gtest/gtest.h>

#include <fstream>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "core/error.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

// n keys of one type, A1 every `spacing_s` seconds, each syllable 0.25 s long,
// with rest keys first and last (as CueKeys returns them).
std::vector<Key> SyntheticKeys(int n, KeyType type, double spacing_s) {
  std::vector<Key> keys;
  Key rest;
  keys.push_back(rest);
  for (int i = 0; i < n; ++i) {
    Key k;
    k.type = type;
    k.placement = 3;
    k.shape = 2;
    k.a1_s = 0.5 + i * spacing_s;
    k.end_s = k.a1_s + 0.25;
    keys.push_back(k);
  }
  rest.a1_s = keys.back().end_s;
  rest.end_s = rest.a1_s + 0.5;
  keys.push_back(rest);
  return keys;
}

struct Means {
  double placement_start = 0, placement_target = 0, shape_start = 0, shape_target = 0;
};

Means RelativeMeans(const std::vector<Key>& keys, const std::vector<KeyTiming>& t) {
  Means m;
  int n = 0;
  for (size_t i = 0; i < keys.size(); ++i) {
    if (keys[i].type == KeyType::kRest) continue;
    m.placement_start += t[i].placement_start_s - keys[i].a1_s;
    m.placement_target += t[i].placement_target_s - keys[i].a1_s;
    m.shape_start += t[i].shape_start_s - keys[i].a1_s;
    m.shape_target += t[i].shape_target_s - keys[i].a1_s;
    ++n;
  }
  m.placement_start /= n;
  m.placement_target /= n;
  m.shape_start /= n;
  m.shape_target /= n;
  return m;
}

TEST(Phasing, DefaultsAreAttinasMeans) {
  const PhasingModel m;
  EXPECT_EQ(m.Check(), "");
  EXPECT_DOUBLE_EQ(m.placement_cv.start_mean_s, -0.239);
  EXPECT_DOUBLE_EQ(m.placement_cv.start_sd_s, 0.087);
  EXPECT_DOUBLE_EQ(m.placement_cv.target_mean_s, 0.037);
  EXPECT_DOUBLE_EQ(m.placement_cv.target_sd_s, 0.076);
  EXPECT_DOUBLE_EQ(m.placement_v.start_mean_s, -0.183);
  EXPECT_DOUBLE_EQ(m.placement_v.start_sd_s, 0.079);
  EXPECT_DOUBLE_EQ(m.placement_v.target_mean_s, 0.084);
  EXPECT_DOUBLE_EQ(m.placement_v.target_sd_s, 0.064);
  EXPECT_DOUBLE_EQ(m.shape_cv.start_mean_s, -0.171);
  EXPECT_DOUBLE_EQ(m.shape_cv.start_sd_s, 0.048);
  EXPECT_DOUBLE_EQ(m.shape_cv.target_mean_s, -0.003);
  EXPECT_DOUBLE_EQ(m.shape_cv.target_sd_s, 0.045);
}

TEST(Phasing, SampleMeansMatchConfiguredMeans) {
  const PhasingModel model;
  for (KeyType type : {KeyType::kCV, KeyType::kVowelAlone, KeyType::kConsonantAlone}) {
    const std::vector<Key> keys = SyntheticKeys(5000, type, 1.0);
    std::mt19937_64 rng(20260101);
    const std::vector<KeyTiming> t = SampleTiming(keys, model, rng);
    ASSERT_EQ(t.size(), keys.size());
    const Means m = RelativeMeans(keys, t);
    const MovementTiming& p = PlacementTiming(model, type);
    const MovementTiming& s = ShapeTiming(model, type);
    EXPECT_NEAR(m.placement_start, p.start_mean_s, 0.005) << static_cast<int>(type);
    EXPECT_NEAR(m.placement_target, p.target_mean_s, 0.005) << static_cast<int>(type);
    EXPECT_NEAR(m.shape_start, s.start_mean_s, 0.005) << static_cast<int>(type);
    EXPECT_NEAR(m.shape_target, s.target_mean_s, 0.005) << static_cast<int>(type);
  }
}

TEST(Phasing, SampleSpreadMatchesConfiguredSd) {
  const PhasingModel model;
  const std::vector<Key> keys = SyntheticKeys(5000, KeyType::kCV, 1.0);
  std::mt19937_64 rng(5);
  const std::vector<KeyTiming> t = SampleTiming(keys, model, rng);
  double sum = 0, sum2 = 0;
  int n = 0;
  for (size_t i = 1; i + 1 < keys.size(); ++i) {
    const double d = t[i].placement_start_s - keys[i].a1_s;
    sum += d;
    sum2 += d * d;
    ++n;
  }
  const double sd = std::sqrt(sum2 / n - (sum / n) * (sum / n));
  // Truncation at ±3 sd keeps 98.6 % of the spread.
  EXPECT_NEAR(sd, 0.087, 0.006);
}

TEST(Phasing, ConstraintsHoldOnFastSpeech) {
  // Syllables every 150 ms: the laws overlap, the constraints must bind.
  const PhasingModel model;
  std::vector<Key> keys = SyntheticKeys(400, KeyType::kCV, 0.15);
  for (size_t i = 1; i + 1 < keys.size(); i += 3) keys[i].type = KeyType::kVowelAlone;
  std::mt19937_64 rng(11);
  const std::vector<KeyTiming> t = SampleTiming(keys, model, rng);
  for (size_t i = 0; i < t.size(); ++i) {
    EXPECT_GE(t[i].placement_target_s - t[i].placement_start_s, i == 0 ? 0.0 : model.min_movement_s - 1e-12);
    EXPECT_GE(t[i].shape_target_s - t[i].shape_start_s, i == 0 ? 0.0 : model.min_movement_s - 1e-12);
    if (i > 0) {
      EXPECT_GE(t[i].placement_start_s, t[i - 1].placement_target_s) << i;
      EXPECT_GE(t[i].shape_start_s, t[i - 1].shape_target_s) << i;
    }
  }
  // The leading rest ends when the first movement starts.
  EXPECT_DOUBLE_EQ(t[0].placement_target_s, std::min(t[1].placement_start_s, t[1].shape_start_s));
  // The final rest follows the last key.
  EXPECT_GT(t.back().placement_target_s, keys[keys.size() - 2].end_s);
}

TEST(Phasing, CalibrationRestoresMeansAtSpeechRate) {
  // At 350 ms per key the constraints delay CV placement starts by ~16 ms; the
  // calibrated model's constrained draws give back the target means.
  const PhasingModel target;
  std::vector<Key> keys = SyntheticKeys(3000, KeyType::kCV, 0.35);
  for (size_t i = 1; i + 1 < keys.size(); i += 4) keys[i].type = KeyType::kVowelAlone;
  std::mt19937_64 rng(9);
  const PhasingMeans raw = MeasurePhasing(keys, SampleTiming(keys, target, rng));
  EXPECT_GT(raw.cv.placement.start_mean_s - target.placement_cv.start_mean_s, 0.008);

  const PhasingModel calibrated = CalibratePhasing(keys, target, 77);
  EXPECT_EQ(calibrated.Check(), "");
  EXPECT_LT(calibrated.placement_cv.start_mean_s, target.placement_cv.start_mean_s);
  std::mt19937_64 fresh(1234);  // a different seed than the calibration's
  const PhasingMeans m = MeasurePhasing(keys, SampleTiming(keys, calibrated, fresh));
  EXPECT_GT(m.cv.count, 2000);
  EXPECT_GT(m.v.count, 500);
  EXPECT_EQ(m.c.count, 0);
  EXPECT_NEAR(m.cv.placement.start_mean_s, target.placement_cv.start_mean_s, 0.005);
  EXPECT_NEAR(m.cv.placement.target_mean_s, target.placement_cv.target_mean_s, 0.005);
  EXPECT_NEAR(m.cv.shape.start_mean_s, target.shape_cv.start_mean_s, 0.005);
  EXPECT_NEAR(m.cv.shape.target_mean_s, target.shape_cv.target_mean_s, 0.005);
  EXPECT_NEAR(m.v.placement.start_mean_s, target.placement_v.start_mean_s, 0.005);
  EXPECT_NEAR(m.v.placement.target_mean_s, target.placement_v.target_mean_s, 0.005);
}

TEST(Phasing, DeterministicForASeed) {
  const PhasingModel model;
  const std::vector<Key> keys = SyntheticKeys(50, KeyType::kCV, 0.3);
  std::mt19937_64 a(42), b(42), c(43);
  const auto ta = SampleTiming(keys, model, a);
  const auto tb = SampleTiming(keys, model, b);
  const auto tc = SampleTiming(keys, model, c);
  bool differs = false;
  for (size_t i = 0; i < ta.size(); ++i) {
    EXPECT_EQ(ta[i].placement_start_s, tb[i].placement_start_s);
    EXPECT_EQ(ta[i].shape_target_s, tb[i].shape_target_s);
    differs = differs || ta[i].placement_start_s != tc[i].placement_start_s;
  }
  EXPECT_TRUE(differs);
}

TEST(Phasing, MeanTimingIsTheMeans) {
  const PhasingModel model;
  const std::vector<Key> keys = SyntheticKeys(3, KeyType::kCV, 1.0);
  const auto t = MeanTiming(keys, model);
  EXPECT_NEAR(t[1].placement_start_s - keys[1].a1_s, -0.239, 1e-12);
  EXPECT_NEAR(t[1].placement_target_s - keys[1].a1_s, 0.037, 1e-12);
  EXPECT_NEAR(t[2].shape_start_s - keys[2].a1_s, -0.171, 1e-12);
  EXPECT_NEAR(t[2].shape_target_s - keys[2].a1_s, -0.003, 1e-12);
  EXPECT_NEAR(t[0].placement_start_s, keys[1].a1_s - 0.239, 1e-12);
  EXPECT_NEAR(t[4].placement_start_s, keys[3].end_s, 1e-12);
  EXPECT_NEAR(t[4].placement_target_s, keys[3].end_s + 0.3, 1e-12);
}

TEST(Phasing, TruncatedNormalStaysInBounds) {
  std::mt19937_64 rng(3);
  double sum = 0;
  for (int i = 0; i < 20000; ++i) {
    const double x = SampleTruncatedNormal(1.0, 0.5, 2.0, rng);
    ASSERT_GE(x, 0.0);
    ASSERT_LE(x, 2.0);
    sum += x;
  }
  EXPECT_NEAR(sum / 20000, 1.0, 0.01);
  EXPECT_EQ(SampleTruncatedNormal(0.25, 0.0, 3.0, rng), 0.25);
}

TEST(Phasing, JsonRoundTrip) {
  PhasingModel m;
  m.placement_cv.start_mean_s = -0.2;
  m.shape_v.target_sd_s = 0.021;
  m.min_movement_s = 0.05;
  m.truncate_sd = 2.5;
  testing::TempDir dir;
  const std::string path = (dir / "phasing.json").string();
  SavePhasingModel(m, path);
  const PhasingModel r = LoadPhasingModel(path);
  EXPECT_NEAR(r.placement_cv.start_mean_s, -0.2, 1e-12);
  EXPECT_NEAR(r.shape_v.target_sd_s, 0.021, 1e-12);
  EXPECT_NEAR(r.min_movement_s, 0.05, 1e-12);
  EXPECT_DOUBLE_EQ(r.truncate_sd, 2.5);
  EXPECT_NEAR(r.rest.target_mean_s, m.rest.target_mean_s, 1e-12);
  EXPECT_NEAR(PhasingModelToJson(m)["placement_cv"]["start_mean_ms"].get<double>(), -200.0, 1e-9);
}

TEST(Phasing, BadModelsAreRejected) {
  PhasingModel m;
  m.shape_cv.start_sd_s = -0.01;
  EXPECT_NE(m.Check().find("shape_cv"), std::string::npos);
  std::mt19937_64 rng(1);
  EXPECT_THROW(SampleTiming({}, m, rng), InvalidInput);
  PhasingModel late;
  late.placement_v.start_mean_s = 0.2;  // starts after its target
  EXPECT_FALSE(late.Check().empty());

  nlohmann::json j = PhasingModelToJson(PhasingModel{});
  j["placement_cv"]["start_sd_ms"] = "wide";
  EXPECT_THROW(PhasingModelFromJson(j, "x.json"), ParseError);
  j = PhasingModelToJson(PhasingModel{});
  j["rest"].erase("target_mean_ms");
  try {
    PhasingModelFromJson(j, "x.json");
    FAIL() << "missing field accepted";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("x.json"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("rest.target_mean_ms"), std::string::npos);
  }

  testing::TempDir dir;
  const std::string path = (dir / "broken.json").string();
  std::ofstream(path) << "{\"placement_cv\": {\"start_mean_ms\": -239,";
  try {
    LoadPhasingModel(path);
    FAIL() << "truncated JSON accepted";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.where().file, path);
    EXPECT_TRUE(e.where().offset.has_value());
  }
  EXPECT_THROW(LoadPhasingModel((dir / "absent.json").string()), IoError);
}

}  // namespace
}  // namespace csw
