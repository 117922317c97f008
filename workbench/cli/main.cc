// csw — the Cued Speech Workbench command-line tool. A thin shell over
// workbench/jobs: parse options, run the job with a progress bar on stderr,
// print results, map errors to exit codes: 0 ok, 1 usage error, 2 bad data
// (unreadable, damaged or inconsistent input), 3 internal error, 130 after
// Ctrl-C (SIGINT), 143 after SIGTERM. A signal cancels the job through its
// Progress (the job rolls back); a second one ends the process at once.
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <atomic>
#include <csignal>
#include <cstdio>
#include <iostream>
#include <memory>

#include "core/error.h"
#include "core/progress.h"
#include "workbench/cli/commands.h"

namespace {

csw::Progress* g_progress = nullptr;
std::atomic<int> g_signal{0};

void OnSignal(int sig) {
  if (g_signal.exchange(sig) != 0) _exit(128 + sig);  // second signal: the user means it
  if (g_progress) g_progress->Cancel();
}

void InstallHandler(int sig) {
  struct sigaction sa {};
  sa.sa_handler = OnSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(sig, &sa, nullptr);
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
  InstallHandler(SIGINT);
  InstallHandler(SIGTERM);

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
      const int sig = g_signal.load();
      std::fprintf(stderr, "csw: %s; nothing was changed\n", sig == SIGTERM ? "terminated" : "cancelled");
      return sig == SIGTERM ? 143 : 130;
    } catch (const csw::jobs::UsageError& e) {
      printer.Done();
      std::fprintf(stderr, "csw: %s\n", e.what());
      return 1;
    } catch (const csw::Error& e) {
      printer.Done();
      std::fprintf(stderr, "%s\n", e.what());
      return 2;
    } catch (const std::bad_alloc&) {
      printer.Done();
      std::fprintf(stderr, "csw: internal error: out of memory\n");
      return 3;
    } catch (const std::exception& e) {
      printer.Done();
      std::fprintf(stderr, "csw: internal error: %s\n", e.what());
      return 3;
    }
  }
  return 1;
}
