#pragma once
// A synthetic cued-speech take for the screenshot tour and the GUI benchmark:
// a talker's head (rigid cluster + face grid whose lower half follows the jaw),
// a cueing hand moving between the five LfPC positions ahead of each syllable,
// a voiced audio track, and "words" / "syllables" / "cues" tiers that match the
// motion. Deterministic; clearly named "synthetic" wherever it is shown.
#include <string>

#include "core/markerset.h"
#include "core/take.h"

namespace csw::gui {

struct DemoTakeOptions {
  std::string name = "synthetic_cued_speech";
  double seconds = 20.0;
  double rate_hz = 120.0;
  int markers = 113;  // >= 30: 4 head, 3 forearm, 3 palm, 15 finger, the rest face
  double audio_rate_hz = 16000.0;
};

Take MakeDemoTake(const DemoTakeOptions& options);
// The marker set naming the demo take's roles (head/forearm clusters, sticks).
MarkerSet DemoMarkerSet(int markers = 113);

}  // namespace csw::gui
