#pragma once
// Phasing statistics (issue 11, scope item 5; docs/analysis-phasing.md): every
// key's measured gesture times (kinematic and posterior) relative to A1
// (consonant onset for CV and lone-C keys, vowel onset for lone-V keys) or to
// the vowel onset; per key type (CV, lone V, lone C) and component (placement,
// shape): mean, sd, 95 % confidence interval (Student t), count; histograms;
// one CSV row per key. Uses the types of synth/phasing.h (KeyType, KeyTiming).
// Pure computation: no files.
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "synth/cueing.h"
#include "synth/phasing.h"
#include "synth/phonetics.h"

namespace csw::phasing {

// Two-sided Student t quantile: the t with P(|T| < t) = coverage for `dof`
// degrees of freedom (exact series of Abramowitz & Stegun 26.7.3-4, inverted by
// bisection). dof >= 1, coverage in (0, 1); else InvalidInput.
double StudentTTwoSided(double coverage, int dof);

struct TimeSummary {
  int count = 0;
  double mean_ms = 0.0;
  double sd_ms = 0.0;    // sample standard deviation (n − 1); 0 for count < 2
  double ci95_ms = 0.0;  // half-width of the 95 % CI of the mean: t(0.975, n−1) · sd / √n; 0 for count < 2
};
// Summary of the finite values (NaN = left out).
TimeSummary SummariseTimes(const std::vector<double>& values_ms);

struct Histogram {
  double first_ms = 0.0;  // left edge of bin 0
  double bin_ms = 20.0;
  std::vector<int> counts;   // bin i = [first + i·bin, first + (i+1)·bin)
  int below = 0, above = 0;  // finite values outside the bins
};
Histogram MakeHistogram(const std::vector<double>& values_ms, double first_ms, double bin_ms, int bins);

// All times of a key with NaN (what is not measured).
KeyTiming UnmeasuredTiming();

// One key of one take (a CSV row). Times on the take's clock, NaN = not measured
// or left out (no change of that component, not dominant, ...).
struct PhasingKeyRow {
  std::string take;
  int key_index = 0;  // index in the take's key sequence (CueKeys order)
  std::string code;   // "PS"
  KeyType type = KeyType::kCV;
  double a1_s = 0.0;
  double vowel_onset_s = 0.0;  // NaN for lone consonants
  KeyTiming kinematic = UnmeasuredTiming();
  KeyTiming posterior = UnmeasuredTiming();
  KeyTiming truth = UnmeasuredTiming();  // known timing (simulation), else NaN
};

// The vowel onset of a key: the start of its vowel phone (CV, lone V; for lone
// V that is A1), NaN for lone consonants and rest. phones = the phone list the
// key's indices refer to.
double VowelOnset(const Key& key, const std::vector<Phone>& phones);

enum class PhasingMethod { kKinematic, kPosterior, kTruth };
enum class PhasingReference { kA1, kVowelOnset };
enum class Component { kPlacement, kShape };
enum class Landmark { kOnset, kTarget };

const char* KeyTypeLabel(KeyType type);  // "CV", "V", "C", "rest"

// (time − reference) in ms of one landmark of the rows of one key type (NaN kept
// out: the returned vector holds only finite values).
std::vector<double> RelativeTimesMs(const std::vector<PhasingKeyRow>& rows, PhasingMethod method,
                                    PhasingReference reference, KeyType type, Component component, Landmark landmark);

struct KeyTypeSummary {
  TimeSummary placement_onset, placement_target, shape_onset, shape_target;
};
struct PhasingSummary {
  KeyTypeSummary cv, v, c;
};
PhasingSummary SummarisePhasing(const std::vector<PhasingKeyRow>& rows, PhasingMethod method,
                                PhasingReference reference);

// {"CV": {"placement": {"onset": {"mean_ms", "sd_ms", "ci95_ms", "count"},
// "target": {...}}, "shape": {...}}, "V": {...}, "C": {...}}
nlohmann::json PhasingSummaryToJson(const PhasingSummary& summary);

// CSV (comma-separated, header first; times in seconds on the take's clock,
// empty when not measured; "rel" columns in ms relative to A1).
std::string PhasingCsvHeader();
std::string PhasingCsvRow(const PhasingKeyRow& row);

}  // namespace csw::phasing
