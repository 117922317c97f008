#pragma once
// csw export: one take of a corpus as C3D, TRC or CSV.
#include <string>

#include "core/progress.h"

namespace csw::jobs {

struct ExportOptions {
  std::string corpus;
  std::string take;
  std::string format;  // "c3d", "trc", "csv"
  std::string output;
  std::string Check() const;  // "" when valid, else the reason
};

// Writes into a hidden temporary folder next to the output and renames: a failed
// or cancelled export never leaves half a file. Throws UsageError for bad options.
void Export(const ExportOptions& options, Progress& progress);

}  // namespace csw::jobs
