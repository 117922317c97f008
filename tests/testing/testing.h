#pragma once
// Helpers shared by the tests: where the third-party data lives, temporary dirs.
#include <filesystem>
#include <initializer_list>
#include <string>

namespace csw::testing {

// True in the AddressSanitizer build (scripts/test.sh, stage 2), where -O0 and
// the sanitizers make virtual-cuer simulations 10-50 x slower: statistical
// tests over many simulated takes run on a subset there (the full count runs
// in stage 1); the sanitizers still see every code path.
#if defined(__SANITIZE_ADDRESS__)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif

// ../shared/data (from CSW_SHARED_DATA, set by ctest), or "" when absent.
std::filesystem::path SharedDataDir();
// SharedDataDir()/relative, or calls GTEST_SKIP-able empty path when absent.
std::filesystem::path SharedData(const std::string& relative);
// The paths among `relative` that are absent from ../shared/data, each as
// "../shared/data/<path>", joined by ", "; "" when all are there.
std::string MissingSharedData(std::initializer_list<std::string> relative);
// The project source tree (CSW_SOURCE_DIR).
std::filesystem::path SourceDir();

// A fresh temporary directory removed at destruction (kept, and its path
// printed, when the environment sets CSW_KEEP_TEST_FILES=1).
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

// Skips the current test, naming every missing file, when any of the given
// ../shared/data files is absent: CSW_REQUIRE_SHARED_DATA("a.c3d", "b.trc").
#define CSW_REQUIRE_SHARED_DATA(...)                                                                         \
  do {                                                                                                       \
    const std::string csw_missing_ = ::csw::testing::MissingSharedData({__VA_ARGS__});                       \
    if (!csw_missing_.empty())                                                                               \
      GTEST_SKIP() << "missing " << csw_missing_ << " (set CSW_SHARED_DATA to the folder to run this test)"; \
  } while (0)
