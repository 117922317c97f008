#pragma once
// csw simulate: the virtual cuer (datasets/virtual_cuer.h).
#include <cstdint>
#include <string>
#include <vector>

#include "core/progress.h"

namespace csw {
struct SimulateOptions;
struct SignerOptions;
}  // namespace csw

namespace csw::jobs {

// Writes C3D, WAV, TextGrid, ground truth and markerset.json per take into
// options.output. Every capture option applies to every corpus, demo included
// (demo: shapes, visemes and the first `count` sentences in
// output/{shapes,visemes,sentences}, int16 C3D, no ground truth).
struct SimulateJobOptions {
  std::string corpus = "sentences";  // shapes, visemes, sentences, or demo (all three)
  std::string output;
  uint64_t seed = 1;
  int count = 0;                   // sentences: first N (0 = all / demo default 20)
  std::vector<std::string> texts;  // user sentences instead of the shipped list
  std::string sentences_file;      // one sentence per line
  double noise_mm = 0.2;
  bool occlusions = true;
  double dropouts_per_s = 0.03;  // per marker: rate of short dropped-sample runs
  bool label_swaps = false;
  double rate_hz = 120.0;
  bool clean = false;  // also write <take>.clean.c3d without artefacts
  // Marker layout: "default" or "lab2" (datasets/virtual_cuer.h, SimulateOptions::layout).
  std::string layout = "default";
  double hand_scale = 1.0;  // the hand's size relative to the layout's (--hand-scale)
  // The cuer's speaking rate (--speech-rate, words per minute, espeak-ng's
  // 80-450; SimulateOptions::speech_rate_wpm): a faster cuer leaves more keys
  // only approached.
  int speech_rate_wpm = 80;
  // Phasing-model JSON (synth/phasing.h LoadPhasingModel) for the gesture
  // times; "" = the defaults. Read by Simulate (a bad file: ParseError naming it).
  std::string phasing_file;
  // signs (the virtual signer, datasets/virtual_signer.h): the corpus
  // <output>/signs.h5 of `count` takes (0 = 20) and <output>/<take>.truth.json;
  // rate_hz, noise_mm and seed apply. The transition duration law (surface or
  // simple), and an annotator's tier "manual": the `signs` tier with every
  // boundary moved by up to manual_jitter_s (0 = no such tier).
  std::string law = "surface";
  double manual_jitter_s = 0.1;
  double hand_offset_s = 0.03;    // each hand's movements shifted by up to this (0 = synchronous hands)
  double duration_noise_s = 0.0;  // Gaussian noise added to the law (0 = the law exactly)
  std::string naming = "csw";     // joint names: csw or mixamo
  std::string Check() const;      // "" when valid, else the reason (a usage error)
};

// The datasets options for `options` (sentences_file and phasing_file not read yet).
SimulateOptions ToSimulateOptions(const SimulateJobOptions& options);

// The virtual signer's options for `options` (corpus "signs").
SignerOptions ToSignerOptions(const SimulateJobOptions& options);

// Writes everything into a hidden sibling folder ".<output>.csw-partial" and
// moves it into place at the end, so a failed or cancelled run changes nothing
// (a stale partial folder from a killed run is removed by the next run).
// Returns the take names (demo: "shapes/shapes_01", ...), sorted for demo.
// Throws UsageError when Check() fails, Cancelled, csw::Error.
std::vector<std::string> Simulate(const SimulateJobOptions& options, Progress& progress);

}  // namespace csw::jobs
