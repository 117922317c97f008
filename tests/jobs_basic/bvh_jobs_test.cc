// csw import / export / inspect of BVH files: the unit guessed with a warning in
// the import report (exact text and JSON), --units overriding it, the skeleton
// and orientations stored in the corpus, and the export back to BVH.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <string>

#include "io/corpus/corpus.h"
#include "io/formats/bvh.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/jobs.h"

namespace csw::jobs {
namespace {

using nlohmann::json;

// A person-sized chain in cm: hips 90 above the floor, a 80-unit spine, a foot
// 90 below: rest size 170 -> guessed cm. Frame 1 turns the spine 90° about z.
const char kPerson[] =
    "HIERARCHY\nROOT Hips\n{\n\tOFFSET 0 90 0\n\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation "
    "Yrotation\n\tJOINT Spine\n\t{\n\t\tOFFSET 0 10 0\n\t\tCHANNELS 3 Zrotation Xrotation Yrotation\n\t\tEnd Site\n"
    "\t\t{\n\t\t\tOFFSET 0 70 0\n\t\t}\n\t}\n\tJOINT Foot\n\t{\n\t\tOFFSET 0 -90 0\n\t\tCHANNELS 3 Zrotation "
    "Xrotation Yrotation\n\t\tEnd Site\n\t\t{\n\t\t\tOFFSET 0 0 10\n\t\t}\n\t}\n}\nMOTION\nFrames: 2\n"
    "Frame Time: 0.01\n0 90 0 0 0 0 0 0 0 0 0 0\n0 90 0 0 0 0 90 0 0 0 0 0\n";

std::string WriteFile(const testing::TempDir& dir, const std::string& name, const std::string& text) {
  const std::string path = (dir / name).string();
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

TEST(BvhImportJob, GuessedUnitIsWarnedInTheReport) {
  testing::TempDir dir;
  ImportOptions o;
  o.files = {WriteFile(dir, "signer.bvh", kPerson)};
  o.corpus = (dir / "c.h5").string();
  Progress progress;
  ImportResult r = Import(o, progress);
  ASSERT_EQ(r.takes, std::vector<std::string>{"signer"});
  EXPECT_EQ(r.frames, 2);
  const std::string warning =
      "signer: BVH has no length unit: guessed 'cm' from the skeleton's size of 170 file units (taken for a person "
      "about 1.7 m tall); give the unit (--units mm|cm|dm|m|in) if this is wrong";
  EXPECT_EQ(r.warnings, std::vector<std::string>{warning});
  EXPECT_EQ(ImportWarningsText(r), "warning: " + warning + "\n");
  EXPECT_EQ(ImportSummaryText(o, r), "imported 1 take(s), 2 frames into " + o.corpus + "\n");
  const json j = ImportReportJson(o, r);
  EXPECT_EQ(j, json({{"corpus", o.corpus}, {"takes", {"signer"}}, {"frames", 2}, {"warnings", {warning}}}));

  Take t = Corpus::Open(o.corpus).LoadTake("signer");
  EXPECT_EQ(t.source_units, "cm");
  ASSERT_EQ(t.skeleton.size(), 5u);
  EXPECT_EQ(t.marker_names, (std::vector<std::string>{"Hips", "Spine", "Spine_End", "Foot", "Foot_End"}));
  EXPECT_EQ(t.provenance.sources.at(0).format, "bvh");
  // Frame 1: spine turned 90° about z: its end site at hips + (0,100) + Rz90·(0,700) mm.
  const float* end = t.markers.at(1, 2);
  EXPECT_NEAR(end[0], -700.0, 1e-3);
  EXPECT_NEAR(end[1], 1000.0, 1e-3);
  EXPECT_NEAR(t.orientations.at(1, 1)[3], std::sqrt(0.5), 1e-6);
}

TEST(BvhImportJob, UnitsOptionOverridesTheGuessAndExportWritesBvh) {
  testing::TempDir dir;
  ImportOptions o;
  o.files = {WriteFile(dir, "signer.bvh", kPerson)};
  o.corpus = (dir / "c.h5").string();
  o.units = "in";
  Progress progress;
  ImportResult r = Import(o, progress);
  EXPECT_TRUE(r.warnings.empty());
  Take t = Corpus::Open(o.corpus).LoadTake("signer");
  EXPECT_EQ(t.source_units, "in");
  EXPECT_NEAR(t.markers.at(0, 0)[1], 90 * 25.4, 1e-3);

  // Export in the imported unit (in) reads back to the same take.
  ExportOptions e{o.corpus, "signer", "bvh", (dir / "out.bvh").string(), ""};
  Export(e, progress);
  BvhReadOptions in;
  in.units = "in";
  Take back = ReadBvh(e.output, in);
  ASSERT_EQ(back.frames(), 2);
  for (size_t k = 0; k < t.markers.data().size(); ++k) EXPECT_NEAR(back.markers.data()[k], t.markers.data()[k], 1e-3);
  for (size_t k = 0; k < t.orientations.data().size(); ++k) {
    EXPECT_NEAR(back.orientations.data()[k], t.orientations.data()[k], 1e-6);
  }
  // In metres on request: the root OFFSET 90 in = 2.286 m.
  e.units = "m";
  e.output = (dir / "out_m.bvh").string();
  Export(e, progress);
  std::ifstream f(e.output);
  std::string text((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("OFFSET 0 2.286 0\n"), std::string::npos) << text.substr(0, 200);
}

TEST(BvhImportJob, ExportOfATakeWithoutSkeletonIsRefused) {
  testing::TempDir dir;
  const std::string corpus = (dir / "c.h5").string();
  {
    Take t;
    t.name = "plain";
    t.rate_hz = 100;
    t.marker_names = {"M"};
    t.markers.Resize(2, 1);
    CorpusTransaction tx(corpus);
    tx.WriteTake(t);
    tx.Commit();
  }
  Progress progress;
  ExportOptions e{corpus, "plain", "bvh", (dir / "out.bvh").string(), ""};
  try {
    Export(e, progress);
    ADD_FAILURE() << "no error";
  } catch (const InvalidInput& err) {
    EXPECT_NE(std::string(err.what()).find("take \"plain\" has no skeleton"), std::string::npos) << err.what();
  }
  EXPECT_FALSE(std::filesystem::exists(e.output));
}

TEST(BvhInspectJob, GivesJointsEndSitesAndChannels) {
  testing::TempDir dir;
  Progress progress;
  const json j = Inspect(WriteFile(dir, "signer.bvh", kPerson), progress);
  EXPECT_EQ(j["format"], "bvh");
  EXPECT_EQ(j["joints"], 3);
  EXPECT_EQ(j["end_sites"], 2);
  EXPECT_EQ(j["channels"], 12);
  EXPECT_EQ(j["frames"], 2);
  EXPECT_EQ(j["units"], "cm");
  EXPECT_DOUBLE_EQ(j["rate_hz"].get<double>(), 100.0);
}

}  // namespace
}  // namespace csw::jobs
