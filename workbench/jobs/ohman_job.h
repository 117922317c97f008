#pragma once
// `csw coartic fit`: Öhman's coarticulation model (issue 14 item 6;
// docs/coarticulation.md) fitted on symmetric VCV takes. Per selected take:
// the face model of --models (csw fit face) is inverted frame by frame, its
// guided-PCA parameters are the articulatory parameters x, and the take's
// phone tier gives the intervals. analysis/coarticulation/ohman.h then finds
// the isolated vowels (vowel references), the V C V tokens between pauses,
// and fits per consonant w_c(x), c(x) (where identifiable), the residual of
// the line through the contexts, k_c(t) and its stylisation.
//
// The fit is written (-o) as JSON, format "csw-ohman" version 1 (the "fit"
// object of the result; OhmanFitToJson / OhmanFitFromJson), so trajectories
// can be generated later from it without the corpus. Writes nothing into the
// corpus; --figures draws k_c(t) per consonant in its three contexts (the
// MOTHER paper's Figure 8) and, per take with tokens, the inverted
// parameters, the vocalic carrier and the generated trajectories (Figure 9).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/coarticulation/ohman.h"
#include "core/progress.h"
#include "models/inversion.h"

namespace csw::jobs {

struct OhmanJobOptions {
  std::string corpus;
  std::string models;              // model file with a face model (csw fit face)
  std::vector<std::string> takes;  // take selection; empty = every take but fill versions
  std::string phones = "phones";   // the phone tier (IPA labels)
  std::string output;              // fit file (JSON, "csw-ohman"); "" = not written
  std::string figures;             // folder for the k_c(t) figures ("" = none)
  coarticulation::OhmanOptions fit;
  InversionOptions inversion;
  std::string Check() const;  // "" or the reason (a usage error)
};

// {"corpus", "models", "output", "figures": [...], "takes": [{"take", "frames",
//  "solved_frames", "tokens", "generation": {"correlation": [P], "rms": [P],
//  "unknown_phones": [...]} (trajectories regenerated from the fit with the
//  take's phones, phones unknown to the fit left out, against the inverted
//  ones: in-sample)}], "skipped": [{"take", "reason"}],
//  "fit": OhmanFitToJson(...), "summary": {"tokens", "consonants",
//  "identifiable", "parameters"}}
nlohmann::json Ohman(const OhmanJobOptions& options, Progress& progress);
std::string OhmanText(const nlohmann::json& result);

// The persisted fit: {"format": "csw-ohman", "version": 1, "parameters":
// [names], "vowels": [{"vowel", "source", "occurrences", "target": [P]}],
// "rest": [P], "range": [P], "consonants": [{"consonant", "contexts", "tokens",
// "w", "intercept", "c", "residual" (P each, null = undefined),
// "effect"/"measured_effect"/"realisation": {vowel: [P]}, "k_style":
// {"left_inset_s", "left_ramp_s", "right_inset_s", "right_ramp_s", "rms",
// "samples"}, "mean_k": {"times_s", "k"}}], "tokens": [{"take", "vowel",
// "consonant", "v1_centre_s", "c_start_s", "c_end_s", "v2_centre_s",
// "realisation_s", "k_times_s", "k" (pooled k per frame, null where
// undefined)}], "warnings"}.
nlohmann::json OhmanFitToJson(const coarticulation::OhmanFit& fit, const std::vector<std::string>& parameter_names,
                              const std::vector<std::string>& take_names);
// Reads it back (tokens are not read: generation does not need them).
// ParseError naming `where` and the key on anything malformed.
coarticulation::OhmanFit OhmanFitFromJson(const nlohmann::json& j, const std::string& where,
                                          std::vector<std::string>* parameter_names = nullptr);

}  // namespace csw::jobs
