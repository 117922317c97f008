#pragma once
// `csw sign-sequence`: a new sign utterance from captured signs (issue 14,
// item 5; docs/transitions.md, "Transition synthesis"). For a list of glosses:
//   1. every occurrence of each gloss in a sign tier of the selected skeleton
//      takes is a candidate; motion retrieval picks one occurrence per gloss so
//      that the summed distance between consecutive signs' bounding postures is
//      least (analysis/signing RetrieveSequence);
//   2. each transition's duration comes from a duration model (a models file of
//      `csw transitions -o`, its best model or --model; or the seed's SURFACE
//      plane), measured over the file's joints (every joint, or each arm with
//      the longer of the two durations);
//   3. each transition's motion is an interpolation of the bounding postures or
//      a blend of the retraction that followed sign i in its capture with the
//      preparation that preceded sign i + 1 in its capture;
// and the result is written as a BVH file (the first candidate take's skeleton)
// with a TextGrid beside it (tiers `signs`: glosses and "transition"; `source`:
// the take and time each sign was cut from).
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw::jobs {

struct SignSequenceOptions {
  std::string corpus;
  std::vector<std::string> takes;    // take selection; empty = every take but fill versions
  std::vector<std::string> glosses;  // the utterance, in order (at least one)
  std::string tier = "signs";        // the tier whose intervals are labelled with glosses
  std::string durations;             // models file of `csw transitions -o`; "" = the seed's SURFACE plane
  std::string model;                 // model in that file; "" = its best
  std::string method = "blend";      // "blend" or "interpolate"
  bool smooth = false;               // blend weights 3u² − 2u³ instead of linear
  std::string output;                // the BVH file; a .TextGrid is written beside it
  std::string Check() const;
};

// {"corpus", "output", "textgrid", "rate_hz", "frames", "duration_s", "method", "model",
//  "signs": [{"gloss", "take", "start_s", "end_s", "candidates"}],
//  "transitions": [{"from", "to", "duration_s", "geodesic", "euclidean"}]}
nlohmann::json SignSequence(const SignSequenceOptions& options, Progress& progress);
std::string SignSequenceText(const nlohmann::json& result);

}  // namespace csw::jobs
