#pragma once
// `csw invert`: invert face / hand models on takes (per frame: cluster pose
// and shape parameters from the visible markers), score the reconstruction,
// and optionally write each take with its gaps filled as a new take.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/take.h"
#include "models/inversion.h"

namespace csw::jobs {

struct InvertOptions {
  std::string corpus;
  std::string models;
  std::vector<std::string> takes;  // take selection (take_selection.h); empty = every take but fill versions
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
// asked; pose errors against the truth. model_reports.h: InvertText renders it.
nlohmann::json Invert(const InvertOptions& options, Progress& progress);

// The models' reconstruction of one whole take, in the take's column layout:
// every marker that a model of the file (options.only: "face", "hand", "" =
// all) reconstructs, NaN elsewhere and where a frame's solve gives nothing.
// Gaps get the same edge correction as `csw invert --fill`. For `csw clean
// --fill model`. `where` names the take in errors (unbound model markers).
MarkerArray ModelReconstruction(const Take& take, const InvertOptions& options, const std::string& where,
                                Progress& progress);

}  // namespace csw::jobs
