#pragma once
// `csw keys suggest`: a proposed target frame for every expected key, so that a
// user labelling target frames confirms rather than hunts (issue 11, item 3;
// docs/analysis.md, "Suggested targets").
//
// Per selected take: the expected keys from its phone tier (the LfPC rules,
// synth/phone_symbols.h, as `csw cue`), each key's expected shape and placement
// target times from a phasing model (the defaults of synth/phasing.h: Attina's
// means, or --phasing FILE.json), the hand features (analysis/keys/hand_features.h:
// the seven distances and the fingertips in the head frame, from the marker
// set's roles or a hand-layout file), and for each key the frame where the
// feature's filtered speed has the local minimum nearest its expected time
// (analysis/target_suggestion.h): the seven distances for the shape, the tip of
// the key's longest extended finger (index for shapes 1 and 6, middle
// otherwise) for the placement. Written as two point tiers whose texts are the
// key codes "PS": `keys_suggested` (shape targets) and `placement_suggested`
// (placement targets), in one transaction. Keys with no suggestion (the hand
// does not slow down near the expected time, markers missing) are listed with
// the reason and get no point. When the take has a label tier (`keys`, and
// `placement_targets`), each suggestion is compared with the label of the same
// code nearest to it (within 0.3 s).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/target_suggestion.h"
#include "core/progress.h"

namespace csw::jobs {

struct KeysSuggestOptions {
  std::string corpus;
  std::vector<std::string> takes;  // take selection; empty = every take but fill versions
  std::string phones = "phones";   // phone tier
  std::string symbols = "auto";    // its symbols: auto, ipa, mfa, xsampa, sppas
  std::string markerset;           // marker-set JSON; "" = the one the corpus remembers for each take
  std::string layout;              // JSON file with a "hand_layout" section; "" = from the marker set's roles
  std::string phasing;             // phasing model JSON (synth/phasing.h); "" = the defaults
  std::string tier = "keys_suggested";
  std::string placement_tier = "placement_suggested";
  std::string labels = "keys";                        // compared with, when present
  std::string label_placement = "placement_targets";  // placement labels, when present (else `labels`)
  analysis::TargetSuggestionOptions suggest;
  bool dry_run = false;       // report only, write no tier
  std::string Check() const;  // "" when valid, else the reason (a usage error)
};

// {"corpus", "takes": [{"take", "keys", "shape": {"suggested", "missing": [{"key", "code", "why"}],
//   "offset_ms": {"mean", "max"}}, "placement": {...}, "labels": {"shape": {"matched", "error_ms":
//   {"mean", "max"}, "within_40ms"}, "placement": {...}}}], "suggested", "keys", "tiers_written"}
nlohmann::json KeysSuggest(const KeysSuggestOptions& options, Progress& progress);
std::string KeysSuggestText(const nlohmann::json& result);

}  // namespace csw::jobs
