// Text and JSON output of inspect and info on inputs whose facts the test knows:
// a corpus and a model file built here, JSON written here.
#include <gtest/gtest.h>
#include <hdf5.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "io/corpus/corpus.h"
#include "io/formats/textgrid.h"
#include "io/models/model_file.h"
#include "models/rigid_model.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/jobs.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// `markers` markers over `frames` frames at `rate`; one missing sample at
// frame 3 of marker 1 when `one_gap`.
Take KnownTake(const std::string& name, int64_t frames, int64_t markers, double rate, bool one_gap) {
  Take t;
  t.name = name;
  t.rate_hz = rate;
  for (int64_t m = 0; m < markers; ++m) t.marker_names.push_back("M" + std::to_string(m));
  t.markers.Resize(frames, markers);
  for (int64_t f = 0; f < frames; ++f) {
    for (int64_t m = 0; m < markers; ++m) {
      float* p = t.markers.at(f, m);
      p[0] = static_cast<float>(m * 10 + f);
      p[1] = static_cast<float>(m);
      p[2] = 1000.0f;
    }
  }
  if (one_gap) t.markers.SetMissing(3, 1);
  return t;
}

TEST(InfoJob, SmallCorpusGivesItsKnownTakesInJson) {
  testing::TempDir dir;
  const std::string path = (dir / "c.h5").string();
  {
    CorpusTransaction tx(path);
    Take a = KnownTake("a", 240, 5, 120.0, true);
    a.tiers.push_back({"phones", LabelTier::Kind::kInterval, 0.0, 2.0, {{0.0, 2.0, "a"}}});
    tx.WriteTake(a);
    tx.WriteTake(KnownTake("b", 60, 3, 100.0, false));
    tx.Commit();
  }
  const json j = Info(path);
  EXPECT_EQ(j["corpus"], path);
  EXPECT_EQ(j["take_count"].get<int64_t>(), 2);
  EXPECT_EQ(j["frames"].get<int64_t>(), 300);
  EXPECT_NEAR(j["duration_s"].get<double>(), 2.6, 1e-12);
  ASSERT_EQ(j["takes"].size(), 2u);
  const json& a = j["takes"][0];
  EXPECT_EQ(a["name"], "a");
  EXPECT_EQ(a["rate_hz"].get<double>(), 120.0);
  EXPECT_EQ(a["frames"].get<int64_t>(), 240);
  EXPECT_EQ(a["duration_s"].get<double>(), 2.0);
  EXPECT_EQ(a["markers"].get<int64_t>(), 5);
  EXPECT_EQ(a["gaps"].get<int64_t>(), 1);
  EXPECT_EQ(a["tiers"], json::array({"phones"}));
  EXPECT_FALSE(a["audio"].get<bool>());
  EXPECT_EQ(a["analog_channels"].get<int64_t>(), 0);
  const json& b = j["takes"][1];
  EXPECT_EQ(b["name"], "b");
  EXPECT_EQ(b["rate_hz"].get<double>(), 100.0);
  EXPECT_EQ(b["frames"].get<int64_t>(), 60);
  EXPECT_NEAR(b["duration_s"].get<double>(), 0.6, 1e-12);
  EXPECT_EQ(b["markers"].get<int64_t>(), 3);
  EXPECT_EQ(b["gaps"].get<int64_t>(), 0);
  EXPECT_EQ(b["tiers"], json::array());
}

TEST(InfoJob, DefaultTextIsAHeaderAndOneAlignedRowPerTake) {
  const json info = {{"corpus", "c.h5"},
                     {"take_count", 2},
                     {"frames", 300},
                     {"duration_s", 2.6},
                     {"takes",
                      {{{"name", "a"},
                        {"rate_hz", 120.0},
                        {"frames", 240},
                        {"duration_s", 2.0},
                        {"markers", 5},
                        {"gaps", 1},
                        {"tiers", {"phones", "keys"}},
                        {"audio", true},
                        {"analog_channels", 0}},
                       {{"name", "b"},
                        {"rate_hz", 100.0},
                        {"frames", 60},
                        {"duration_s", 0.6},
                        {"markers", 3},
                        {"gaps", 0},
                        {"tiers", json::array()},
                        {"audio", false},
                        {"analog_channels", 0}}}}};
  const std::string expected =
      "c.h5: 2 take(s), 300 frames, 2.6 s\n"
      "  take                        rate   frames  dur(s) markers  gaps audio tiers\n"
      "  a                           120.0      240    2.00       5     1   yes phones,keys\n"
      "  b                           100.0       60    0.60       3     0    no -\n";
  EXPECT_EQ(InfoText(info), expected);
}

TEST(InspectJob, TextIsOneKeyValueLinePerFieldInKeyOrder) {
  json facts = {{"file", "x.wav"}, {"format", "wav"},    {"bytes", 44},          {"rate_hz", 16000.0},
                {"channels", 1},   {"duration_s", 0.25}, {"labels", {"a", "b"}}, {"warnings", json::array()}};
  facts["many"] = json::array();
  for (int i = 0; i < 13; ++i) facts["many"].push_back(i);
  const std::string expected =
      "bytes: 44\n"
      "channels: 1\n"
      "duration_s: 0.25\n"
      "file: x.wav\n"
      "format: wav\n"
      "labels: [\"a\",\"b\"]\n"
      "many: [13 items]\n"
      "rate_hz: 16000.0\n"
      "warnings: []\n";
  EXPECT_EQ(InspectText(facts), expected);
}

TEST(InspectJob, ModelFileTextHasOneBlockPerModel) {
  const json facts = {{"file", "m.h5"},
                      {"format", "models"},
                      {"bytes", 1000},
                      {"model_count", 1},
                      {"models",
                       {{"head_motion",
                         {{"markers", 4},
                          {"parameters", 3},
                          {"training_takes", {"a", "b@0:50%"}},
                          {"training_frames", 200},
                          {"selected_frames", 150},
                          {"training_rms_mm", 0.25},
                          {"created_utc", "2026-01-02T03:04:05Z"},
                          {"csw_version", "0.1.0"}}}}}};
  const std::string expected =
      "bytes: 1000\n"
      "file: m.h5\n"
      "format: models\n"
      "model_count: 1\n"
      "models:\n"
      "  head_motion: 4 markers, 3 parameters, 200 training frames (150 selected), 0.250 mm rms\n"
      "    training takes: a,b@0:50%\n"
      "    created: 2026-01-02T03:04:05Z (csw 0.1.0)\n";
  EXPECT_EQ(InspectText(facts), expected);
}

TEST(InspectJob, TextGridGivesItsTiers) {
  testing::TempDir dir;
  const std::string path = (dir / "t.TextGrid").string();
  WriteTextGrid(path, {{"phones", LabelTier::Kind::kInterval, 0.0, 1.5, {{0.0, 0.5, "b"}, {0.5, 1.5, "a"}}}}, 0.0, 1.5);
  Progress progress;
  const json j = Inspect(path, progress);
  EXPECT_EQ(j["format"], "textgrid");
  EXPECT_EQ(j["xmin"].get<double>(), 0.0);
  EXPECT_EQ(j["xmax"].get<double>(), 1.5);
  ASSERT_EQ(j["tiers"].size(), 1u);
  EXPECT_EQ(j["tiers"][0]["name"], "phones");
  EXPECT_EQ(j["tiers"][0]["kind"], "interval");
  EXPECT_EQ(j["tiers"][0]["labels"].get<int64_t>(), 2);
}

TEST(InspectJob, CorpusIsToldByItsFormatAttribute) {
  testing::TempDir dir;
  const std::string path = (dir / "c.hdf5").string();
  {
    CorpusTransaction tx(path);
    tx.WriteTake(KnownTake("only", 30, 2, 120.0, false));
    tx.Commit();
  }
  Progress progress;
  const json j = Inspect(path, progress);
  EXPECT_EQ(j["format"], "corpus");
  EXPECT_EQ(j["take_count"].get<int64_t>(), 1);
  EXPECT_EQ(j["takes"][0]["name"], "only");
}

TEST(InspectJob, ModelFileIsDescribedNotTakenForACorpus) {
  testing::TempDir dir;
  // A head cluster of 4 markers turning about z and moving along x.
  const std::vector<std::string> names = {"H1", "H2", "H3", "H4"};
  const double local[4][3] = {{50, 0, 0}, {-50, 0, 0}, {0, 60, 0}, {0, 0, 40}};
  MarkerArray m(300, 4);
  for (int64_t f = 0; f < 300; ++f) {
    const double a = 0.3 * std::sin(0.05 * static_cast<double>(f)), tx = 20.0 * std::cos(0.03 * static_cast<double>(f));
    for (int k = 0; k < 4; ++k) {
      float* p = m.at(f, k);
      p[0] = static_cast<float>(std::cos(a) * local[k][0] - std::sin(a) * local[k][1] + tx);
      p[1] = static_cast<float>(std::sin(a) * local[k][0] + std::cos(a) * local[k][1]);
      p[2] = static_cast<float>(local[k][2] + 1500.0 + 0.01 * static_cast<double>(f % 7));
    }
  }
  ModelFile file;
  file.head = FitRigidModel("head", names, {m});
  file.head->info.training_takes = {"t1", "t2@0:50%"};
  file.head->info.created_utc = "2026-01-02T03:04:05Z";
  file.head->info.csw_version = "9.9.9";
  const int parameters = file.head->motion.count();  // what was saved, known before inspect runs
  const int64_t training_frames = file.head->info.training_frames;
  const std::string path = (dir / "models.h5").string();
  SaveModelFile(path, file);

  Progress progress;
  const json j = Inspect(path, progress);
  EXPECT_EQ(j["format"], "models");
  EXPECT_EQ(j["model_count"].get<int64_t>(), 1);
  ASSERT_TRUE(j["models"].contains("head_motion")) << j.dump();
  const json& h = j["models"]["head_motion"];
  EXPECT_EQ(h["markers"].get<int64_t>(), 4);
  EXPECT_EQ(h["parameters"].get<int>(), parameters);
  EXPECT_EQ(h["training_takes"], json::array({"t1", "t2@0:50%"}));
  EXPECT_EQ(h["training_frames"].get<int64_t>(), training_frames);
  EXPECT_EQ(h["created_utc"], "2026-01-02T03:04:05Z");
  EXPECT_EQ(h["csw_version"], "9.9.9");
  EXPECT_NE(InspectText(j).find("  head_motion: 4 markers, "), std::string::npos) << InspectText(j);
}

TEST(InspectJob, NonHdf5H5FileIsAClearError) {
  testing::TempDir dir;
  const std::string path = (dir / "fake.h5").string();
  std::ofstream(path) << "this is not HDF5";
  Progress progress;
  try {
    Inspect(path, progress);
    FAIL() << "no error for a file that is not HDF5";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()), path + ": not an HDF5 file (expected a csw corpus or model file)");
  }
}

TEST(InspectJob, Hdf5FileOfAnotherFormatIsAClearError) {
  testing::TempDir dir;
  const std::string plain = (dir / "plain.h5").string(), other = (dir / "other.h5").string();
  for (const std::string& path : {plain, other}) {
    hid_t f = H5Fcreate(path.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    if (path == other) {
      hid_t type = H5Tcopy(H5T_C_S1);
      H5Tset_size(type, 9);
      hid_t space = H5Screate(H5S_SCALAR);
      hid_t attr = H5Acreate2(f, "format", type, space, H5P_DEFAULT, H5P_DEFAULT);
      ASSERT_GE(H5Awrite(attr, type, "my-stuff"), 0);
      H5Aclose(attr);
      H5Sclose(space);
      H5Tclose(type);
    }
    H5Fclose(f);
  }
  Progress progress;
  auto message = [&](const std::string& path) {
    try {
      Inspect(path, progress);
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_EQ(message(plain), plain +
                                ": an HDF5 file that is neither a csw corpus nor a csw model file (no root attribute "
                                "'format'; expected 'csw-corpus' or 'csw-models')");
  EXPECT_EQ(message(other), other +
                                ": an HDF5 file that is neither a csw corpus nor a csw model file (root attribute "
                                "format is 'my-stuff'; expected 'csw-corpus' or 'csw-models')");
}

}  // namespace
}  // namespace csw::jobs
