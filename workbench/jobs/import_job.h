#pragma once
// csw import: captures with their labels and audio into a corpus.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw::jobs {

struct ImportOptions {
  std::vector<std::string> files;  // captures (.c3d, .trc, .bvh) and labels/audio (.TextGrid, .eaf, .wav)
  std::string corpus;              // output corpus (created when absent)
  std::string markerset;           // optional marker-set JSON: every take must bind to it
  bool replace = false;            // replace takes that already exist
  int64_t chunk_frames = 4096;     // frames streamed per write
  // Length unit of the .bvh files (BVH has none): "mm", "cm", "dm", "m" or
  // "in"; "" guesses it from each skeleton's size, with a warning in the report.
  std::string units;
  std::string Check() const;  // "" when valid, else the reason (a usage error)
};

struct ImportResult {
  std::vector<std::string> takes;     // imported take names
  std::vector<std::string> warnings;  // "file: warning"
  int64_t frames = 0;
  int64_t bytes_read = 0;
};

// Imports all files into the corpus in one crash-safe transaction: either every
// take lands or the corpus is left exactly as it was. Labels and audio pair with
// captures by base name (take01.c3d + take01.TextGrid + take01.wav).
// Throws UsageError when Check() fails, csw::Error for bad data.
ImportResult Import(const ImportOptions& options, Progress& progress);

// The import report: {"corpus", "takes", "frames", "warnings"} (csw import --json).
nlohmann::json ImportReportJson(const ImportOptions& options, const ImportResult& result);
// The report as text: one "warning: <take>: <warning>" line per warning (the
// CLI prints these on stderr), then "imported N take(s), F frames into C".
std::string ImportWarningsText(const ImportResult& result);
std::string ImportSummaryText(const ImportOptions& options, const ImportResult& result);

}  // namespace csw::jobs
