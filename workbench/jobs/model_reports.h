#pragma once
// Rendering of the model jobs' results: error statistics as JSON, and the
// default text output of `csw fit` and `csw invert` from their JSON summaries.
#include <nlohmann/json.hpp>
#include <string>

#include "models/inversion.h"

namespace csw::jobs {

// {"count": n, "mean_<unit>": …, "sd_<unit>": …, "max_<unit>": …}; {"count": 0} when empty.
nlohmann::json StatsJson(const ErrorStats& stats, const std::string& unit = "mm");

// Text of `csw fit` from Fit's JSON (fit_job.h): one header line, then per model.
std::string FitText(const nlohmann::json& summary);

// Text of `csw invert` from Invert's JSON (invert_job.h): per model, one line per
// take, one per role (training, held-out), pose errors; then filled takes.
std::string InvertText(const nlohmann::json& summary);

}  // namespace csw::jobs
