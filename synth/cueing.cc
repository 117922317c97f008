#include "synth/cueing.h"

#include <string_view>

namespace csw {
namespace {

// ../shared/docs/cued-speech.md, "Hand shapes" and "Hand placements".
struct Group {
  std::string_view ipa;
  int value;
};

// clang-format 14 miscounts the columns of these UTF-8 tables: keep them as written.
// clang-format off
constexpr Group kShapes[] = {
    {"p", 1}, {"d", 1}, {"ʒ", 1}, {"k", 2}, {"v", 2}, {"z", 2}, {"s", 3}, {"ʁ", 3}, {"b", 4}, {"n", 4}, {"ɥ", 4},
    {"t", 5}, {"m", 5}, {"f", 5}, {"l", 6}, {"ʃ", 6}, {"ɲ", 6}, {"w", 6},
    {"ɡ", 7}, {"g", 7},  // U+0261 and the ASCII letter some sources write
    {"j", 8}, {"ŋ", 8},
};

constexpr Group kPlacements[] = {
    {"a", 1}, {"o", 1}, {"œ", 1}, {"ə", 1}, {"ɛ̃", 2}, {"ø", 2}, {"i", 3}, {"ɔ̃", 3},
    {"ɑ̃", 3}, {"ɛ", 4}, {"u", 4}, {"ɔ", 4}, {"y", 5}, {"e", 5}, {"œ̃", 5},
};
// clang-format on

int Lookup(const Group* begin, const Group* end, const std::string& ipa) {
  for (const Group* g = begin; g != end; ++g)
    if (g->ipa == ipa) return g->value;
  return 0;
}

Key RestKey(double a1_s, double end_s) {
  Key k;
  k.type = KeyType::kRest;
  k.a1_s = a1_s;
  k.end_s = end_s;
  return k;
}

}  // namespace

std::string Key::Code() const { return std::to_string(placement) + std::to_string(shape); }

int ConsonantShape(const std::string& ipa) { return Lookup(std::begin(kShapes), std::end(kShapes), ipa); }

int VowelPlacement(const std::string& ipa) { return Lookup(std::begin(kPlacements), std::end(kPlacements), ipa); }

bool IsVowel(const std::string& ipa) { return VowelPlacement(ipa) != 0; }
bool IsConsonant(const std::string& ipa) { return ConsonantShape(ipa) != 0; }

std::vector<Key> CueKeys(const std::vector<Phone>& phones) {
  std::vector<Key> keys;
  const int n = static_cast<int>(phones.size());
  // Next cued phone after i (skipping uncued sounds such as [h]), stopping at a
  // pause; -1 when none.
  auto next_cued = [&](int i) {
    for (int k = i + 1; k < n; ++k) {
      if (phones[k].ipa.empty()) return -1;
      if (IsVowel(phones[k].ipa) || IsConsonant(phones[k].ipa)) return k;
    }
    return -1;
  };
  int i = 0;
  while (i < n) {
    const Phone& p = phones[i];
    if (IsConsonant(p.ipa)) {
      Key k;
      k.shape = ConsonantShape(p.ipa);
      k.consonant_phone = i;
      k.a1_s = p.start_s;
      const int v = next_cued(i);
      if (v >= 0 && IsVowel(phones[v].ipa)) {
        k.type = KeyType::kCV;
        k.placement = VowelPlacement(phones[v].ipa);
        k.vowel_phone = v;
        k.end_s = phones[v].end_s;
        i = v + 1;
      } else {
        k.type = KeyType::kConsonantAlone;
        k.placement = 1;  // side
        k.end_s = p.end_s;
        ++i;
      }
      keys.push_back(k);
    } else if (IsVowel(p.ipa)) {
      Key k;
      k.type = KeyType::kVowelAlone;
      k.placement = VowelPlacement(p.ipa);
      k.shape = 5;
      k.vowel_phone = i;
      k.a1_s = p.start_s;
      k.end_s = p.end_s;
      keys.push_back(k);
      ++i;
    } else {
      ++i;  // pause or uncued sound
    }
  }
  const double start = phones.empty() ? 0.0 : phones.front().start_s;
  const double end = phones.empty() ? 0.0 : phones.back().end_s;
  if (keys.empty()) return {RestKey(start, end)};
  std::vector<Key> out;
  out.reserve(keys.size() + 2);
  out.push_back(RestKey(start, keys.front().a1_s));
  out.insert(out.end(), keys.begin(), keys.end());
  out.push_back(RestKey(keys.back().end_s, end));
  return out;
}

const char* KeyTypeText(KeyType type) {
  switch (type) {
    case KeyType::kCV:
      return "CV";
    case KeyType::kVowelAlone:
      return "V";
    case KeyType::kConsonantAlone:
      return "C";
    case KeyType::kRest:
      break;
  }
  return "rest";
}

bool ParseKeyTypeText(const std::string& text, KeyType* type) {
  for (KeyType t : {KeyType::kRest, KeyType::kCV, KeyType::kConsonantAlone, KeyType::kVowelAlone}) {
    if (text == KeyTypeText(t)) {
      *type = t;
      return true;
    }
  }
  return false;
}

}  // namespace csw
