#pragma once
// Model jobs (issue 4): fit rigid/face/hand models from a corpus and a marker
// set, and invert them on takes to fill gaps and report reconstruction errors.
// Shared by `csw fit`, `csw invert` and the GUI.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"
#include "models/inversion.h"

namespace csw::jobs {

// A take, or a frame range of it: "name", "name@first:end" (frames, 0-based,
// end exclusive, either may be omitted) or with percentages of the take's
// length ("name@:50%", "name@50%:"). Resolved against the take's frame count.
struct TakeRange {
  std::string spec;  // as given
  std::string take;
  int64_t first = 0;
  int64_t count = -1;  // -1 = to the end (before Resolve)
};
// Throws InvalidInput on a malformed spec (naming it).
TakeRange ParseTakeRange(const std::string& spec);
// Fixes first/count for a take of `frames` frames; throws InvalidInput when
// the range is empty or outside the take.
void ResolveTakeRange(TakeRange* range, int64_t frames);

struct FitOptions {
  std::string corpus;
  std::string kind;                // "rigid", "face" or "hand"
  std::vector<std::string> train;  // take specs; empty = every take of the corpus
  std::string config;              // model configuration JSON (docs/model-format.md); optional
  std::string markerset;           // marker set JSON; overrides the config's "markerset"
  std::string output;              // model file (updated: other models kept)
  std::string figures;             // folder for PNG + SVG figures ("" = none)
  std::string Check() const;       // "" when valid, else the reason
};

// Fits and saves. Returns a JSON summary (model sizes, variance explained,
// training frames, fitted throat weights, figure paths).
nlohmann::json Fit(const FitOptions& options, Progress& progress);
std::string FitText(const nlohmann::json& summary);

struct InvertOptions {
  std::string corpus;
  std::string models;
  std::vector<std::string> takes;  // take specs; empty = every take (except .filled versions)
  std::string only;                // "face", "hand" or "" (every model in the file)
  bool fill = false;               // write each take with gaps filled as a new take "<take>.filled"
  double hide_fraction = 0;        // hide this fraction of visible shape samples and score them
  uint64_t seed = 1;               // for hide_fraction
  std::string truth;               // folder with <take>.clean.c3d: score occluded samples and poses
  std::string figures;             // folder for PNG + SVG figures
  int threads = 0;                 // takes inverted in parallel (0 = hardware threads)
  // Add the model's misfit at the edges of each gap, interpolated across it, to
  // the reconstruction of missing samples (CorrectGapsWithEdgeResiduals).
  bool edge_correction = true;
  InversionOptions inversion;
  std::string Check() const;
};

// Per model: per take and overall (training / held-out) mean, sd, max
// absolute errors (mm) of visible samples; hidden and occluded samples when
// asked; pose errors against the truth.
nlohmann::json Invert(const InvertOptions& options, Progress& progress);
std::string InvertText(const nlohmann::json& summary);

}  // namespace csw::jobs
