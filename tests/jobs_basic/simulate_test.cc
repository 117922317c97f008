// Simulate's output: the take names it returns and what lands in the output
// folder (written into a hidden partial folder, then moved into place).
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <set>

#include "tests/testing/testing.h"
#include "workbench/jobs/jobs.h"

namespace csw::jobs {
namespace {

namespace fs = std::filesystem;

std::set<std::string> Names(const fs::path& dir) {
  std::set<std::string> out;
  for (const auto& e : fs::directory_iterator(dir)) out.insert(e.path().filename().string());
  return out;
}

TEST(SimulateJob, ShapesIntoANewFolderGiveTheKnownFiles) {
  testing::TempDir dir;
  SimulateJobOptions o;
  o.corpus = "shapes";
  o.output = (dir / "new" / "shapes").string();  // parent folders are created
  Progress progress;
  const std::vector<std::string> takes = Simulate(o, progress);
  EXPECT_EQ(takes, std::vector<std::string>{"shapes_01"});
  EXPECT_EQ(Names(dir / "new" / "shapes"),
            (std::set<std::string>{"markerset.json", "shapes_01.c3d", "shapes_01.TextGrid", "shapes_01.truth.json"}));
  EXPECT_EQ(Names(dir / "new"), std::set<std::string>{"shapes"});  // no partial folder left
}

TEST(SimulateJob, IntoAnExistingFolderKeepsItsOtherFiles) {
  testing::TempDir dir;
  fs::create_directories(dir / "out");
  std::ofstream(dir / "out" / "notes.txt") << "mine";
  std::ofstream(dir / "out" / "shapes_01.c3d") << "old";  // replaced by the new take
  SimulateJobOptions o;
  o.corpus = "shapes";
  o.output = (dir / "out").string() + "/";  // a trailing slash names the same folder
  Progress progress;
  Simulate(o, progress);
  EXPECT_EQ(Names(dir / "out"), (std::set<std::string>{"markerset.json", "notes.txt", "shapes_01.c3d",
                                                       "shapes_01.TextGrid", "shapes_01.truth.json"}));
  std::ifstream notes(dir / "out" / "notes.txt");
  std::string text;
  notes >> text;
  EXPECT_EQ(text, "mine");
  EXPECT_GT(fs::file_size(dir / "out" / "shapes_01.c3d"), 1000u);
  EXPECT_EQ(Names(dir.path()), std::set<std::string>{"out"});
}

TEST(SimulateJob, CancelledRunChangesNothing) {
  testing::TempDir dir;
  SimulateJobOptions o;
  o.corpus = "shapes";
  o.output = (dir / "out").string();
  Progress progress;
  progress.Cancel();
  EXPECT_THROW(Simulate(o, progress), Cancelled);
  EXPECT_TRUE(Names(dir.path()).empty());
}

}  // namespace
}  // namespace csw::jobs
