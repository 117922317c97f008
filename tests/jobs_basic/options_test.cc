// Check() of every basic job's options: valid requests pass, each bad one gives
// its exact reason (these become the CLI's usage errors, exit code 1).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "datasets/virtual_cuer.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/jobs.h"

namespace csw::jobs {
namespace {

TEST(ImportOptionsCheck, AcceptsCapturesLabelsAndAudio) {
  ImportOptions o;
  o.files = {"a.c3d", "a.TextGrid", "a.wav", "b.trc", "b.eaf"};
  o.corpus = "c.h5";
  EXPECT_EQ(o.Check(), "");
}

TEST(ImportOptionsCheck, RejectsEachBadRequestWithItsReason) {
  ImportOptions o;
  o.corpus = "c.h5";
  EXPECT_EQ(o.Check(), "import: no input files");
  o.files = {"a.c3d"};
  o.corpus = "";
  EXPECT_EQ(o.Check(), "import: no output corpus (-o)");
  o.corpus = "c.h5";
  o.chunk_frames = 0;
  EXPECT_EQ(o.Check(), "import: chunk_frames must be positive");
  o.chunk_frames = 4096;
  o.files = {"a.c3d", "other.h5"};
  EXPECT_EQ(o.Check(), "import: other.h5: unsupported file type (expected .c3d, .trc, .bvh, .TextGrid, .eaf or .wav)");
  o.files = {"notes.txt"};
  EXPECT_EQ(o.Check(), "import: notes.txt: unsupported file type (expected .c3d, .trc, .bvh, .TextGrid, .eaf or .wav)");
  o.files = {"a.c3d", "lab/Markers.JSON"};
  EXPECT_EQ(o.Check(),
            "import: lab/Markers.JSON: unsupported file type (expected .c3d, .trc, .bvh, .TextGrid, .eaf or .wav); a "
            "marker set is given with --markerset lab/Markers.JSON");
}

// A folder's files given with a wildcard include its marker set: when it is
// also the --markerset file (same path or the same file by another path), it
// is not a take.
TEST(ImportOptionsCheck, TheMarkerSetAmongTheFilesIsLeftOut) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "csw_import_markerset_check";
  std::filesystem::create_directories(dir);
  const std::string set = (dir / "markerset.json").string();
  std::ofstream(set) << "{}";
  ImportOptions o;
  o.corpus = "c.h5";
  o.markerset = set;
  o.files = {"a.c3d", set};
  EXPECT_EQ(o.Check(), "");
  o.files = {"a.c3d", (dir / "." / "markerset.json").string()};
  EXPECT_EQ(o.Check(), "");
  o.files = {"a.c3d", (dir / "other.json").string()};
  EXPECT_NE(o.Check().find("unsupported file type"), std::string::npos);
  std::filesystem::remove_all(dir);
}

TEST(ImportOptionsCheck, UnitsAreOneOfFiveAndOnlyForBvhFiles) {
  ImportOptions o;
  o.files = {"a.bvh", "a.TextGrid", "b.c3d"};
  o.corpus = "c.h5";
  EXPECT_EQ(o.Check(), "");  // guessed
  for (const char* u : {"mm", "cm", "dm", "m", "in"}) {
    o.units = u;
    EXPECT_EQ(o.Check(), "") << u;
  }
  o.units = "ft";
  EXPECT_EQ(o.Check(), "import: --units must be mm, cm, dm, m or in, not 'ft'");
  o.units = "cm";
  o.files = {"b.c3d", "c.trc"};
  EXPECT_EQ(o.Check(), "import: --units applies to .bvh files (C3D and TRC files carry their unit)");
  Progress progress;
  EXPECT_THROW(Import(o, progress), UsageError);
}

TEST(ExportOptionsCheck, UnitsOnlyForBvh) {
  ExportOptions o{"c.h5", "take01", "bvh", "out.bvh", "m"};
  EXPECT_EQ(o.Check(), "");
  o.units = "yd";
  EXPECT_EQ(o.Check(), "export: --units must be mm, cm, dm, m or in, not 'yd'");
  o.units = "cm";
  o.format = "trc";
  EXPECT_EQ(o.Check(), "export: --units applies to --format bvh only");
}

TEST(ImportOptionsCheck, MissingMarkersetFileIsAUsageError) {
  testing::TempDir dir;
  ImportOptions o;
  o.files = {"a.c3d"};
  o.corpus = "c.h5";
  o.markerset = (dir / "nope.json").string();
  EXPECT_EQ(o.Check(), "import: --markerset " + o.markerset + ": no such file");
  std::ofstream(dir / "set.json") << "{}";
  o.markerset = (dir / "set.json").string();
  EXPECT_EQ(o.Check(), "");
  // Import itself refuses with the same reason, as a UsageError.
  o.markerset = (dir / "nope.json").string();
  Progress progress;
  EXPECT_THROW(Import(o, progress), UsageError);
}

TEST(ExportOptionsCheck, RequiresEveryFieldAndAKnownFormat) {
  ExportOptions o{"c.h5", "take01", "c3d", "out.c3d", ""};
  EXPECT_EQ(o.Check(), "");
  for (const char* f : {"trc", "csv", "bvh"}) {
    o.format = f;
    EXPECT_EQ(o.Check(), "") << f;
  }
  o.format = "xyz";
  EXPECT_EQ(o.Check(), "export: --format must be c3d, trc, csv or bvh");
  o.format = "c3d";
  o.take = "";
  EXPECT_EQ(o.Check(), "export: corpus, --take and -o are required");
  Progress progress;
  EXPECT_THROW(Export(o, progress), UsageError);
}

TEST(SimulateJobOptionsCheck, AcceptsEveryCorpusWithCaptureOptions) {
  testing::TempDir dir;
  for (const char* corpus : {"shapes", "visemes", "sentences", "demo"}) {
    SimulateJobOptions o;
    o.corpus = corpus;
    o.output = (dir / "out").string();
    o.rate_hz = 100;
    o.noise_mm = 0;
    o.occlusions = false;
    o.dropouts_per_s = 0;
    o.label_swaps = true;
    o.clean = true;
    EXPECT_EQ(o.Check(), "") << corpus;
  }
}

TEST(SimulateJobOptionsCheck, RejectsEachBadRequestWithItsReason) {
  testing::TempDir dir;
  SimulateJobOptions o;
  EXPECT_EQ(o.Check(), "simulate: no output folder (-o)");
  o.output = (dir / "out").string();
  o.corpus = "poems";
  EXPECT_EQ(o.Check(), "simulate: unknown corpus \"poems\" (shapes, visemes, sentences, signs or demo)");
  o.corpus = "sentences";
  o.count = -1;
  EXPECT_EQ(o.Check(), "simulate: --count must be >= 0");
  o.count = 0;
  o.texts = {"bonjour"};
  o.sentences_file = "s.txt";
  EXPECT_EQ(o.Check(), "simulate: give --text or --sentences, not both");
  o.sentences_file = "";
  o.corpus = "shapes";
  EXPECT_EQ(o.Check(), "simulate: --text applies to the sentences and demo corpora, not shapes");
  o.texts.clear();
  o.corpus = "sentences";
  o.sentences_file = (dir / "none.txt").string();
  EXPECT_EQ(o.Check(), "simulate: --sentences " + o.sentences_file + ": no such file");
  o.sentences_file = "";
  o.rate_hz = 5;
  EXPECT_EQ(o.Check(), "simulate: --rate must be in [10, 2000] Hz");
  o.rate_hz = 120;
  o.noise_mm = -1;
  EXPECT_EQ(o.Check(), "simulate: --noise must be in [0, 50] mm");
  o.noise_mm = 0.2;
  o.dropouts_per_s = 11;
  EXPECT_EQ(o.Check(), "simulate: --dropouts must be in [0, 10] per s");
  o.dropouts_per_s = 0.03;
  // A ranged option: both sides refused with the reason, a value inside
  // accepted and passed on to the simulator.
  auto ranged = [&o](auto& field, auto low, auto high, auto inside, const std::string& why) {
    field = low;
    EXPECT_EQ(o.Check(), why);
    field = high;
    EXPECT_EQ(o.Check(), why);
    field = inside;
    EXPECT_EQ(o.Check(), "");
  };
  ranged(o.hand_scale, 0.4, 2.5, 0.8, "simulate: --hand-scale must be in [0.5, 2]");
  EXPECT_EQ(ToSimulateOptions(o).hand_scale, 0.8);
  o.corpus = "signs";
  EXPECT_EQ(o.Check(), "simulate: --hand-scale applies to the virtual cuer, not signs");
  o.corpus = "sentences";
  o.hand_scale = 1.0;
  ranged(o.speech_rate_wpm, 79, 451, 140, "simulate: --speech-rate must be in [80, 450] words per minute");
  EXPECT_EQ(ToSimulateOptions(o).speech_rate_wpm, 140);
  o.corpus = "shapes";
  EXPECT_EQ(o.Check(), "simulate: --speech-rate applies to the sentences and demo corpora (cued speech), not shapes");
  o.corpus = "signs";
  EXPECT_EQ(o.Check(), "simulate: --speech-rate applies to the virtual cuer, not signs");
  o.corpus = "sentences";
  o.speech_rate_wpm = 80;
  o.phasing_file = (dir / "none.json").string();
  EXPECT_EQ(o.Check(), "simulate: --phasing " + o.phasing_file + ": no such file");
  std::ofstream(dir / "p.json") << "{}";
  o.phasing_file = (dir / "p.json").string();
  EXPECT_EQ(o.Check(), "");
  o.corpus = "shapes";
  EXPECT_EQ(o.Check(), "simulate: --phasing applies to the sentences and demo corpora, not shapes");
  o.corpus = "visemes";
  EXPECT_EQ(o.Check(), "simulate: --phasing applies to the sentences and demo corpora, not visemes");
  o.corpus = "sentences";
  o.phasing_file = "";
  std::ofstream(dir / "file") << "x";
  o.output = (dir / "file").string();
  EXPECT_EQ(o.Check(), "simulate: -o " + o.output + " is a file, not a folder");
}

TEST(SimulateJobOptions, DemoCarriesEveryCaptureOption) {
  SimulateJobOptions o;
  o.corpus = "demo";
  o.output = "out";
  o.seed = 7;
  o.rate_hz = 100;
  o.noise_mm = 0.5;
  o.occlusions = false;
  o.dropouts_per_s = 0;
  o.label_swaps = true;
  o.clean = true;
  o.texts = {"bonjour"};
  SimulateOptions s = ToSimulateOptions(o);
  EXPECT_EQ(s.seed, 7u);
  EXPECT_EQ(s.rate_hz, 100.0);
  EXPECT_EQ(s.noise_mm, 0.5);
  EXPECT_FALSE(s.occlusions);
  EXPECT_EQ(s.dropouts_per_s, 0.0);
  EXPECT_TRUE(s.label_swaps);
  EXPECT_TRUE(s.write_clean);
  EXPECT_EQ(s.sentences, std::vector<std::string>{"bonjour"});
}

}  // namespace
}  // namespace csw::jobs
