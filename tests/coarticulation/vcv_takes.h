#pragma once
// Virtual-cuer VCV takes for the Öhman tests: a take of isolated vowels a, i,
// u and one take per vowel context V with V C V items for a handful of
// consonants, each item between pauses; phones built directly (no espeak-ng),
// durations drawn from the seed (vowels 0.10-0.14 s, consonants 0.08-0.12 s,
// pauses 0.30-0.40 s). No hand, no audio.
#include <random>
#include <string>
#include <vector>

#include "datasets/virtual_cuer.h"
#include "tests/testing/testing.h"

namespace csw::testing {

inline std::vector<std::string> OhmanTestConsonants() {
  if (kSanitized) return {"p", "f", "s", "ʃ"};
  return {"p", "f", "t", "s", "ʃ", "k", "l", "ʁ"};
}

inline Utterance VcvUtterance(const std::vector<std::pair<std::vector<std::string>, bool>>& items,
                              std::mt19937_64& rng) {
  std::uniform_real_distribution<double> vowel(0.10, 0.14), cons(0.08, 0.12), pause(0.30, 0.40);
  Utterance u;
  double t = 0;
  auto push = [&](const std::string& ipa, double d) {
    Phone p;
    p.ipa = ipa;
    p.start_s = t;
    p.end_s = t + d;
    u.phones.push_back(p);
    t += d;
  };
  for (const auto& [phones, unused] : items) {
    push("", pause(rng));
    for (const std::string& ph : phones) {
      const bool is_vowel = ph == "a" || ph == "i" || ph == "u";
      push(ph, is_vowel ? vowel(rng) : cons(rng));
    }
  }
  push("", pause(rng));
  return u;
}

// The takes: "vowels", then "vcv_a", "vcv_i", "vcv_u".
inline std::vector<SimulationResult> SimulateVcvTakes(uint64_t seed, const std::vector<std::string>& consonants) {
  SimulateOptions o;
  o.kind = CorpusKind::kVisemes;
  o.seed = seed;
  o.audio = false;
  const VirtualCuer cuer(o);
  std::mt19937_64 rng(seed * 7919 + 17);
  std::vector<SimulationResult> out;
  out.push_back(
      cuer.SimulateUtterance("vowels", VcvUtterance({{{"a"}, true}, {{"i"}, true}, {{"u"}, true}}, rng), false));
  for (const char* v : {"a", "i", "u"}) {
    std::vector<std::pair<std::vector<std::string>, bool>> items;
    for (const std::string& c : consonants) items.push_back({{v, c, v}, true});
    out.push_back(cuer.SimulateUtterance(std::string("vcv_") + v, VcvUtterance(items, rng), false));
  }
  return out;
}

}  // namespace csw::testing
