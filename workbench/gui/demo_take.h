#pragma once
// The GUI's demo take (screenshot tour, GUI benchmark): made in
// memory by the virtual cuer (datasets/virtual_cuer.h), the same simulator as
// `csw simulate`, so the workbench shows what the rest of csw analyses: 113
// markers (face, throat, forearm, hand) with capture noise and occlusions,
// espeak-ng audio, and the words / phones / keys / gesture tiers, with the
// virtual cuer's ground truth alongside.
#include <cstdint>
#include <string>

#include "core/markerset.h"
#include "core/take.h"
#include "datasets/virtual_cuer.h"

namespace csw::gui {

struct DemoTakeOptions {
  std::string name = "virtual_cuer_demo";
  // The shipped sentences (datasets/sentences_fr.txt) are cued as one
  // utterance, in order (from the top again when the list runs out), until
  // their estimated speech time (65 ms per character at the cuer's 80 words
  // per minute) reaches `seconds`; 0 = the first sentence only (about 3 s).
  double seconds = 0.0;
  double rate_hz = 120.0;
  uint64_t seed = 1;
  bool audio = true;  // espeak-ng audio track
};

// The text MakeDemoTake cues for these options.
std::string DemoText(const DemoTakeOptions& options);
// The demo take with the virtual cuer's ground truth (keys, gesture times,
// clean markers). Throws csw::Error when espeak-ng fails.
SimulationResult SimulateDemoTake(const DemoTakeOptions& options);
// SimulateDemoTake(options).take.
Take MakeDemoTake(const DemoTakeOptions& options);
// The virtual cuer's marker set (head/forearm clusters, hand segments, sticks).
MarkerSet DemoMarkerSet();

}  // namespace csw::gui
