#pragma once
// LfPC (French Cued Speech) rules: phones -> keys (../shared/docs/cued-speech.md).
#include <string>
#include <vector>

#include "synth/phonetics.h"

namespace csw {

enum class KeyType { kRest, kCV, kConsonantAlone, kVowelAlone };
const char* KeyTypeText(KeyType type);  // "CV", "V", "C", "rest"
// The inverse of KeyTypeText; false (and *type unchanged) for any other text.
bool ParseKeyTypeText(const std::string& text, KeyType* type);

// One key: placement P (0-5) and shape S (0-8), written "PS" (e.g. "24"); "00" is rest.
struct Key {
  int placement = 0;
  int shape = 0;
  KeyType type = KeyType::kRest;
  int consonant_phone = -1;  // index into the phone list, -1 if none
  int vowel_phone = -1;      // index into the phone list, -1 if none
  double a1_s = 0.0;         // acoustic onset of the key's syllable (consonant onset for CV)
  double end_s = 0.0;        // acoustic end of the syllable part this key codes
  std::string Code() const;  // "PS"
};

// Shape of a consonant (IPA) 1-8, or 0 when not a consonant.
int ConsonantShape(const std::string& ipa);
// Placement of a vowel (IPA) 1-5, or 0 when not a vowel.
int VowelPlacement(const std::string& ipa);
bool IsVowel(const std::string& ipa);
bool IsConsonant(const std::string& ipa);  // semi-vowels j ɥ w count as consonants

// Keys of an utterance's phones: rest "00" first and last, CV keys, lone consonants
// at the side (1S), lone vowels with shape 5 (P5). Pauses ("") separate syllables;
// phones that are neither vowels nor consonants of the tables (e.g. [h]) are not
// cued and are skipped. A consonant pairs with the next vowel even across a word
// boundary (enchaînement, liaison). The leading rest key spans [first phone start,
// first key's a1_s], the trailing one [last key's end_s, last phone end]; with no
// cued phone the result is one rest key spanning the phones.
// docs/phonetics.md gives the rules with worked examples.
std::vector<Key> CueKeys(const std::vector<Phone>& phones);

}  // namespace csw
