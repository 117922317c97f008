#include "synth/phone_symbols.h"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <map>
#include <sstream>
#include <string_view>

#include "core/error.h"

namespace csw {
namespace {

struct Entry {
  std::string_view symbol;
  std::string_view ipa;   // IPA phonemes separated by spaces; "" = pause
  std::string_view note;  // ambiguous: the alternatives
};

// Readings that are pauses or fillers in every symbol set (compared case-insensitively).
constexpr std::string_view kPauses[] = {"",      "_",   "#",     "##",      "+",  "sil", "sp", "spn",   "<p:>",
                                        "<sil>", "pau", "<eps>", "silence", "fp", "gb",  "@@", "dummy", "*"};

// X-SAMPA (and French SAMPA). docs/phonetics.md, "Phone symbols of other aligners".
// clang-format off
constexpr Entry kXsampa[] = {
    {"i", "i", ""}, {"e", "e", ""}, {"E", "ɛ", ""}, {"a", "a", ""}, {"A", "a", ""}, {"O", "ɔ", ""},
    {"o", "o", ""}, {"u", "u", ""}, {"y", "y", ""}, {"2", "ø", ""}, {"9", "œ", ""}, {"@", "ə", ""},
    {"e~", "ɛ̃", ""}, {"E~", "ɛ̃", ""}, {"a~", "ɑ̃", ""}, {"A~", "ɑ̃", ""}, {"o~", "ɔ̃", ""}, {"O~", "ɔ̃", ""},
    {"9~", "œ̃", ""},
    {"E/", "e", "e or ɛ"}, {"O/", "o", "o or ɔ"}, {"&/", "ø", "ø or œ"}, {"A/", "a", ""}, {"U~/", "ɛ̃", "ɛ̃ or œ̃"},
    {"p", "p", ""}, {"b", "b", ""}, {"t", "t", ""}, {"d", "d", ""}, {"k", "k", ""}, {"g", "ɡ", ""},
    {"c", "k", ""}, {"J\\", "ɡ", ""},
    {"f", "f", ""}, {"v", "v", ""}, {"s", "s", ""}, {"z", "z", ""}, {"S", "ʃ", ""}, {"Z", "ʒ", ""},
    {"m", "m", ""}, {"n", "n", ""}, {"J", "ɲ", ""}, {"N", "ŋ", ""}, {"l", "l", ""}, {"L", "l", ""},
    {"R", "ʁ", ""}, {"r", "ʁ", ""}, {"R\\", "ʁ", ""}, {"X", "ʁ", ""}, {"x", "ʁ", ""},
    {"w", "w", ""}, {"H", "ɥ", ""}, {"j", "j", ""},
    {"dZ", "d ʒ", ""}, {"tS", "t ʃ", ""}, {"ts", "t s", ""}, {"dz", "d z", ""},
};

// SPPAS's French phone set: X-SAMPA plus these (they take precedence).
constexpr Entry kSppasOnly[] = {
    {"eu", "ə", "ə or ø"}, {"U~", "ɛ̃", "ɛ̃ or œ̃"}, {"h", "ɥ", ""},
};

// IPA, after the decorations are stripped (Montreal Forced Aligner's French phone
// set included). Entries that are not the LfPC phonemes themselves.
constexpr Entry kIpaAliases[] = {
    {"ɑ", "a", ""}, {"ɐ", "a", ""}, {"æ", "a", ""}, {"ɪ", "i", ""}, {"ʊ", "u", ""}, {"ʏ", "y", ""},
    {"ɵ", "ø", ""}, {"ɶ", "œ", ""}, {"ɜ", "œ", ""}, {"ʌ", "œ", ""}, {"ɒ", "ɔ", ""},
    {"\u00E3", "ɑ̃", ""}, {"a\u0303", "ɑ̃", ""}, {"ɒ̃", "ɑ̃", ""}, {"\u1EBD", "ɛ̃", ""}, {"e\u0303", "ɛ̃", ""}, {"æ̃", "ɛ̃", ""},
    {"\u00F5", "ɔ̃", ""}, {"o\u0303", "ɔ̃", ""},
    {"g", "ɡ", ""}, {"c", "k", ""}, {"ɟ", "ɡ", ""}, {"ʎ", "l", ""},
    {"ʀ", "ʁ", ""}, {"r", "ʁ", ""}, {"ɾ", "ʁ", ""}, {"χ", "ʁ", ""}, {"ɹ", "ʁ", ""}, {"x", "ʁ", ""},
    {"dʒ", "d ʒ", ""}, {"tʃ", "t ʃ", ""}, {"ts", "t s", ""}, {"dz", "d z", ""},
};
// clang-format on

// Sounds with a symbol but no LfPC cue.
constexpr Entry kUncued[] = {{"h", "h", ""}, {"ʔ", "ʔ", ""}, {"ɦ", "h", ""}, {"?", "ʔ", ""}};

// Decorations removed from a symbol before it is looked up: length, stress,
// syllable breaks, secondary articulations, optional-phone brackets, tie bars.
constexpr std::string_view kIpaStrip[] = {"ː",      "ˑ",      "ˈ",      "ˌ",      "ʲ",      "ʰ",      "ʷ",
                                          "\u032A", "\u0325", "\u030A", "\u0329", "\u0361", "\u035C", ".",
                                          "(",      ")",      "[",      "]",      "/",      ":"};
constexpr std::string_view kSampaStrip[] = {"\"", "%", ":", ".", "(", ")", "[", "]", "'"};
// Liaison marks, and espeak-ng's linking glide ";" (synth/phonetics.h
// IsEspeakLinking; phone tiers written from espeak-ng before it was dropped
// carry it): alone, they stand for nothing.
constexpr std::string_view kLiaison[] = {"‿", "-\\", ";"};

void EraseAll(std::string* s, std::string_view what) {
  for (size_t at = s->find(what); at != std::string::npos; at = s->find(what)) s->erase(at, what.size());
}

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

bool IsPause(const std::string& symbol) {
  const std::string l = Lower(symbol);
  for (std::string_view p : kPauses)
    if (l == p) return true;
  return false;
}

const Entry* Find(const Entry* begin, const Entry* end, const std::string& symbol) {
  for (const Entry* e = begin; e != end; ++e)
    if (e->symbol == symbol) return e;
  return nullptr;
}

SymbolReading FromEntry(const Entry& e) {
  SymbolReading r;
  r.kind = SymbolReading::Kind::kPhonemes;
  std::istringstream in{std::string(e.ipa)};
  std::string p;
  while (in >> p) r.ipa.push_back(p);
  if (!e.note.empty())
    r.note = "'" + std::string(e.symbol) + "' (" + std::string(e.note) + ") read as " + std::string(e.ipa);
  return r;
}

bool IsAscii(const std::string& s) {
  return std::all_of(s.begin(), s.end(), [](char c) { return static_cast<unsigned char>(c) < 0x80; });
}

std::string Seconds(double t) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f s", t);
  return buf;
}

}  // namespace

bool ParsePhoneSymbols(const std::string& text, PhoneSymbols* symbols) {
  const std::string t = Lower(text);
  if (t == "auto") {
    *symbols = PhoneSymbols::kAuto;
  } else if (t == "ipa" || t == "mfa") {
    *symbols = PhoneSymbols::kIpa;
  } else if (t == "xsampa" || t == "x-sampa" || t == "sampa") {
    *symbols = PhoneSymbols::kXsampa;
  } else if (t == "sppas") {
    *symbols = PhoneSymbols::kSppas;
  } else {
    return false;
  }
  return true;
}

std::string PhoneSymbolsName(PhoneSymbols symbols) {
  switch (symbols) {
    case PhoneSymbols::kAuto:
      return "auto";
    case PhoneSymbols::kIpa:
      return "ipa";
    case PhoneSymbols::kXsampa:
      return "xsampa";
    case PhoneSymbols::kSppas:
      return "sppas";
  }
  return "auto";
}

PhoneSymbols DetectPhoneSymbols(const std::vector<std::string>& labels) {
  bool sppas = false;
  for (const std::string& label : labels) {
    std::string l = label;
    EraseAll(&l, "‿");
    if (!IsAscii(l)) return PhoneSymbols::kIpa;
    std::istringstream in(l);
    std::string tok;
    while (in >> tok) {
      if (tok == "eu" || tok == "U~" || tok == "#" || tok == "+" || tok == "fp" || tok == "gb" || tok == "@@" ||
          tok == "dummy")
        sppas = true;
    }
  }
  return sppas ? PhoneSymbols::kSppas : PhoneSymbols::kXsampa;
}

SymbolReading ReadPhoneSymbol(const std::string& symbol, PhoneSymbols symbols) {
  SymbolReading r;
  if (IsPause(symbol)) {
    r.kind = SymbolReading::Kind::kPause;
    return r;
  }
  for (std::string_view l : kLiaison) {
    if (symbol == l) {
      r.kind = SymbolReading::Kind::kNothing;
      return r;
    }
  }
  std::string s = symbol;
  EraseAll(&s, "‿");
  if (symbols == PhoneSymbols::kIpa) {
    for (std::string_view d : kIpaStrip) EraseAll(&s, d);
    if (s.empty()) {
      r.kind = SymbolReading::Kind::kNothing;
      return r;
    }
    if (VowelPlacement(s) != 0 || ConsonantShape(s) != 0) {
      r.kind = SymbolReading::Kind::kPhonemes;
      r.ipa = {s == "g" ? std::string("ɡ") : s};
      return r;
    }
    if (const Entry* e = Find(std::begin(kIpaAliases), std::end(kIpaAliases), s)) return FromEntry(*e);
  } else {
    EraseAll(&s, "-\\");
    for (std::string_view d : kSampaStrip) EraseAll(&s, d);
    // X-SAMPA diacritics follow an underscore ("t_d"): the base symbol counts.
    if (const size_t u = s.find('_'); u != std::string::npos && u > 0) s.resize(u);
    if (s.empty()) {
      r.kind = SymbolReading::Kind::kNothing;
      return r;
    }
    if (symbols == PhoneSymbols::kSppas) {
      if (const Entry* e = Find(std::begin(kSppasOnly), std::end(kSppasOnly), s)) return FromEntry(*e);
    }
    if (const Entry* e = Find(std::begin(kXsampa), std::end(kXsampa), s)) return FromEntry(*e);
  }
  if (const Entry* e = Find(std::begin(kUncued), std::end(kUncued), s)) {
    r.kind = SymbolReading::Kind::kUncued;
    r.uncued = std::string(e->ipa);
    return r;
  }
  r.kind = SymbolReading::Kind::kUnknown;
  return r;
}

MappedPhones MapPhoneTier(const LabelTier& tier, PhoneSymbols symbols, const std::string& where) {
  if (tier.kind != LabelTier::Kind::kInterval)
    throw InvalidInput(where + ": a phone tier must be an interval tier, '" + tier.name + "' is a point tier");
  MappedPhones out;
  if (symbols == PhoneSymbols::kAuto) {
    std::vector<std::string> labels;
    labels.reserve(tier.labels.size());
    for (const Label& l : tier.labels) labels.push_back(l.text);
    symbols = DetectPhoneSymbols(labels);
  }
  out.symbols = symbols;

  struct Tally {
    int count = 0;
    double first_s = 0;
    std::string what;
  };
  std::map<std::string, Tally> unknown, ambiguous;
  auto tally = [](std::map<std::string, Tally>& m, const std::string& sym, double t, const std::string& what) {
    Tally& x = m[sym];
    if (x.count++ == 0) {
      x.first_s = t;
      x.what = what;
    }
  };
  auto push = [&](std::string ipa, double start, double end) {
    if (ipa.empty() && !out.phones.empty() && out.phones.back().ipa.empty()) {
      out.phones.back().end_s = end;  // merge adjacent pauses
      return;
    }
    Phone p;
    p.ipa = std::move(ipa);
    p.start_s = start;
    p.end_s = end;
    out.phones.push_back(std::move(p));
  };

  const double eps = 1e-9;
  double t = tier.start_s;
  for (size_t i = 0; i < tier.labels.size(); ++i) {
    const Label& l = tier.labels[i];
    if (!(l.start_s <= l.end_s) || l.start_s < t - eps) {
      throw InvalidInput(where + ": label " + std::to_string(i + 1) + " [" + Seconds(l.start_s) + ", " +
                         Seconds(l.end_s) + "] '" + l.text +
                         "' overlaps the previous one or is out of time order; a phone tier needs "
                         "consecutive intervals");
    }
    if (l.start_s > t + eps) push("", t, l.start_s);  // a gap is a pause
    std::vector<std::string> ipa;                     // "" = pause
    std::istringstream in(l.text);
    std::string tok;
    bool any = false;
    while (in >> tok) {
      any = true;
      const SymbolReading r = ReadPhoneSymbol(tok, symbols);
      switch (r.kind) {
        case SymbolReading::Kind::kPause:
          ipa.push_back("");
          break;
        case SymbolReading::Kind::kNothing:
          break;
        case SymbolReading::Kind::kPhonemes:
          ipa.insert(ipa.end(), r.ipa.begin(), r.ipa.end());
          if (!r.note.empty()) tally(ambiguous, tok, l.start_s, r.note);
          break;
        case SymbolReading::Kind::kUncued:
          ipa.push_back(r.uncued);
          break;
        case SymbolReading::Kind::kUnknown:
          ipa.push_back("?" + tok);  // in neither LfPC table whatever the symbol: transparent to CueKeys
          tally(unknown, tok, l.start_s, "");
          break;
      }
    }
    if (!any) ipa.push_back("");  // an empty label is a pause
    if (ipa.empty()) {
      // Only liaison marks: the interval belongs to nothing; keep the tier contiguous.
      if (!out.phones.empty())
        out.phones.back().end_s = l.end_s;
      else
        push("", l.start_s, l.end_s);
    } else {
      const double step = (l.end_s - l.start_s) / static_cast<double>(ipa.size());
      for (size_t k = 0; k < ipa.size(); ++k) {
        const double a = l.start_s + step * static_cast<double>(k);
        const double b = k + 1 == ipa.size() ? l.end_s : a + step;
        push(ipa[k], a, b);
      }
    }
    t = l.end_s;
  }
  if (tier.end_s > t + eps) {
    push("", t, tier.end_s);
  } else if (!out.phones.empty() && tier.end_s > out.phones.back().end_s) {
    out.phones.back().end_s = tier.end_s;  // rounding of the last label's end
  }

  const std::string set = PhoneSymbolsName(symbols);
  for (const auto& [sym, x] : unknown) {
    out.warnings.push_back(where + ": unknown " + set + " phone symbol '" + sym + "' (" + std::to_string(x.count) +
                           (x.count == 1 ? " time" : " times") + ", first at " + Seconds(x.first_s) + "): not cued");
  }
  for (const auto& [sym, x] : ambiguous) {
    out.warnings.push_back(where + ": ambiguous " + set + " phone symbol " + x.what + " (" + std::to_string(x.count) +
                           (x.count == 1 ? " time" : " times") + ", first at " + Seconds(x.first_s) + ")");
  }
  return out;
}

LabelTier ExpectedKeysTier(const std::vector<Key>& keys, double start_s, double end_s, const std::string& name) {
  LabelTier tier;
  tier.name = name;
  tier.kind = LabelTier::Kind::kInterval;
  tier.start_s = start_s;
  tier.end_s = end_s;
  const double eps = 1e-9;  // boundaries this close are one boundary
  double t = start_s;
  for (const Key& k : keys) {
    const double a = k.a1_s < t + eps ? t : k.a1_s;
    const double b = k.end_s > end_s - eps ? end_s : k.end_s;
    if (!(b > a)) {
      if (k.type == KeyType::kRest) continue;
      // A cued key always gets an interval; one of zero length keeps its place.
      tier.labels.push_back({a, a, k.Code()});
      continue;
    }
    tier.labels.push_back({a, b, k.Code()});
    t = b;
  }
  return tier;
}

CuedTier CuePhoneTier(const LabelTier& phones, PhoneSymbols symbols, const std::string& where,
                      const std::string& name) {
  CuedTier out;
  out.mapped = MapPhoneTier(phones, symbols, where);
  out.keys = CueKeys(out.mapped.phones);
  out.tier = ExpectedKeysTier(out.keys, phones.start_s, phones.end_s, name);
  return out;
}

}  // namespace csw
