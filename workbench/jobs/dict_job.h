#pragma once
// `csw dict build`: the dikey dictionary of a corpus (issue 15, the seed's §5;
// synth/dictionary.h, docs/dictionary-format.md). Per selected take:
//   1. the key tier (--tier: `keys_aligned` as `csw keys score` writes it, or
//      the labelled `keys`), rests 00 added at the take's ends when missing;
//   2. the face model inverted (head pose) and the hand model inverted (forearm
//      pose and hand-shape parameters), every frame;
//   3. one dikey per succession of keys: hand parameters, forearm pose in the
//      head frame and head pose per frame; units with an unsolved frame are
//      left out (counted); with a phone tier whose cued keys (LfPC, as `csw
//      cue`) have the key tier's codes, each unit's phasing relative to its
//      arriving key's syllable;
//   4. with the phone tier, one diphone per succession of phones (pauses
//      included), middle to middle, with the face model's parameters per frame
//      and a reference to the audio segment.
// Writes DICT.h5 (io/dictionary) with the models' fingerprint, and reports the
// coverage of the corpus's key successions: present, missing, candidates each.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"
#include "models/inversion.h"
#include "synth/dictionary.h"

namespace csw::jobs {

struct DictBuildOptions {
  std::string corpus;
  std::string models;              // model file with a face and a hand model (csw fit)
  std::string keys;                // key model file (csw keys train); optional, recorded and checked for /keys
  std::string output;              // dictionary file (replaced)
  std::vector<std::string> takes;  // take selection; empty = every take but fill versions
  std::string tier = "keys_aligned";
  std::string phones = "phones";  // phone tier for the phasing and the diphones ("" = none)
  // Point tier of placement targets ("" = none; absent in a take = unknown):
  // each key's placement lag after its shape target (DikeyUnit), which the
  // synthesizer writes into its own placement_targets tier.
  std::string placement_tier = "placement_targets";
  dict::DikeyOptions dikeys;
  InversionOptions inversion;
  int threads = 0;  // takes inverted in parallel (0 = hardware threads)
  std::string Check() const;
};

// {"corpus", "models", "keys", "output", "tier", "models_fingerprint",
//  "takes": [{"take", "frames", "keys", "dikeys", "rejected_unsolved", "rejected_outside", "phasing",
//             "placement_lags": keys whose placement target was found}],
//  "dikeys": {"successions", "kept", "rejected_unsolved", "rejected_outside", "frames"},
//  "diphones": {the same, "distinct", "coverage": {"p1+p2": candidates}},
//  "coverage": {"corpus": COVERAGE, "dictionary": COVERAGE, "complete": bool,
//               "missing_dikeys": ["PS-PS", ...]}}
// with COVERAGE = CoverageJson.
nlohmann::json DictBuild(const DictBuildOptions& options, Progress& progress);
std::string DictBuildText(const nlohmann::json& result);

// {"units", "placement": {"counts": 6×6, "present", "missing": [[from, to], ...]},
//  "shape": {"counts": 9×9, "present", "missing"}, "dikeys": {"PS-PS": candidates}}
nlohmann::json CoverageJson(const dict::Coverage& coverage);

}  // namespace csw::jobs
