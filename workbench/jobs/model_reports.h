#pragma once
// Rendering of the model jobs' results: error statistics as JSON, and the
// default text output of `csw fit` and `csw invert` from their JSON summaries.
#include <nlohmann/json.hpp>
#include <string>

#include "models/inversion.h"

namespace csw::jobs {

// {"count": n, "mean_<unit>": …, "sd_<unit>": …, "max_<unit>": …}; {"count": 0} when empty.
nlohmann::json StatsJson(const ErrorStats& stats, const std::string& unit = "mm");
// The same plus the exact 99th and 99.9th percentiles (ErrorSamples::Percentile,
// linear interpolation between closest ranks): "p99_<unit>", "p99_9_<unit>".
nlohmann::json StatsJson(const ErrorSamples& samples, const std::string& unit = "mm");

// Text of `csw fit` from Fit's JSON (fit_job.h): one header line, then per model.
std::string FitText(const nlohmann::json& summary);

// Text of `csw invert` from Invert's JSON (invert_job.h): per model, one line per
// take, one per role (training, held-out), pose errors, the 3 shape markers
// with the largest 99.9th percentile (visible, and hidden with --hide), the
// worst frames (up to 5 of the JSON's list); then filled takes. Statistics read
// "mean ± sd mm (p99 …, p99.9 …, max …, n=…)", the percentiles when present.
std::string InvertText(const nlohmann::json& summary);

}  // namespace csw::jobs
