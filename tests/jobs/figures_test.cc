// The figures module loader (workbench/jobs/figures.h): a module that cannot
// be loaded is a clear error naming the path; the built module draws, and its
// errors cross the dlopen boundary as messages.
#include "workbench/jobs/figures.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <string>

#include "core/build_paths.h"
#include "core/error.h"
#include "tests/testing/testing.h"

namespace csw::jobs {
namespace {

std::string LoadError(const std::string& module) {
  ::setenv("CSW_FIGURES_MODULE", module.c_str(), 1);
  std::string what = "(no error)";
  try {
    figures::Require();
  } catch (const InvalidInput& e) {
    what = e.what();
  }
  ::unsetenv("CSW_FIGURES_MODULE");
  return what;
}

TEST(Figures, ModuleThatCannotBeLoadedIsNamed) {
#ifndef CSW_FIGURES_MODULE_FILE
  EXPECT_NE(LoadError("/x.so").find("built without figures"), std::string::npos);
  GTEST_SKIP() << "built without the figures module (CSW_BUILD_GUI=OFF)";
#endif
  testing::TempDir dir;
  const std::string missing = (dir / "libcsw_figures.so").string();
  std::string e = LoadError(missing);
  EXPECT_NE(e.find("cannot load the figures module"), std::string::npos) << e;
  EXPECT_NE(e.find(missing + ": no such file"), std::string::npos) << e;
  const std::string text = (dir / "not_a_library.so").string();
  std::ofstream(text) << "not an ELF file\n";
  e = LoadError(text);
  EXPECT_NE(e.find(text + ": "), std::string::npos) << e;
  EXPECT_NE(e.find("cannot load the figures module"), std::string::npos) << e;
}

#ifdef CSW_FIGURES_MODULE_FILE
TEST(Figures, BuiltModuleDrawsAndReportsErrors) {
  ::setenv("CSW_FIGURES_MODULE", CSW_FIGURES_MODULE_FILE, 1);
  testing::TempDir dir;
  const std::string png = (dir / "bars.png").string();
  figures::SaveErrorBars(png, "test", {{"a", 0.3, 0.1, 0.9, false}, {"b", 0.4, 0.1, 1.2, true}}, 1.0);
  std::ifstream in(png, std::ios::binary);
  unsigned char h[24] = {};
  in.read(reinterpret_cast<char*>(h), 24);
  ASSERT_TRUE(in);
  EXPECT_EQ(h[1], 'P');
  EXPECT_EQ(h[2], 'N');
  EXPECT_EQ(h[3], 'G');
  const int width = (h[16] << 24) | (h[17] << 16) | (h[18] << 8) | h[19];
  const int height = (h[20] << 24) | (h[21] << 16) | (h[22] << 8) | h[23];
  EXPECT_EQ(width, report::kFigureWidth);
  EXPECT_EQ(height, report::kFigureHeight);
  // The module's InvalidInput, as a message naming the file.
  const std::string empty = (dir / "empty.png").string();
  try {
    figures::SaveErrorBars(empty, "test", {}, 0);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_EQ(std::string(e.what()), empty + ": no utterances to plot");
  }
  ::unsetenv("CSW_FIGURES_MODULE");
}
#endif

}  // namespace
}  // namespace csw::jobs
