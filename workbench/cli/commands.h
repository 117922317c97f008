#pragma once
#include <CLI/CLI.hpp>
#include <memory>
#include <string>
#include <vector>

#include "core/progress.h"
#include "workbench/jobs/job_util.h"

namespace csw::cli {

// A bad combination of options detected after parsing (exit code 1); the jobs
// throw the same type for their own option checks.
using UsageError = jobs::UsageError;

// One subcommand: registers its options on the app, then runs if parsed.
class Command {
 public:
  virtual ~Command() = default;
  virtual void Register(CLI::App& app) = 0;
  virtual int Run(Progress& progress) = 0;
  bool parsed() const { return sub_ != nullptr && sub_->parsed(); }

 protected:
  CLI::App* sub_ = nullptr;
};

std::vector<std::unique_ptr<Command>> MakeCommands();

// Progress on stderr: a redrawn bar on a terminal, a line every 10% otherwise.
class ProgressPrinter {
 public:
  explicit ProgressPrinter(const bool* quiet);
  void Print(const std::string& stage, double fraction);
  void Done();

 private:
  const bool* quiet_;
  bool tty_;
  std::string stage_;
  int last_tenth_ = -1;
  int last_percent_ = -1;
  bool drawn_ = false;
};

}  // namespace csw::cli
