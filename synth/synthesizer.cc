#include "synth/synthesizer.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

#include "core/error.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "synth/cueing.h"

namespace csw::dict {

namespace {

bool IsPause(const std::string& ipa) { return ipa.empty() || ipa == "_"; }

// The phones on the output clock as the face concatenation wants them:
// contiguous over [0, duration], pauses "_", successive pauses merged.
std::vector<PhoneTarget> FacePhones(const std::vector<Phone>& phones, double duration_s) {
  std::vector<PhoneTarget> out;
  auto add = [&](const std::string& phone, double start, double end) {
    if (end <= start) return;
    if (!out.empty()) start = out.back().end_s;  // contiguous
    if (end <= start) return;
    if (!out.empty() && phone == "_" && out.back().phone == "_") {
      out.back().end_s = end;
      return;
    }
    out.push_back({phone, start, end});
  };
  if (!phones.empty() && phones.front().start_s > 0) add("_", 0, phones.front().start_s);
  for (const Phone& p : phones) add(IsPause(p.ipa) ? "_" : p.ipa, p.start_s, p.end_s);
  if (!out.empty() && out.back().end_s < duration_s) add("_", out.back().end_s, duration_s);
  if (!out.empty()) out.back().end_s = std::max(out.back().end_s, duration_s);
  return out;
}

double OutputRate(const Dictionary& d, double given) {
  if (given > 0) return given;
  if (std::isfinite(d.corpus_rate_hz) && d.corpus_rate_hz > 0) return d.corpus_rate_hz;
  return d.dikeys.front().rate_hz;
}

}  // namespace

std::string SynthesisOptions::Check() const {
  if (const std::string why = plan.Check(); !why.empty()) return why;
  if (!(concat.rate_hz >= 0) || !std::isfinite(concat.rate_hz))
    return "the output frame rate must be >= 0 (0 = the dictionary's)";
  ConcatOptions c = concat;
  if (c.rate_hz == 0) c.rate_hz = 100;  // checked with a stand-in rate
  if (!(max_jump_factor >= 0) || !std::isfinite(max_jump_factor))
    return "max_jump_factor must be >= 0 (0 = no speed limit)";
  if (speed_limit_passes < 0) return "speed_limit_passes must be >= 0";
  if (face_fragments) {
    FragmentOptions f = fragments;
    f.rate_hz = 100;  // the output rate is the concatenation's
    if (const std::string why = f.Check(); !why.empty()) return why;
  }
  return c.Check();
}

Synthesis Synthesize(const Utterance& utterance, const Dictionary& dictionary, const FaceModel& face,
                     const HandModel& hand, const SynthesisOptions& options, const std::string& name) {
  const std::string where = "synthesis of '" + name + "'";
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(where + ": " + why);
  if (utterance.phones.empty()) throw InvalidInput(where + ": the text gave no phone");
  if (dictionary.dikeys.empty()) throw InvalidInput(where + ": the dictionary has no dikey");
  if (dictionary.hand_parameter_names.size() != static_cast<size_t>(hand.num_parameters()) ||
      (!dictionary.diphones.empty() &&
       dictionary.face_parameter_names.size() != static_cast<size_t>(face.num_parameters()))) {
    throw InvalidInput(where + ": the dictionary has " + std::to_string(dictionary.hand_parameter_names.size()) +
                       " hand and " + std::to_string(dictionary.face_parameter_names.size()) +
                       " face parameters, the models " + std::to_string(hand.num_parameters()) + " and " +
                       std::to_string(face.num_parameters()));
  }
  Synthesis s;
  const std::vector<Key> keys = CueKeys(utterance.phones);
  const bool any_key = std::any_of(keys.begin(), keys.end(), [](const Key& k) { return k.type != KeyType::kRest; });
  if (!any_key) throw InvalidInput(where + ": the text gives no key to cue ('" + utterance.text + "')");
  const double audio_s = std::max(utterance.duration_s(), utterance.audio.duration_s());
  s.plan = PlanKeys(keys, utterance.phones, audio_s, dictionary, options.plan);
  const double lead = s.plan.lead_in_s, duration = s.plan.duration_s;

  ConcatOptions concat = options.concat;
  concat.rate_hz = OutputRate(dictionary, options.concat.rate_hz);
  const double rate = concat.rate_hz;

  std::vector<KeyTarget> targets;
  for (const PlannedKey& k : s.plan.keys) {
    KeyTarget t;
    t.code = k.code;
    t.target_s = k.target_s;
    if (k.type != KeyType::kRest) {
      t.a1_s = k.a1_s;
      t.type = k.type;
    }
    targets.push_back(t);
  }
  s.hand = ConcatenateDikeys(dictionary, targets, duration, concat);

  s.phones = utterance.phones;
  for (Phone& p : s.phones) {
    p.start_s += lead;
    p.end_s += lead;
  }
  s.face_phones = FacePhones(s.phones, duration);
  const int64_t frames = s.hand.frames();
  if (!dictionary.diphones.empty() && s.face_phones.size() >= 2) {
    if (options.face_fragments) {
      FragmentOptions fo = options.fragments;
      fo.rate_hz = rate;
      s.fragments = ConcatenateFragments(dictionary, s.face_phones, duration, fo);
      s.face = ToFaceTrack(s.fragments, s.face_phones);
      for (const FragmentReport& f : s.fragments.fragments) {
        if (f.linear_fallback)
          s.warnings.push_back("face fragment '" + f.phones + "' (take '" + f.take +
                               "'): the RBF resampling strayed, resampled linearly");
      }
    } else {
      s.face = ConcatenateDiphones(dictionary, s.face_phones, duration, concat);
    }
  } else {
    s.face.rate_hz = rate;
    s.face.face_params = Eigen::MatrixXd::Zero(frames, face.num_parameters());
    s.warnings.push_back("the dictionary has no diphone: the face keeps its mean shape (build it with a phone tier)");
  }
  if (s.face.frames() != frames) {
    throw InvalidInput(where + ": the face track has " + std::to_string(s.face.frames()) + " frames, the hand " +
                       std::to_string(frames));
  }

  s.tracks.rate_hz = rate;
  s.tracks.face_params = s.face.face_params;
  s.tracks.head_pose = s.hand.head_pose;
  s.tracks.hand_params = s.hand.hand_params;
  s.tracks.forearm_in_head = s.hand.forearm_in_head;
  s.take = MarkersFromParameters(face, hand, s.tracks, name);
  s.take.first_frame = 1;
  const double corpus_rate = std::isfinite(dictionary.corpus_rate_hz) && dictionary.corpus_rate_hz > 0
                                 ? dictionary.corpus_rate_hz
                                 : dictionary.dikeys.front().rate_hz;
  if (options.max_jump_factor > 0 && std::isfinite(dictionary.corpus_max_jump_mm) &&
      dictionary.corpus_max_jump_mm > 0 && corpus_rate > 0) {
    s.speed_limit_mm = options.max_jump_factor * dictionary.corpus_max_jump_mm * corpus_rate / rate;
    s.speed_limit = LimitMarkerSpeed(face, hand, s.speed_limit_mm, options.speed_limit_passes, &s.tracks, &s.take);
    s.take.first_frame = 1;
    if (s.speed_limit.max_jump_after_mm > s.speed_limit_mm) {
      char line[200];
      std::snprintf(line, sizeof line,
                    "a marker still moves %.1f mm between two frames after the speed limit (%.1f mm): the tracks "
                    "jump next to a gap, or %d passes were not enough",
                    s.speed_limit.max_jump_after_mm, s.speed_limit_mm, options.speed_limit_passes);
      s.warnings.push_back(line);
    }
  }

  // Tiers.
  const double end_s = static_cast<double>(frames - 1) / rate;
  auto tier = [&](const std::string& tier_name, LabelTier::Kind kind) {
    LabelTier t;
    t.name = tier_name;
    t.kind = kind;
    t.start_s = 0;
    t.end_s = end_s;
    return t;
  };
  LabelTier words = tier("words", LabelTier::Kind::kInterval);
  for (const Word& w : utterance.words) words.labels.push_back({w.start_s + lead, w.end_s + lead, w.text});
  LabelTier phones = tier("phones", LabelTier::Kind::kInterval);
  for (const PhoneTarget& p : s.face_phones) phones.labels.push_back({p.start_s, std::min(p.end_s, end_s), p.phone});
  LabelTier key_tier = tier("keys", LabelTier::Kind::kPoint);
  LabelTier placement_tier = tier("placement_targets", LabelTier::Kind::kPoint);
  LabelTier expected = tier("expected_keys", LabelTier::Kind::kInterval);
  LabelTier gestures = tier("gestures", LabelTier::Kind::kInterval);
  for (size_t i = 0; i < s.plan.keys.size(); ++i) {
    const PlannedKey& k = s.plan.keys[i];
    const double t = std::min(k.target_s, end_s);
    key_tier.labels.push_back({t, t, k.code.Text()});
    // The placement arrives when the unit leaving the key reaches it (its
    // stored lag), else at the key's target.
    double tp = t;
    if (i < s.hand.keys.size() && std::isfinite(s.hand.keys[i].leaving_placement_lag_s)) {
      const double lo = i > 0 ? s.plan.keys[i - 1].target_s : 0.0;
      const double hi = i + 1 < s.plan.keys.size() ? s.plan.keys[i + 1].target_s : end_s;
      tp = std::clamp(k.target_s + s.hand.keys[i].leaving_placement_lag_s, lo + 0.6 * (k.target_s - lo),
                      k.target_s + 0.4 * (hi - k.target_s));
      tp = std::min(tp, end_s);
    }
    placement_tier.labels.push_back({tp, tp, k.code.Text()});
    if (i < keys.size() && keys[i].type != KeyType::kRest) {
      expected.labels.push_back({keys[i].a1_s + lead, std::min(keys[i].end_s + lead, end_s), k.code.Text()});
    }
    if (i > 0) {
      const double from = std::min(s.plan.keys[i - 1].target_s, end_s);
      const KeyReport& r = s.hand.keys[i - 1];
      if (t > from) gestures.labels.push_back({from, t, k.code.Text() + " " + FallbackLevelName(r.level)});
    }
  }
  s.take.tiers = {words, phones, expected, key_tier, placement_tier, gestures};

  // Audio: lead-in silence, the utterance, silence to the end of the take
  // (frames / rate, as long as its video).
  if (utterance.audio.rate_hz > 0 && !utterance.audio.samples.empty()) {
    s.audio.rate_hz = utterance.audio.rate_hz;
    s.audio.channels = 1;
    const int channels = std::max(1, utterance.audio.channels);
    const auto lead_samples = static_cast<size_t>(std::llround(lead * s.audio.rate_hz));
    const auto total = static_cast<size_t>(std::llround(s.take.duration_s() * s.audio.rate_hz));
    s.audio.samples.assign(lead_samples, 0.0f);
    for (int64_t f = 0; f < utterance.audio.frames(); ++f)
      s.audio.samples.push_back(utterance.audio.samples[static_cast<size_t>(f * channels)]);
    if (s.audio.samples.size() < total) s.audio.samples.resize(total, 0.0f);
  }
  for (const std::string& w : utterance.warnings) s.warnings.push_back(w);
  return s;
}

int MatchSpeakingRate(const std::string& text, double mean_phone_s, const PhonetiseOptions& base) {
  if (!(mean_phone_s > 0) || !std::isfinite(mean_phone_s)) return 150;
  PhonetiseOptions o = base;
  o.synthesize_audio = false;
  double rate = 150;
  for (int step = 0; step < 2; ++step) {
    o.rate_wpm = static_cast<int>(std::lround(rate));
    const double m = MeanPhoneDuration(Phonetise(text, o).phones);
    if (!(m > 0) || !std::isfinite(m)) break;
    rate = std::clamp(rate * m / mean_phone_s, 80.0, 450.0);
  }
  return static_cast<int>(std::lround(rate));
}

}  // namespace csw::dict
