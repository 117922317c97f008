#pragma once
// Helpers shared by the tests: where the third-party data lives, temporary dirs.
#include <filesystem>
#include <string>

namespace csw::testing {

// ../shared/data (from CSW_SHARED_DATA, set by ctest), or "" when absent.
std::filesystem::path SharedDataDir();
// SharedDataDir()/relative, or calls GTEST_SKIP-able empty path when absent.
std::filesystem::path SharedData(const std::string& relative);
// The project source tree (CSW_SOURCE_DIR).
std::filesystem::path SourceDir();

// A fresh temporary directory removed at destruction.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace csw::testing

// Skips the current test with a clear message when ../shared/data is absent.
#define CSW_REQUIRE_SHARED_DATA(rel)                                           \
  do {                                                                         \
    if (::csw::testing::SharedData(rel).empty())                               \
      GTEST_SKIP() << "shared test data not found: ../shared/data/" << (rel)   \
                   << " (set CSW_SHARED_DATA to the folder to run this test)"; \
  } while (0)
