// csw pack / csw upgrade jobs: option checks, exact text output, and JSON
// facts checked against a corpus built by the test.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "core/progress.h"
#include "io/corpus/corpus.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/jobs.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

Take SmallTake(const std::string& name, int64_t frames) {
  Take t;
  t.name = name;
  t.rate_hz = 100.0;
  t.marker_names = {"A", "B"};
  t.markers.Resize(frames, 2);
  for (int64_t f = 0; f < frames; ++f) {
    for (int64_t m = 0; m < 2; ++m) {
      float* p = t.markers.at(f, m);
      p[0] = static_cast<float>(f);
      p[1] = static_cast<float>(m);
      p[2] = 3.0f;
    }
  }
  t.markerset_json = R"({"name":"two"})";
  return t;
}

TEST(PackJob, OptionsCheckNamesWhatIsMissingOrExists) {
  testing::TempDir dir;
  EXPECT_EQ((PackOptions{"", "x.h5"}.Check()), "pack: no corpus given");
  EXPECT_EQ((PackOptions{"c.h5", ""}.Check()), "pack: no output file given (-o)");
  const std::string exists = (dir / "exists.h5").string();
  { std::ofstream(exists) << "x"; }
  EXPECT_EQ((PackOptions{"c.h5", exists}.Check()), "pack: " + exists + " exists; give a new file name");
  EXPECT_EQ((PackOptions{"c.h5", (dir / "new.h5").string()}.Check()), "");
}

TEST(PackJob, TextOutputIsOneLine) {
  const json r = {{"corpus", "c.h5"}, {"output", "one.h5"}, {"takes", 3}, {"bytes", 12345}};
  EXPECT_EQ(PackText(r), "packed 3 take(s) of c.h5 into one.h5 (12345 bytes, one self-contained file)\n");
  EXPECT_EQ(UpgradeText({{"corpus", "c.h5"}, {"upgraded", true}, {"takes", 2}, {"format_version", 2}}),
            "c.h5: upgraded to format version 2 (2 take(s) now in c.h5.d/)\n");
  EXPECT_EQ(UpgradeText({{"corpus", "c.h5"}, {"upgraded", false}, {"takes", 2}, {"format_version", 2}}),
            "c.h5: already format version 2 with its folder; nothing to do\n");
}

TEST(PackJob, PackAndUpgradeKeepEveryTake) {
  testing::TempDir dir;
  const std::string corpus = (dir / "c.h5").string();
  {
    CorpusTransaction tx(corpus);
    tx.WriteTake(SmallTake("a", 10));
    tx.WriteTake(SmallTake("b", 7));
    tx.Commit();
  }
  Progress progress;
  const std::string one = (dir / "one.h5").string();
  const json packed = Pack(PackOptions{corpus, one}, progress);
  EXPECT_EQ(packed["takes"].get<int>(), 2);
  EXPECT_EQ(packed["bytes"].get<int64_t>(), static_cast<int64_t>(fs::file_size(one)));
  EXPECT_FALSE(fs::exists(one + ".d"));

  const json up = Upgrade(one, progress);
  EXPECT_TRUE(up["upgraded"].get<bool>());
  EXPECT_EQ(up["takes"].get<int>(), 2);
  EXPECT_EQ(up["format_version"].get<int>(), 2);
  const Corpus c = Corpus::Open(one);
  const Take b = c.LoadTake("b");
  ASSERT_EQ(b.frames(), 7);
  EXPECT_EQ(b.markers.at(6, 1)[0], 6.0f);
  EXPECT_EQ(b.markers.at(6, 1)[1], 1.0f);
  EXPECT_EQ(b.markerset_json, R"({"name":"two"})");
  EXPECT_FALSE(Upgrade(one, progress)["upgraded"].get<bool>());
}

}  // namespace
}  // namespace csw::jobs
