#pragma once
// The timing plan of a synthesised utterance (issue 15, the seed's §5): from
// the phones and keys of a French text (synth/phonetics, synth/cueing) to the
// target time of every key, before any unit is chosen. Two rules:
//   - kGlobal, the seed's one rule: a CV key's hand reaches its target at the
//     middle of the consonant, a lone vowel's at the vowel's acoustic onset, a
//     lone consonant's at the consonant's onset;
//   - kPerDikey: each key's target is its syllable's acoustic onset (A1) plus
//     the mean phasing the dictionary measured on the units with the same
//     succession (previous key → this key); where the dictionary has none,
//     the mean over the units arriving at the same key code, then the global
//     rule.
// Two successive targets are at least min_interval_s apart and at least
// min_slot_fraction of the succession's median unit duration (the targets
// moved as little as possible, in the least-squares sense, to keep every gap).
// The rest keys at both ends are placed one typical movement (the median
// duration of the dictionary's units leaving / reaching rest) before the first
// target and after the last; when the first would fall before time 0, the
// whole utterance is delayed by a lead-in of silence (`lead_in_s`).
//
// Pure: no file I/O.
#include <string>
#include <vector>

#include "core/labels.h"
#include "synth/cueing.h"
#include "synth/dictionary.h"

namespace csw::dict {

enum class PhasingRule { kGlobal, kPerDikey };
const char* PhasingRuleName(PhasingRule rule);  // "global", "dikey"
bool ParsePhasingRule(const std::string& name, PhasingRule* rule);

struct PlannedKey {
  KeyCode code;
  KeyType type = KeyType::kRest;
  double a1_s = 0;      // the syllable's acoustic onset (output clock, lead-in included); NaN for rests
  double target_s = 0;  // when the hand reaches the key (output clock)
  // Which rule gave target_s: "global", "dikey" (the succession's mean),
  // "code" (the arriving code's mean), "type" (the mean of the key type's
  // units), "rest"; each mean over units of this key's type (or of unknown
  // type when the dictionary has none of it); "+pushed" appended when the
  // minimum interval moved it.
  std::string source;
};

struct SynthesisPlan {
  double lead_in_s = 0;          // silence added before the text's audio and phones
  double duration_s = 0;         // output duration: lead-in + audio + the final return to rest
  std::vector<PlannedKey> keys;  // rest first and last, targets strictly increasing
};

struct PlanOptions {
  PhasingRule rule = PhasingRule::kPerDikey;
  // Shortest time between two successive targets (s): later targets are
  // pushed to keep it (fast syllables), and the push is reported by
  // PlannedKey::source gaining "+pushed".
  double min_interval_s = 0.04;
  // When the dictionary has no unit leaving (reaching) rest: the time from
  // the leading rest to the first target (from the last target to rest).
  double default_rest_s = 0.4;
  // kPerDikey: a succession's mean phasing is shrunk towards the mean of the
  // units arriving at the same code, as if that mean had this many more
  // units ((sum + k · code mean) / (n + k)): a succession seen in two units
  // is mostly noise (0 = the succession's own mean).
  double shrinkage_units = 3;
  // A slot (previous target → this target) is at least this fraction of the
  // median duration of the dictionary's units for that succession (of all
  // its units when it has none for it): a unit squeezed into much less time
  // than the corpus ever took makes the hand jump. Later targets are pushed
  // ("+pushed"). 0 = only min_interval_s.
  double min_slot_fraction = 0.6;
  // How targets are spaced when a slot is too short. true: every target is
  // moved as little as possible (least squares over the utterance, by
  // pool-adjacent-violators) so that all the gaps hold; a short slot opens
  // on both sides, the earlier key "+advanced", the later "+pushed", and
  // the targets keep their phasing on average. false: each later target is
  // pushed (all late).
  bool least_squares_spacing = true;
  std::string Check() const;
};

// Keys as CueKeys gives them for `phones` (rest first and last), times on the
// phones' clock. Throws InvalidInput when keys or phones are inconsistent
// (a key's phone index out of range, times not finite).
SynthesisPlan PlanKeys(const std::vector<Key>& keys, const std::vector<Phone>& phones, double audio_duration_s,
                       const Dictionary& dictionary, const PlanOptions& options = {});

// Mean duration (s) of the non-pause phones of the dictionary's diphones (each
// phone interval counted once per take); NaN when it has none. The speaking
// rate the synthesizer matches.
double MeanPhoneDuration(const Dictionary& dictionary);
// The same for a phone list (pauses, labelled "", left out); NaN when empty.
double MeanPhoneDuration(const std::vector<Phone>& phones);

}  // namespace csw::dict
