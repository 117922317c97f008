// libFuzzer target for the phone-symbol conversion of synth/phone_symbols.h.
// The first byte picks the symbols (auto, IPA, X-SAMPA, SPPAS); the rest is
// split at '\n' into the labels of a contiguous interval tier (0.1 s each).
// Invariants: each symbol reads (ReadPhoneSymbol) without crashing; the tier
// maps and cues (CuePhoneTier) or throws csw::Error; a cued tier's labels are
// key codes that ReadExpectedKeyTier (core/labels.h) reads back as the cued
// keys in order (rests of zero length are left out), and mapped phones are
// contiguous.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/labels.h"
#include "synth/phone_symbols.h"

namespace {

// Aborts (a finding) naming the broken invariant's line.
#define CHECK(ok)                                                                     \
  do {                                                                                \
    if (!(ok)) {                                                                      \
      std::fprintf(stderr, "%s:%d: invariant broken: %s\n", __FILE__, __LINE__, #ok); \
      std::abort();                                                                   \
    }                                                                                 \
  } while (0)

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  static const csw::PhoneSymbols kSymbols[] = {csw::PhoneSymbols::kAuto, csw::PhoneSymbols::kIpa,
                                               csw::PhoneSymbols::kXsampa, csw::PhoneSymbols::kSppas};
  const csw::PhoneSymbols symbols = kSymbols[data[0] % 4];
  const std::string in(reinterpret_cast<const char*>(data) + 1, size - 1);
  csw::LabelTier tier;
  tier.name = "phones";
  tier.kind = csw::LabelTier::Kind::kInterval;
  std::vector<std::string> texts;
  size_t start = 0;
  while (start <= in.size() && texts.size() < 200) {
    size_t end = in.find('\n', start);
    if (end == std::string::npos) end = in.size();
    texts.push_back(in.substr(start, end - start));
    start = end + 1;
  }
  for (size_t i = 0; i < texts.size(); ++i)
    tier.labels.push_back({0.1 * static_cast<double>(i), 0.1 * static_cast<double>(i + 1), texts[i]});
  tier.end_s = 0.1 * static_cast<double>(texts.size());
  for (const std::string& t : texts) {
    const csw::SymbolReading r =
        csw::ReadPhoneSymbol(t, symbols == csw::PhoneSymbols::kAuto ? csw::PhoneSymbols::kIpa : symbols);
    if (r.kind == csw::SymbolReading::Kind::kPhonemes) CHECK(!r.ipa.empty() && r.ipa.size() <= 2);
  }
  csw::DetectPhoneSymbols(texts);
  try {
    const csw::CuedTier cued = csw::CuePhoneTier(tier, symbols, "fuzz");
    CHECK(cued.mapped.symbols != csw::PhoneSymbols::kAuto);
    for (size_t i = 1; i < cued.mapped.phones.size(); ++i)
      CHECK(cued.mapped.phones[i - 1].end_s <= cued.mapped.phones[i].start_s + 1e-9);
    // The tier's keys read back are the cued keys, rests of zero length aside.
    std::vector<std::string> want, got;
    for (const csw::Key& k : cued.keys)
      if (k.type != csw::KeyType::kRest) want.push_back(k.Code());
    for (const csw::ExpectedKey& k : csw::ReadExpectedKeyTier(cued.tier, "fuzz"))
      if (!k.code.IsRest()) got.push_back(k.code.Text());
    CHECK(want == got);
  } catch (const csw::Error&) {
  }
  return 0;
}
