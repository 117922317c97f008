#pragma once
// `csw cue`: the expected Cued Speech keys of a phone alignment (docs/cli.md,
// docs/phonetics.md section 4). The phone tier's symbols (IPA, X-SAMPA, SPPAS,
// MFA; given or detected) are read as IPA phonemes (synth/phone_symbols.h), the
// LfPC rules (synth/cueing.h) give the keys, and the keys are written as an
// interval tier `expected_keys` (one interval per key from its A1 to its end,
// text "PS"; the time between keys is an empty interval):
//   - CORPUS.h5: into every selected take, replacing an earlier tier of that name
//     and keeping the others, in one crash-safe transaction;
//   - FILE.TextGrid: into OUT.TextGrid (-o), with all the input's tiers.
// Unknown and ambiguous phone symbols give warnings, not errors. A take without
// the phone tier is an error naming the take and the tiers it has; nothing is
// written then.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw::jobs {

struct CueOptions {
  std::string input;                   // corpus (.h5) or TextGrid
  std::string output;                  // TextGrid input: the TextGrid to write (required); corpus: must be empty
  std::vector<std::string> takes;      // corpus: take selection (take_selection.h), whole takes; default every take
  std::string phones = "phones";       // the phone tier
  std::string symbols = "auto";        // auto, ipa (or mfa), xsampa, sppas
  std::string tier = "expected_keys";  // the tier written
  bool dry_run = false;                // report only, write nothing
  std::string Check() const;           // "" when valid, else the reason (a usage error)
};

// {"input", "kind": "corpus"|"textgrid", "output", "tier", "symbols", "dry_run",
//  "takes": [{"take", "phones_tier", "symbols", "phones", "pauses", "keys",
//             "counts": {"CV", "V", "C", "rest"}, "sequence", "warnings": [...]}],
//  "keys", "warnings"}: "phones" counts the cued and uncued phones (not pauses),
//  "keys" the keys without rest, "sequence" every key code with the rests, the
//  top-level "keys" and "warnings" the totals.
nlohmann::json Cue(const CueOptions& options, Progress& progress);
// The default text output: one line per take, its warnings, then what was written.
std::string CueText(const nlohmann::json& result);

}  // namespace csw::jobs
