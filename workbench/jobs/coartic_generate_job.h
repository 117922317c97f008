#pragma once
// `csw coartic generate`: articulatory parameter trajectories for a phone
// string from an Öhman fit (`csw coartic fit -o`; docs/coarticulation.md,
// "Generation"): the vocalic carrier between the vowel targets, then each
// consonant added in increasing w order (analysis/coarticulation GenerateOhman).
// Phones come as text ("a p a", each symbol optionally with ":MS" for its
// duration in milliseconds; "_" or "#" is a pause) or as an interval tier of a
// TextGrid. Writes a CSV (time_s, then one column per parameter) and, with
// --figures, the trajectories with the phone boundaries.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/take.h"

namespace csw::jobs {

struct CoarticGenerateOptions {
  std::string fit;       // the Öhman fit file (JSON, format csw-ohman)
  std::string phones;    // "a p:90 a _ i t i" ("" when textgrid is given)
  std::string textgrid;  // a TextGrid with a phone tier
  std::string tier = "phones";
  double vowel_ms = 150;  // default durations of symbols given without one
  double consonant_ms = 90;
  double pause_ms = 200;
  double rate_hz = 100;       // samples per second of the output
  bool skip_unknown = false;  // leave out phones the fit does not know instead of failing
  std::string output;         // CSV file ("" = none)
  std::string figures;        // folder for generated.png ("" = none)
  std::string Check() const;
};

// The phone intervals of a phone string ("a p:90 a"), from time 0, with the
// default durations for symbols the fit knows as vowels (`vowels`) or not.
// InvalidInput naming the item for a bad duration.
std::vector<Label> ParsePhoneString(const std::string& text, const std::vector<std::string>& vowels,
                                    const CoarticGenerateOptions& options);

// {"fit", "phones": [{"phone", "start_s", "end_s"}], "samples", "rate_hz", "duration_s",
//  "parameters": [names], "range": [{"parameter", "min", "max"}], "output", "figures"}
nlohmann::json CoarticGenerate(const CoarticGenerateOptions& options, Progress& progress);
std::string CoarticGenerateText(const nlohmann::json& result);

}  // namespace csw::jobs
