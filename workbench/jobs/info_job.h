#pragma once
// csw info: a summary of a corpus.
#include <nlohmann/json.hpp>
#include <string>

namespace csw::jobs {

// {"corpus", "format_version", "takes": [{name, rate_hz, frames, duration_s,
// markers, gaps, tiers, audio, analog_channels, markerset (bool: the take
// remembers the marker set it was imported with)}], "take_count", "frames",
// "duration_s"}.
// Throws csw::Error when the corpus cannot be opened.
nlohmann::json Info(const std::string& corpus);
// A header line and one aligned row per take (docs/cli.md shows an example).
std::string InfoText(const nlohmann::json& info);

}  // namespace csw::jobs
