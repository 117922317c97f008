#pragma once
// Phone symbols of other tools -> the IPA phonemes of the LfPC rules (synth/cueing.h),
// so that expected keys can be computed for any phone alignment a user brings:
// IPA (Praat, WebMAUS, Montreal Forced Aligner's French phone set), X-SAMPA / French
// SAMPA, and SPPAS's French phone set. The one table is in docs/phonetics.md
// ("Phone symbols of other aligners"); the test synth.PhoneSymbols.DocTableMatchesCode
// checks that the page and the code agree.
//
// Every label of a phone tier becomes zero, one or more phones:
//   - a pause ("", "_", "#", "+", "sil", "sp", "<p:>", ...) or a filler
//     (SPPAS "fp", "gb", "@@", "dummy", MFA "spn") -> one pause phone (ipa ""),
//     which breaks the syllable;
//   - a phoneme -> its IPA phoneme; an affricate (dʒ, tʃ, ts, dz) -> two phones
//     sharing the interval equally; several space-separated symbols in one label
//     likewise share it;
//   - a liaison mark alone ("‿", "-\") -> nothing (the liaison consonant itself is
//     a normal consonant and takes the next vowel, as in "les amis" l e z a m i);
//     likewise espeak-ng's linking glide ";" (synth/phonetics.h IsEspeakLinking),
//     whose interval goes to the phone before it;
//   - a sound LfPC does not cue ([h], [ʔ]) -> an uncued phone, transparent to
//     the rules, no warning;
//   - an unknown symbol -> an uncued phone (ipa "?" + the symbol) and one warning per
//     symbol (never a throw);
//   - an ambiguous symbol (SPPAS "eu" = ə or ø, "U~" = ɛ̃ or œ̃, SAMPA archiphonemes
//     "E/", "O/", "&/", "U~/") -> the documented reading and one warning per symbol.
// Gaps between the intervals of a tier are pauses.
#include <string>
#include <vector>

#include "core/take.h"
#include "synth/cueing.h"
#include "synth/phonetics.h"

namespace csw {

enum class PhoneSymbols { kAuto, kIpa, kXsampa, kSppas };

// "auto", "ipa", "xsampa", "sppas" (also "x-sampa", "sampa", "mfa" = ipa); false when unknown.
bool ParsePhoneSymbols(const std::string& text, PhoneSymbols* symbols);
std::string PhoneSymbolsName(PhoneSymbols symbols);  // "auto", "ipa", "xsampa", "sppas"

// The symbol set of a tier's labels: IPA when any label has a non-ASCII
// character other than a liaison mark; else SPPAS when a label is one of SPPAS's
// own symbols ("eu", "U~", "#", "+", "fp", "gb", "@@", "dummy"; not "h", which X-SAMPA
// reads as [h]); else X-SAMPA.
// Never returns kAuto.
PhoneSymbols DetectPhoneSymbols(const std::vector<std::string>& labels);

// What one symbol (one whitespace-free token) stands for.
struct SymbolReading {
  enum class Kind { kPhonemes, kPause, kNothing, kUncued, kUnknown };
  Kind kind = Kind::kUnknown;
  std::vector<std::string> ipa;  // kPhonemes: IPA phonemes of the LfPC tables (1, or 2 for affricates)
  std::string uncued;            // kUncued: the IPA of the sound ("h", "ʔ")
  std::string note;              // non-empty for an ambiguous symbol: how it was read
};
// `symbols` must not be kAuto.
SymbolReading ReadPhoneSymbol(const std::string& symbol, PhoneSymbols symbols);

// Phones of an interval tier, in the symbols given (kAuto: DetectPhoneSymbols
// on the tier's labels). Phones are contiguous over [tier.start_s, tier.end_s]
// (gaps are pauses; adjacent pauses are merged). `where` prefixes the warnings
// ("corpus.h5: take 't1': tier 'phones'"). Throws InvalidInput (naming `where`)
// when the tier is a point tier or its labels overlap or are out of order.
struct MappedPhones {
  PhoneSymbols symbols = PhoneSymbols::kIpa;  // as used (never kAuto)
  std::vector<Phone> phones;                  // ipa "" = pause
  std::vector<std::string> warnings;          // one per unknown or ambiguous symbol
};
MappedPhones MapPhoneTier(const LabelTier& tier, PhoneSymbols symbols, const std::string& where);

// The keys as an interval tier over [start_s, end_s]: one interval per key from its
// A1 to its end, text "PS"; rest keys of zero length are left out. Labels are in
// time order and do not overlap (gaps between keys stay gaps).
LabelTier ExpectedKeysTier(const std::vector<Key>& keys, double start_s, double end_s,
                           const std::string& name = "expected_keys");

// MapPhoneTier + CueKeys + ExpectedKeysTier.
struct CuedTier {
  MappedPhones mapped;
  std::vector<Key> keys;  // with the leading and trailing rest keys
  LabelTier tier;         // "expected_keys" (or `name`)
};
CuedTier CuePhoneTier(const LabelTier& phones, PhoneSymbols symbols, const std::string& where,
                      const std::string& name = "expected_keys");

}  // namespace csw
