#include "tests/testing/testing.h"

#include <cstdio>
#include <cstdlib>
#include <random>

#include "core/build_paths.h"

namespace csw::testing {

namespace fs = std::filesystem;

fs::path SharedDataDir() {
  const char* env = std::getenv("CSW_SHARED_DATA");
  fs::path p = env ? fs::path(env) : fs::path(CSW_SHARED_DATA_DEFAULT);
  std::error_code ec;
  if (fs::is_directory(p, ec)) return fs::canonical(p);
  return {};
}

fs::path SharedData(const std::string& relative) {
  fs::path dir = SharedDataDir();
  if (dir.empty()) return {};
  fs::path p = dir / relative;
  std::error_code ec;
  return fs::exists(p, ec) ? p : fs::path();
}

std::string MissingSharedData(std::initializer_list<std::string> relative) {
  std::string missing;
  for (const std::string& r : relative) {
    if (!SharedData(r).empty()) continue;
    if (!missing.empty()) missing += ", ";
    missing += "../shared/data/" + r;
  }
  return missing;
}

fs::path SourceDir() {
  const char* env = std::getenv("CSW_SOURCE_DIR");
  return env ? fs::path(env) : fs::path(CSW_SOURCE_DIR_DEFAULT);
}

TempDir::TempDir() {
  std::random_device rd;
  for (int i = 0; i < 100; ++i) {
    fs::path p = fs::temp_directory_path() / ("csw-test-" + std::to_string(rd()));
    std::error_code ec;
    if (fs::create_directory(p, ec)) {
      path_ = p;
      return;
    }
  }
  throw std::runtime_error("cannot create a temporary directory");
}

TempDir::~TempDir() {
  // CSW_KEEP_TEST_FILES=1 keeps the files (to look at a test's figures).
  if (const char* keep = std::getenv("CSW_KEEP_TEST_FILES"); keep != nullptr && *keep != '\0' && *keep != '0') {
    std::fprintf(stderr, "kept %s\n", path_.string().c_str());
    return;
  }
  std::error_code ec;
  fs::remove_all(path_, ec);
}

}  // namespace csw::testing
