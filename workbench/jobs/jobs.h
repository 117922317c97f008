#pragma once
// Jobs: every user action as a function taking options, a Progress (with cancel)
// and returning a result. The CLI (workbench/cli) and the GUI (workbench/gui) are
// thin shells over these (architecture.md: "one library, two thin shells").
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw::jobs {

// ---- inspect ---------------------------------------------------------------
// Header facts of any supported file (C3D, TRC, TextGrid, EAF, WAV, corpus) as JSON.
// For C3D: processor, storage, points, first_frame, frames, point_rate_hz,
// analog_channels, analog_subframes_per_frame, valid_point_samples, sum_xyz_valid,
// labels, events, warnings. Throws csw::Error for unreadable files.
nlohmann::json Inspect(const std::string& path, Progress& progress);
// Human-readable rendering of Inspect's JSON.
std::string InspectText(const nlohmann::json& facts);

// ---- import ----------------------------------------------------------------
struct ImportOptions {
  std::vector<std::string> files;  // captures (.c3d, .trc) and labels/audio (.TextGrid, .eaf, .wav)
  std::string corpus;              // output corpus (created when absent)
  std::string markerset;           // optional marker-set JSON: every take must bind to it
  bool replace = false;            // replace takes that already exist
  int64_t chunk_frames = 4096;     // frames streamed per write
  std::string Check() const;       // "" when valid, else the reason
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
ImportResult Import(const ImportOptions& options, Progress& progress);

// ---- info ------------------------------------------------------------------
nlohmann::json Info(const std::string& corpus);
std::string InfoText(const nlohmann::json& info);

// ---- export ----------------------------------------------------------------
struct ExportOptions {
  std::string corpus;
  std::string take;
  std::string format;  // "c3d", "trc", "csv"
  std::string output;
  std::string Check() const;
};
void Export(const ExportOptions& options, Progress& progress);

// ---- simulate --------------------------------------------------------------
// The virtual cuer (datasets/virtual_cuer.h): writes C3D, WAV, TextGrid, ground
// truth and markerset.json per take into options.output.
struct SimulateJobOptions {
  std::string corpus = "sentences";  // shapes, visemes, sentences, or demo (all three)
  std::string output;
  uint64_t seed = 1;
  int count = 0;                   // sentences: first N (0 = all / demo default 20)
  std::vector<std::string> texts;  // user sentences instead of the shipped list
  std::string sentences_file;      // one sentence per line
  double noise_mm = 0.2;
  bool occlusions = true;
  bool label_swaps = false;
  double rate_hz = 120.0;
  bool clean = false;  // also write <take>.clean.c3d without artefacts
  std::string Check() const;
};
std::vector<std::string> Simulate(const SimulateJobOptions& options, Progress& progress);

}  // namespace csw::jobs
