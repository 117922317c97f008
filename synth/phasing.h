#pragma once
// Hand-speech phasing model: when each key's placement and shape movements start
// and reach their targets, relative to the key's acoustic onset A1
// (../shared/docs/cued-speech.md, "Timing"; docs/phonetics.md, "Phasing").
#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <random>
#include <string>
#include <vector>

#include "synth/cueing.h"

namespace csw {

// One movement: start and target times relative to the reference instant, in
// seconds (negative = before it), each a normal law (mean, sd).
struct MovementTiming {
  double start_mean_s = 0.0;
  double start_sd_s = 0.0;
  double target_mean_s = 0.0;
  double target_sd_s = 0.0;
};

struct PhasingModel {
  // CV keys, relative to A1 = consonant onset (Attina 2005).
  MovementTiming placement_cv{-0.239, 0.087, 0.037, 0.076};
  MovementTiming shape_cv{-0.171, 0.048, -0.003, 0.045};
  // Vowel-only keys (shape 5), relative to A1 = vowel onset (Attina 2005 for the
  // placement; the shape uses the same law, the seed reporting shape and
  // placement gestures as highly synchronised).
  MovementTiming placement_v{-0.183, 0.079, 0.084, 0.064};
  MovementTiming shape_v{-0.183, 0.079, 0.084, 0.064};
  // Consonant-only keys (side placement), relative to A1 = consonant onset: the
  // CV laws (the seed: target reached near the consonantal onset, as for CV keys).
  MovementTiming placement_c{-0.239, 0.087, 0.037, 0.076};
  MovementTiming shape_c{-0.171, 0.048, -0.003, 0.045};
  // Return to rest after the last key, relative to the end of the last key's
  // syllable (project default, no published measure).
  MovementTiming rest{0.000, 0.040, 0.300, 0.060};
  // Draws are normal laws truncated to mean ± truncate_sd · sd.
  double truncate_sd = 3.0;
  // Shortest movement (start to target).
  double min_movement_s = 0.060;

  std::string Check() const;  // "" when valid, else the reason
};

// JSON (times in milliseconds: {"placement_cv": {"start_mean_ms": -239, ...}, ...}).
nlohmann::json PhasingModelToJson(const PhasingModel& model);
// Throws csw::ParseError naming `source` when a field is missing, not a number,
// or the model fails Check(). Missing movements keep their defaults.
PhasingModel PhasingModelFromJson(const nlohmann::json& json, const std::string& source = "<json>");
PhasingModel LoadPhasingModel(const std::string& path);                     // throws IoError / ParseError
void SavePhasingModel(const PhasingModel& model, const std::string& path);  // throws IoError

// Absolute times (seconds, same clock as the keys' a1_s) of one key's movements.
// For the first rest key all four are the instant the hand leaves rest.
struct KeyTiming {
  double placement_start_s = 0.0;
  double placement_target_s = 0.0;
  double shape_start_s = 0.0;
  double shape_target_s = 0.0;
};

// The laws of one key type (kRest uses `rest` for both movements).
const MovementTiming& PlacementTiming(const PhasingModel& model, KeyType type);
const MovementTiming& ShapeTiming(const PhasingModel& model, KeyType type);

// One draw of every key's timing, keys as from CueKeys() (rest first and last).
// Per movement: start and target drawn from their truncated normal laws around
// the key's A1; then each movement starts no earlier than the previous key's
// target of the same movement and lasts at least min_movement_s (the start moves
// later, then the target). Deterministic for a given generator state.
// Throws InvalidInput when the model fails Check().
// kOverlapping skips the "after the previous target" bound (only the minimum
// duration holds): movements then overlap and the drawn times keep the model's
// means exactly; the virtual cuer blends overlapping gestures by superposition.
enum class TimingMode { kSequential, kOverlapping };
std::vector<KeyTiming> SampleTiming(const std::vector<Key>& keys, const PhasingModel& model, std::mt19937_64& rng,
                                    TimingMode mode = TimingMode::kSequential);

// The mean timing (every draw at its mean, same constraints).
std::vector<KeyTiming> MeanTiming(const std::vector<Key>& keys, const PhasingModel& model);

// Mean of (time - A1) over the keys of each type, for each of the four times
// (what a phasing analysis measures). Types with no key keep zeros and count 0.
struct PhasingMeans {
  struct Entry {
    int count = 0;
    MovementTiming placement;  // sd fields hold the sample standard deviations
    MovementTiming shape;
  };
  Entry cv, v, c;
};
PhasingMeans MeasurePhasing(const std::vector<Key>& keys, const std::vector<KeyTiming>& timing);

// The constraints delay movements when syllables are short (at 350 ms per key the
// CV placement starts about 16 ms later than its law says), so the means of the
// produced timings differ from the model's. CalibratePhasing() returns a model
// whose draws, constrained on these keys, reproduce `target`'s means: it
// iterates `iterations` times on mean_in += target - measured (seeded draws).
PhasingModel CalibratePhasing(const std::vector<Key>& keys, const PhasingModel& target, uint64_t seed,
                              int iterations = 6);

// A draw from N(mean, sd) truncated to [mean - k·sd, mean + k·sd]; portable
// (does not use std::normal_distribution, whose output differs between libraries).
double SampleTruncatedNormal(double mean, double sd, double k, std::mt19937_64& rng);

}  // namespace csw
