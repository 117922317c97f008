#include "synth/phonetics.h"

#include <dlfcn.h>
#include <espeak-ng/speak_lib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <sstream>
#include <string_view>
#include <utility>

#include "core/error.h"
#include "synth/cueing.h"

namespace csw {
namespace {

// espeak-ng phoneme name -> IPA (space-separated when several phonemes).
// Checked against espeak-ng 1.51's own IPA output (espeakINITIALIZE_PHONEME_IPA on
// "[[name]]" input) and against French phonology; docs/phonetics.md lists it with
// the reasons for the few places where it departs from espeak-ng's IPA.
struct EspeakEntry {
  const char* espeak;
  const char* ipa;
};

constexpr EspeakEntry kEspeakTable[] = {
    // French vowels (phoneme table "fr").
    {"a", "a"},
    {"a-", "a"},
    {"a:", "a"},
    {"a#", "a"},
    {"e", "e"},
    {"e-", "e"},
    {"E", "ɛ"},
    {"E-", "ɛ"},
    {"i", "i"},
    {"o", "o"},
    {"O", "ɔ"},
    {"u", "u"},
    {"u:", "u"},
    {"y", "y"},
    {"y-", "y"},
    {"j.", "y"},
    {"Y", "ø"},
    {"W", "œ"},
    {"W2", "œ"},
    {"@", "ə"},
    {"@-", "ə"},
    {"A~", "ɑ̃"},
    {"E~", "ɛ̃"},
    {"O~", "ɔ̃"},
    {"W~", "œ̃"},
    // French consonants and semi-vowels (liaison variants "z2", "t2", "n2", "r2",
    // "p2" are pronounced when espeak-ng emits them).
    {"p", "p"},
    {"p2", "p"},
    {"b", "b"},
    {"t", "t"},
    {"t2", "t"},
    {"t3", "t"},
    {"d", "d"},
    {"k", "k"},
    {"g", "ɡ"},
    {"f", "f"},
    {"v", "v"},
    {"s", "s"},
    {"z", "z"},
    {"z2", "z"},
    {"z3", "s"},
    {"S", "ʃ"},
    {"Z", "ʒ"},
    {"m", "m"},
    {"n", "n"},
    {"n2", "n"},
    {"n^", "ɲ"},
    {"N", "ŋ"},
    {"l", "l"},
    {"l/", "l"},
    {"l/2", "l"},
    {"r", "ʁ"},
    {"r/", "ʁ"},
    {"r/2", "ʁ"},
    {"r2", "ʁ"},
    {"R", "ʁ"},
    {"j", "j"},
    {"j/", "j"},
    {"w", "w"},
    {"w/", "w"},
    {"dZ", "d ʒ"},
    {"tS", "t ʃ"},
    {"ts", "t s"},
    // Foreign phonemes reached through espeak-ng's language switches, e.g.
    // "(en)" for "week-end", "parking": nearest French phonemes.
    {"I", "i"},
    {"I2", "i"},
    {"I#", "i"},
    {"i:", "i"},
    {"A:", "a"},
    {"A@", "a"},
    {"aa", "a"},
    {"a2", "a"},
    {"V", "œ"},
    {"0", "ɔ"},
    {"O:", "ɔ"},
    {"O@", "ɔ"},
    {"o@", "ɔ"},
    {"U", "u"},
    {"3", "ə"},
    {"3:", "œ"},
    {"e:", "e"},
    {"e@", "ɛ"},
    {"i@", "i"},
    {"U@", "u"},
    {"oU", "o"},
    {"aI", "a j"},
    {"eI", "e j"},
    {"OI", "ɔ j"},
    {"aU", "a w"},
    {"@L", "ə l"},
    {"r-", "ʁ"},
    {"T", "s"},
    {"D", "z"},
    {"x", "ʁ"},
    {"h", "h"},
    {"?", "ʔ"},
};

std::string_view Trimmed(std::string_view s) {
  while (!s.empty() && s.back() == ' ') s.remove_suffix(1);
  return s;
}

const EspeakEntry* FindEntry(const std::string& name) {
  for (const EspeakEntry& e : kEspeakTable)
    if (name == e.espeak) return &e;
  return nullptr;
}

std::vector<std::string> SplitSpaces(const std::string& s) {
  std::vector<std::string> out;
  std::istringstream in(s);
  std::string part;
  while (in >> part) out.push_back(part);
  return out;
}

// Byte offset of the code point with 0-based index `index` in UTF-8 text
// (text.size() when past the end). Continuation bytes do not start a code point.
size_t Utf8Offset(const std::string& text, int64_t index) {
  int64_t seen = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const auto c = static_cast<unsigned char>(text[i]);
    if ((c & 0xC0) == 0x80) continue;
    if (seen == index) return i;
    ++seen;
  }
  return text.size();
}

struct RawEvent {
  espeak_EVENT_TYPE type;
  int text_position;
  int length;
  int64_t sample;
  std::string name;
};

// libespeak-ng is loaded with dlopen on first use, not linked: it pulls in
// ~25 shared libraries (PulseAudio, ALSA, X11, D-Bus, ...) that every csw
// command would otherwise load at start-up, although only simulation and
// synthesis phonetise. The declarations still come from its header.
struct EspeakApi {
  decltype(&::espeak_Initialize) Initialize = nullptr;
  decltype(&::espeak_SetSynthCallback) SetSynthCallback = nullptr;
  decltype(&::espeak_SetVoiceByName) SetVoiceByName = nullptr;
  decltype(&::espeak_SetParameter) SetParameter = nullptr;
  decltype(&::espeak_Synth) Synth = nullptr;
  decltype(&::espeak_Synchronize) Synchronize = nullptr;
};

constexpr const char* kEspeakLibrary = "libespeak-ng.so.1";

template <typename F>
void LoadSymbol(void* handle, const char* name, F* out) {
  void* sym = dlsym(handle, name);
  if (sym == nullptr) throw Error(std::string("espeak-ng: ") + kEspeakLibrary + " has no symbol " + name);
  *out = reinterpret_cast<F>(sym);
}

EspeakApi LoadEspeak() {
  void* handle = dlopen(kEspeakLibrary, RTLD_NOW | RTLD_LOCAL);
  if (handle == nullptr) {
    const char* why = dlerror();
    throw Error(std::string("espeak-ng: cannot load ") + kEspeakLibrary + " (" + (why ? why : "unknown error") +
                "); install the Debian package libespeak-ng1");
  }
  // Never closed: espeak-ng keeps global state for the life of the process.
  EspeakApi api;
  LoadSymbol(handle, "espeak_Initialize", &api.Initialize);
  LoadSymbol(handle, "espeak_SetSynthCallback", &api.SetSynthCallback);
  LoadSymbol(handle, "espeak_SetVoiceByName", &api.SetVoiceByName);
  LoadSymbol(handle, "espeak_SetParameter", &api.SetParameter);
  LoadSymbol(handle, "espeak_Synth", &api.Synth);
  LoadSymbol(handle, "espeak_Synchronize", &api.Synchronize);
  return api;
}

// Global espeak-ng session state (espeak-ng itself is global).
struct EspeakSession {
  std::mutex mutex;
  bool initialised = false;
  EspeakApi api;
  int rate_hz = 0;
  std::vector<short> samples;
  std::vector<RawEvent> events;
};

EspeakSession& Session() {
  static EspeakSession session;
  return session;
}

int SynthCallback(short* wav, int count, espeak_EVENT* events) {
  EspeakSession& s = Session();
  if (wav != nullptr && count > 0) s.samples.insert(s.samples.end(), wav, wav + count);
  for (espeak_EVENT* e = events; e != nullptr && e->type != espeakEVENT_LIST_TERMINATED; ++e) {
    if (e->type != espeakEVENT_PHONEME && e->type != espeakEVENT_WORD) continue;
    RawEvent r;
    r.type = e->type;
    r.text_position = e->text_position;
    r.length = e->length;
    // espeak-ng 1.51 fills `sample` with the absolute sample index in synchronous
    // mode; `audio_position` is the same instant in whole milliseconds. Use the
    // precise one when both agree, else fall back to milliseconds.
    const double from_ms = e->audio_position * 1e-3 * s.rate_hz;
    r.sample =
        std::abs(e->sample - from_ms) <= 0.003 * s.rate_hz ? e->sample : static_cast<int64_t>(std::llround(from_ms));
    if (e->type == espeakEVENT_PHONEME) {
      char name[9] = {0};
      std::memcpy(name, e->id.string, 8);
      r.name = name;
    }
    s.events.push_back(std::move(r));
  }
  return 0;
}

void EnsureInitialised(EspeakSession& s) {
  if (s.initialised) return;
  s.api = LoadEspeak();
  const int rate = s.api.Initialize(AUDIO_OUTPUT_SYNCHRONOUS, 0, nullptr,
                                    espeakINITIALIZE_PHONEME_EVENTS | espeakINITIALIZE_DONT_EXIT);
  if (rate <= 0) throw Error("espeak-ng: cannot initialise (espeak-ng-data not found?)");
  s.api.SetSynthCallback(SynthCallback);
  s.rate_hz = rate;
  s.initialised = true;
}

}  // namespace

std::string PhonetiseOptions::Check() const {
  if (voice.empty()) return "voice is empty";
  if (voice.find_first_of(" \t\n/\\") != std::string::npos) return "voice '" + voice + "' is not a voice name";
  if (rate_wpm < 80 || rate_wpm > 450) return "rate_wpm " + std::to_string(rate_wpm) + " is outside 80-450";
  if (pitch < 0 || pitch > 99) return "pitch " + std::to_string(pitch) + " is outside 0-99";
  return "";
}

std::vector<std::pair<std::string, std::string>> EspeakIpaTable() {
  std::vector<std::pair<std::string, std::string>> out;
  for (const EspeakEntry& e : kEspeakTable) out.emplace_back(e.espeak, e.ipa);
  return out;
}

bool IsEspeakPause(const std::string& espeak_name) { return !espeak_name.empty() && espeak_name[0] == '_'; }

bool IsEspeakLinking(const std::string& espeak_name) { return espeak_name == ";"; }

std::string EspeakToIpa(const std::string& espeak_name) {
  if (IsEspeakPause(espeak_name)) return "";
  const EspeakEntry* e = FindEntry(espeak_name);
  return e ? e->ipa : "";
}

std::vector<std::string> EspeakToIpaPhones(const std::string& espeak_name) {
  return SplitSpaces(EspeakToIpa(espeak_name));
}

void ApplyIpaExceptions(std::vector<Phone>& phones) {
  for (size_t i = 0; i + 1 < phones.size(); ++i) {
    Phone& p = phones[i];
    const Phone& next = phones[i + 1];
    if (p.ipa == "y" && p.word >= 0 && next.word == p.word && IsVowel(next.ipa)) p.ipa = "ɥ";
  }
}

Utterance Phonetise(const std::string& text, const PhonetiseOptions& options) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput("Phonetise: " + why);
  EspeakSession& s = Session();
  std::lock_guard<std::mutex> lock(s.mutex);
  EnsureInitialised(s);
  if (s.api.SetVoiceByName(options.voice.c_str()) != EE_OK)
    throw Error("espeak-ng: voice '" + options.voice + "' is not available");
  s.api.SetParameter(espeakRATE, options.rate_wpm, 0);
  s.api.SetParameter(espeakPITCH, options.pitch, 0);
  s.samples.clear();
  s.events.clear();
  // Text up to the first NUL (espeak-ng reads a C string).
  const std::string input(text.c_str());
  const espeak_ERROR err =
      s.api.Synth(input.c_str(), input.size() + 1, 0, POS_CHARACTER, 0, espeakCHARS_UTF8, nullptr, nullptr);
  if (err != EE_OK) throw Error("espeak-ng: synthesis failed (error " + std::to_string(err) + ")");
  s.api.Synchronize();

  Utterance u;
  u.text = text;
  const double rate = s.rate_hz;
  const auto total = static_cast<int64_t>(s.samples.size());

  // Phoneme events in order with the word each belongs to; language switches
  // such as "(en)" are events without sound and are skipped.
  struct Seg {
    std::string name;
    int64_t start;
    int raw_word;  // index into word_events, -1 before the first word
  };
  std::vector<Seg> segs;
  std::vector<const RawEvent*> word_events;
  for (const RawEvent& e : s.events) {
    if (e.type == espeakEVENT_WORD) {
      word_events.push_back(&e);
      continue;
    }
    if (e.name.empty() || e.name[0] == '(') continue;
    segs.push_back({e.name, std::clamp<int64_t>(e.sample, 0, total), static_cast<int>(word_events.size()) - 1});
  }

  std::vector<int> word_map(word_events.size(), -1);  // raw word -> Utterance::words index
  auto add_phone = [&](std::string ipa, const std::string& name, int64_t a, int64_t b, int raw_word) {
    if (b <= a) return;
    Phone p;
    p.ipa = std::move(ipa);
    p.espeak = name;
    p.start_s = a / rate;
    p.end_s = b / rate;
    if (p.ipa.empty()) {  // pause: merge with a preceding pause
      if (!u.phones.empty() && u.phones.back().ipa.empty()) {
        u.phones.back().end_s = p.end_s;
        return;
      }
    } else if (raw_word >= 0) {
      if (word_map[raw_word] < 0) {
        const RawEvent& we = *word_events[raw_word];
        const size_t from = Utf8Offset(text, std::max(0, we.text_position - 1));
        const size_t to = Utf8Offset(text, std::max(0, we.text_position - 1) + std::max(0, we.length));
        Word w;
        w.text = std::string(Trimmed(std::string_view(text).substr(from, to - std::min(from, to))));
        w.start_s = p.start_s;
        word_map[raw_word] = static_cast<int>(u.words.size());
        u.words.push_back(std::move(w));
      }
      p.word = word_map[raw_word];
      u.words[p.word].end_s = p.end_s;
    }
    u.phones.push_back(std::move(p));
  };

  if (!segs.empty() && segs.front().start > 0) add_phone("", "_", 0, segs.front().start, -1);
  for (size_t i = 0; i < segs.size(); ++i) {
    const Seg& g = segs[i];
    const int64_t end = i + 1 < segs.size() ? std::max(g.start, segs[i + 1].start) : total;
    if (IsEspeakPause(g.name)) {
      add_phone("", g.name, g.start, end, -1);
      continue;
    }
    if (IsEspeakLinking(g.name)) {
      // Not a phoneme (phonetics.h): kept as its own phone ";" with espeak-ng's
      // timing, in neither LfPC table, so transparent to CueKeys; no warning.
      add_phone(g.name, g.name, g.start, end, g.raw_word);
      continue;
    }
    std::vector<std::string> ipa = EspeakToIpaPhones(g.name);
    if (ipa.empty()) {
      // Unknown name: try without espeak-ng's variant decorations ("t#" -> "t").
      std::string base = g.name;
      while (base.size() > 1 && ipa.empty() && std::strchr("-/#.:;0123456789", base.back()) != nullptr) {
        base.pop_back();
        ipa = EspeakToIpaPhones(base);
      }
      if (ipa.empty()) {
        u.warnings.push_back("espeak-ng phoneme '" + g.name + "' has no IPA mapping; kept uncued");
        ipa = {g.name};
      } else {
        u.warnings.push_back("espeak-ng phoneme '" + g.name + "' mapped as '" + base + "'");
      }
    }
    // Several phonemes for one espeak-ng phoneme share its duration equally.
    const auto n = static_cast<int64_t>(ipa.size());
    for (int64_t k = 0; k < n; ++k)
      add_phone(ipa[k], g.name, g.start + (end - g.start) * k / n, g.start + (end - g.start) * (k + 1) / n, g.raw_word);
  }
  if (u.phones.empty() && total > 0) add_phone("", "_", 0, total, -1);
  ApplyIpaExceptions(u.phones);

  u.audio.rate_hz = rate;
  u.audio.channels = 1;
  if (options.synthesize_audio) {
    u.audio.samples.resize(s.samples.size());
    for (size_t i = 0; i < s.samples.size(); ++i) u.audio.samples[i] = s.samples[i] / 32768.0f;
  }
  s.samples.clear();
  s.events.clear();
  return u;
}

std::vector<LabelTier> UtteranceTiers(const Utterance& utterance) {
  const double end = std::max(utterance.duration_s(), utterance.audio.duration_s());
  LabelTier words;
  words.name = "words";
  words.kind = LabelTier::Kind::kInterval;
  words.start_s = 0.0;
  words.end_s = end;
  double t = 0.0;
  for (const Word& w : utterance.words) {
    if (w.end_s <= w.start_s || w.start_s < t) continue;
    if (w.start_s > t) words.labels.push_back({t, w.start_s, ""});
    words.labels.push_back({w.start_s, w.end_s, w.text});
    t = w.end_s;
  }
  if (end > t) words.labels.push_back({t, end, ""});

  LabelTier phones;
  phones.name = "phones";
  phones.kind = LabelTier::Kind::kInterval;
  phones.start_s = 0.0;
  phones.end_s = end;
  t = 0.0;
  for (const Phone& p : utterance.phones) {
    if (p.end_s <= p.start_s || p.start_s < t) continue;
    if (p.start_s > t) phones.labels.push_back({t, p.start_s, ""});
    phones.labels.push_back({p.start_s, p.end_s, p.ipa});
    t = p.end_s;
  }
  if (end > t) phones.labels.push_back({t, end, ""});
  return {words, phones};
}

}  // namespace csw
