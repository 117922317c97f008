#pragma once
// Phonetic front end: French text -> phones with times and audio (libespeak-ng).
// Shared by the virtual cuer (datasets/) and the synthesizer (synth/).
#include <string>
#include <utility>
#include <vector>

#include "core/take.h"

namespace csw {

struct Phone {
  std::string ipa;       // one IPA phoneme, e.g. "a", "ʁ", "ɑ̃", "ɥ"; "" for a pause
  std::string espeak;    // espeak-ng's own phoneme name, e.g. "a~"
  double start_s = 0.0;  // position in the audio
  double end_s = 0.0;
  int word = -1;  // index into Utterance::words, -1 for pauses
};

struct Word {
  std::string text;
  double start_s = 0.0;
  double end_s = 0.0;
};

struct Utterance {
  std::string text;
  std::vector<Word> words;
  std::vector<Phone> phones;  // contiguous, covering [0, audio.duration_s()]
  Audio audio;                // mono, espeak-ng's sample rate (22050 Hz)
  // Recoverable oddities (an espeak-ng phoneme name missing from the table, ...).
  std::vector<std::string> warnings;
  double duration_s() const { return phones.empty() ? 0.0 : phones.back().end_s; }
};

struct PhonetiseOptions {
  std::string voice = "fr";
  int rate_wpm = 150;  // espeak-ng words per minute
  int pitch = 50;      // 0-99
  bool synthesize_audio = true;
  std::string Check() const;  // "" when valid, else the reason
};

// Phonetises and (optionally) synthesises one French utterance. Thread-compatible
// only: libespeak-ng is global state, so calls are serialised internally.
// Throws csw::Error when espeak-ng or its French voice is unavailable.
Utterance Phonetise(const std::string& text, const PhonetiseOptions& options = {});

// words and phones tiers (interval tiers covering the audio) for a TextGrid.
std::vector<LabelTier> UtteranceTiers(const Utterance& utterance);

// The documented espeak-ng -> IPA mapping table (docs/phonetics.md): returns ""
// for an unknown name and for pauses. When one espeak-ng phoneme stands for
// several French phonemes (the affricate "dZ", the English diphthong "aI") the
// IPA phonemes are separated by one space ("d ʒ", "a j").
std::string EspeakToIpa(const std::string& espeak_name);
// The same mapping split into phonemes: {} for an unknown name or a pause.
std::vector<std::string> EspeakToIpaPhones(const std::string& espeak_name);
// The whole table, in documentation order: (espeak-ng name, IPA).
std::vector<std::pair<std::string, std::string>> EspeakIpaTable();
// espeak-ng's pause phonemes ("_", "_:", "_!", "_|", ...).
bool IsEspeakPause(const std::string& espeak_name);
// espeak-ng's linking phoneme ";" (phsource/phonemes: "linking j ... used
// between (i) vowels and a following vowel"; in French it appears between a
// word-final [i] and a vowel-initial word: "bougie ; éclaire", "il y ; a"): a
// transitional glide, not a phoneme of the words, so not cued. Phonetise keeps
// it as its own phone with ipa ";" and espeak-ng's timing (the audio has the
// glide there; the phones of the virtual cuer's corpora stay as they were),
// which CueKeys passes over (in neither LfPC table) and csw cue reads as
// nothing (phone_symbols.h); it is not reported as an unmapped name.
bool IsEspeakLinking(const std::string& espeak_name);

// The one place where espeak-ng's output is corrected towards the phonemes
// actually spoken (docs/phonetics.md, "Exceptions"): espeak-ng writes the
// semi-vowel [ɥ] as the vowel "y" ("cuisinier" -> k y i z i n j e), so a "y"
// immediately followed by a vowel of the same word becomes "ɥ". Applied by
// Phonetise(); exposed for tests and for phone lists built by other means.
void ApplyIpaExceptions(std::vector<Phone>& phones);

}  // namespace csw
