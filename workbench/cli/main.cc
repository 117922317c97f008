// csw — the Cued Speech Workbench command-line tool. A thin shell over
// workbench/jobs: parse options, run the job with a progress bar on stderr,
// print results, map errors to exit codes (0 ok, 1 usage, 2 bad data).
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>

#include "core/error.h"
#include "core/progress.h"
#include "workbench/cli/commands.h"

namespace {

csw::Progress* g_progress = nullptr;

void OnSigint(int) {
  if (g_progress) g_progress->Cancel();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"csw — the Cued Speech Workbench: motion-capture corpora, models and cued-speech synthesis", "csw"};
  app.require_subcommand(1);
  app.set_version_flag("--version", std::string("csw ") + CSW_VERSION);
  bool quiet = false;
  app.add_flag("-q,--quiet", quiet, "No progress output on stderr");

  csw::cli::ProgressPrinter printer(&quiet);
  csw::Progress progress([&printer](const std::string& stage, double f) { printer.Print(stage, f); });
  g_progress = &progress;
  std::signal(SIGINT, OnSigint);
  std::signal(SIGTERM, OnSigint);

  std::vector<std::unique_ptr<csw::cli::Command>> commands = csw::cli::MakeCommands();
  for (auto& c : commands) c->Register(app);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    int rc = app.exit(e);  // prints help or the usage error
    return rc == 0 ? 0 : 1;
  }
  for (auto& c : commands) {
    if (!c->parsed()) continue;
    try {
      int rc = c->Run(progress);
      printer.Done();
      return rc;
    } catch (const csw::Cancelled&) {
      printer.Done();
      std::fprintf(stderr, "csw: cancelled; nothing was changed\n");
      return 130;
    } catch (const csw::cli::UsageError& e) {
      printer.Done();
      std::fprintf(stderr, "csw: %s\n", e.what());
      return 1;
    } catch (const csw::Error& e) {
      printer.Done();
      std::fprintf(stderr, "%s\n", e.what());
      return 2;
    } catch (const std::bad_alloc&) {
      printer.Done();
      std::fprintf(stderr, "csw: out of memory\n");
      return 2;
    } catch (const std::exception& e) {
      printer.Done();
      std::fprintf(stderr, "csw: internal error: %s\n", e.what());
      return 3;
    }
  }
  return 1;
}
