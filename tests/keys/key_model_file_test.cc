#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>

#include "analysis/keys/key_model.h"
#include "core/error.h"
#include "io/models/model_file.h"
#include "tests/testing/testing.h"

namespace csw::keys {
namespace {

// A key model trained on random samples: 9 shape classes on 7 features, 6 placements on 3.
KeyModel RandomModel() {
  std::mt19937_64 rng(3);
  std::normal_distribution<double> n01;
  KeyTrainingSet set;
  set.shape_samples.resize(9 * 20, kNumDistances);
  set.placement_samples.resize(6 * 20, 3);
  for (int i = 0; i < 9 * 20; ++i) {
    for (int d = 0; d < kNumDistances; ++d) set.shape_samples(i, d) = 10 * (i % 9) + d + 2 * n01(rng);
    set.shape_labels.push_back(i % 9);
  }
  for (int i = 0; i < 6 * 20; ++i) {
    for (int d = 0; d < 3; ++d) set.placement_samples(i, d) = 30 * (i % 6) - 10 * d + 3 * n01(rng);
    set.placement_labels.push_back(i % 6);
  }
  set.shape_samples(5, 2) = std::numeric_limits<double>::quiet_NaN();  // a missing value in training
  HandLayout layout;
  layout.proximal = {"T1", "I1", "M1", "R1", "L1"};
  layout.distal = {"TT", "IT", "MT", "RT", "LT"};
  layout.palm = {"P1", "P2", "P3"};
  layout.thumb_palm = "P3";
  layout.head = {"H1", "H2", "H3", "H4"};
  Eigen::Matrix3Xd head(3, 4);
  head << 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 13;
  KeyModelOptions o;
  o.shape.priors = PriorKind::kCounts;
  KeyModel m = TrainKeyModel(set, layout, head, o);
  m.info.corpus = "corpus.h5";
  m.info.training_takes = {"a", "b"};
  return m;
}

TEST(KeyModelFile, RoundTripGivesIdenticalPosteriors) {
  testing::TempDir dir;
  const KeyModel m = RandomModel();
  ModelFile f;
  f.keys = m;
  const std::string path = (dir / "keys.h5").string();
  SaveModelFile(path, f);
  const ModelFile back = LoadModelFile(path);
  ASSERT_TRUE(back.keys.has_value());
  const KeyModel& k = *back.keys;
  EXPECT_EQ(k.layout, m.layout);
  EXPECT_EQ(k.index_shapes, m.index_shapes);
  EXPECT_EQ(k.info.training_takes, m.info.training_takes);
  EXPECT_TRUE(k.head_reference.isApprox(m.head_reference, 0));
  ASSERT_EQ(k.shape.classes().size(), 9u);
  EXPECT_EQ(k.shape.options().priors, PriorKind::kCounts);
  EXPECT_EQ(k.shape.feature_names(), DistanceNames());
  for (size_t i = 0; i < 9; ++i) {
    EXPECT_EQ(k.shape.classes()[i].count, m.shape.classes()[i].count);
    EXPECT_EQ(k.shape.classes()[i].covariance, m.shape.classes()[i].covariance);
  }
  // Bit-identical posteriors on some frames, one with a missing value.
  Eigen::MatrixXd x(3, kNumDistances);
  x << 1, 2, 3, 4, 5, 6, 7, 40, 41, 42, 43, 44, 45, 46, 80, std::numeric_limits<double>::quiet_NaN(), 82, 83, 84, 85,
      86;
  EXPECT_EQ(k.shape.Posteriors(x), m.shape.Posteriors(x));
  Eigen::MatrixXd y(2, 3);
  y << 0, 0, 0, 60, -10, -20;
  EXPECT_EQ(k.placement.Posteriors(y), m.placement.Posteriors(y));
}

TEST(KeyModelFile, DamagedFilesGiveOneErrorNamingTheFile) {
  testing::TempDir dir;
  ModelFile f;
  f.keys = RandomModel();
  const std::string path = (dir / "keys.h5").string();
  SaveModelFile(path, f);
  // Truncated to half.
  const auto size = std::filesystem::file_size(path);
  const std::string cut = (dir / "cut.h5").string();
  std::filesystem::copy_file(path, cut);
  std::filesystem::resize_file(cut, size / 2);
  try {
    LoadModelFile(cut);
    FAIL() << "truncated file loaded";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("cut.h5"), std::string::npos) << e.what();
  }
  // Garbage.
  const std::string junk = (dir / "junk.h5").string();
  std::ofstream(junk) << "this is not a key model";
  try {
    LoadModelFile(junk);
    FAIL() << "garbage loaded";
  } catch (const ParseError& e) {
    EXPECT_NE(std::string(e.what()).find("junk.h5"), std::string::npos) << e.what();
  }
  // A model that would not load back is refused before writing.
  ModelFile bad = f;
  bad.keys->index_shapes = {12};
  EXPECT_THROW(SaveModelFile((dir / "bad.h5").string(), bad), InvalidInput);
  EXPECT_FALSE(std::filesystem::exists(dir / "bad.h5"));
}

}  // namespace
}  // namespace csw::keys
