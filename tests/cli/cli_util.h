#pragma once
// Running the `csw` binary from tests: exit code, stdout and stderr.
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "core/build_paths.h"

namespace csw::testing {

struct RunResult {
  int code = -1;
  std::string out;
  std::string err;
};

// Runs csw with arguments (shell-quoted by the caller), capturing stdout and stderr in dir.
inline RunResult Csw(const std::string& args, const std::filesystem::path& dir) {
  const std::filesystem::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const std::string cmd = std::string(CSW_BINARY) + " " + args + " >" + out.string() + " 2>" + err.string();
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  auto slurp = [](const std::filesystem::path& p) {
    std::ifstream in(p);
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  };
  r.out = slurp(out);
  r.err = slurp(err);
  return r;
}

// Single-quoted for the shell.
inline std::string Q(const std::filesystem::path& p) { return "'" + p.string() + "'"; }

}  // namespace csw::testing
