#pragma once
// `csw fit`: fit rigid (head/forearm), face or hand models on corpus takes and
// save them into a model file (other models in it are kept).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw::jobs {

struct FitOptions {
  std::string corpus;
  std::string kind;                // "rigid", "face" or "hand"
  std::vector<std::string> takes;  // take selection (take_selection.h); empty = every take but fill versions
  std::string config;              // model configuration JSON (docs/model-format.md); optional
  std::string markerset;           // marker set JSON; overrides the config's "markerset"
  std::string output;              // model file (updated: other models kept)
  std::string figures;             // folder for PNG + SVG figures ("" = none)
  std::string Check() const;       // "" when valid, else the reason
};

// Fits and saves. Returns a JSON summary (model_reports.h: FitText renders
// it): corpus, output, kind, training_takes (canonical take specs), figures,
// and per kind: "rigid" (per cluster: motion parameters, variance explained,
// frames, rms, per-take residuals), "face" or "hand".
nlohmann::json Fit(const FitOptions& options, Progress& progress);

}  // namespace csw::jobs
