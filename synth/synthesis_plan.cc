#include "synth/synthesis_plan.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <set>
#include <utility>

#include "core/error.h"

namespace csw::dict {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double Median(std::vector<double> v) {
  if (v.empty()) return kNaN;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

std::string SuccessionKey(const KeyCode& a, const KeyCode& b) { return SuccessionCode(a, b); }

}  // namespace

const char* PhasingRuleName(PhasingRule rule) { return rule == PhasingRule::kGlobal ? "global" : "dikey"; }

bool ParsePhasingRule(const std::string& name, PhasingRule* rule) {
  if (name == "global") {
    *rule = PhasingRule::kGlobal;
  } else if (name == "dikey") {
    *rule = PhasingRule::kPerDikey;
  } else {
    return false;
  }
  return true;
}

std::string PlanOptions::Check() const {
  if (!(min_interval_s > 0 && min_interval_s < 1)) return "min_interval_s must be in (0, 1) s";
  if (!(default_rest_s > 0 && default_rest_s < 10)) return "default_rest_s must be in (0, 10) s";
  if (!(shrinkage_units >= 0 && shrinkage_units < 1e6)) return "shrinkage_units must be >= 0";
  if (!(min_slot_fraction >= 0 && min_slot_fraction <= 1)) return "min_slot_fraction must be in [0, 1]";
  return "";
}

double MeanPhoneDuration(const std::vector<Phone>& phones) {
  double sum = 0;
  int n = 0;
  for (const Phone& p : phones) {
    if (p.ipa.empty() || p.ipa == "_" || p.ipa == ";") continue;
    sum += p.end_s - p.start_s;
    ++n;
  }
  return n ? sum / n : kNaN;
}

double MeanPhoneDuration(const Dictionary& dictionary) {
  // Each phone interval once: (take, start) identifies it.
  std::set<std::pair<std::string, double>> seen;
  double sum = 0;
  int n = 0;
  auto add = [&](const std::string& take, const std::string& phone, double start, double end) {
    if (phone.empty() || phone == "_" || phone == ";") return;
    if (!seen.insert({take, start}).second) return;
    sum += end - start;
    ++n;
  };
  for (const DiphoneUnit& u : dictionary.diphones) {
    add(u.take, u.phone1, u.phone1_start_s, u.phone1_end_s);
    add(u.take, u.phone2, u.phone2_start_s, u.phone2_end_s);
  }
  return n ? sum / n : kNaN;
}

SynthesisPlan PlanKeys(const std::vector<Key>& keys, const std::vector<Phone>& phones, double audio_duration_s,
                       const Dictionary& dictionary, const PlanOptions& options) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput("synthesis plan: " + why);
  if (!std::isfinite(audio_duration_s) || audio_duration_s <= 0) {
    throw InvalidInput("synthesis plan: the audio duration must be positive");
  }
  const int np = static_cast<int>(phones.size());
  auto phone = [&](int index, const char* what, size_t k) -> const Phone& {
    if (index < 0 || index >= np) {
      throw InvalidInput("synthesis plan: key " + std::to_string(k + 1) + ": " + what + " phone index " +
                         std::to_string(index) + " outside the " + std::to_string(np) + " phones");
    }
    const Phone& p = phones[static_cast<size_t>(index)];
    if (!std::isfinite(p.start_s) || !std::isfinite(p.end_s)) {
      throw InvalidInput("synthesis plan: phone " + std::to_string(index + 1) + " has a time that is not finite");
    }
    return p;
  };

  // Dictionary statistics: mean phasing per succession and per arriving key
  // code, each for one key type (A1 differs between types, and shape 5 at a
  // vowel placement may be a lone vowel or a CV key of [m t f]), and per key
  // type. Units of unknown type (dictionaries before the types) pool as "?".
  using Sum = std::pair<double, int>;
  std::map<std::string, Sum> by_succession;
  std::map<std::string, Sum> by_arriving;
  std::map<std::string, Sum> by_type;
  std::vector<double> leave_rest, reach_rest, all_durations;
  std::map<std::string, std::vector<double>> durations;
  auto add = [](Sum& s, double v) {
    s.first += v;
    ++s.second;
  };
  for (const DikeyUnit& u : dictionary.dikeys) {
    durations[SuccessionKey(u.from, u.to)].push_back(u.duration_s());
    all_durations.push_back(u.duration_s());
    if (u.from.IsRest() && !u.to.IsRest()) leave_rest.push_back(u.duration_s());
    if (u.to.IsRest() && !u.from.IsRest()) reach_rest.push_back(u.duration_s());
    if (!std::isfinite(u.phasing_s) || u.to.IsRest()) continue;
    const std::string tag = std::string("|") + (u.to_type ? KeyTypeText(*u.to_type) : "?");
    add(by_succession[SuccessionKey(u.from, u.to) + tag], u.phasing_s);
    add(by_arriving[u.to.Text() + tag], u.phasing_s);
    if (u.to_type) add(by_type[tag], u.phasing_s);
  }
  const double leave = leave_rest.empty() ? options.default_rest_s : Median(leave_rest);
  const double reach = reach_rest.empty() ? options.default_rest_s : Median(reach_rest);

  SynthesisPlan plan;
  std::vector<PlannedKey> cued;
  KeyCode previous;  // rest
  for (size_t k = 0; k < keys.size(); ++k) {
    const Key& key = keys[k];
    if (key.type == KeyType::kRest) continue;
    PlannedKey p;
    p.code = KeyCode{key.placement, key.shape};
    p.type = key.type;
    p.a1_s = key.a1_s;
    if (!std::isfinite(p.a1_s)) throw InvalidInput("synthesis plan: key " + std::to_string(k + 1) + ": A1 not finite");
    double global = 0;
    switch (key.type) {
      case KeyType::kCV: {
        const Phone& c = phone(key.consonant_phone, "consonant", k);
        global = 0.5 * (c.start_s + c.end_s);
        break;
      }
      case KeyType::kVowelAlone:
        global = phone(key.vowel_phone, "vowel", k).start_s;
        break;
      case KeyType::kConsonantAlone:
        global = phone(key.consonant_phone, "consonant", k).start_s;
        break;
      case KeyType::kRest:
        break;
    }
    p.target_s = global;
    p.source = "global";
    if (options.rule == PhasingRule::kPerDikey) {
      // This key's type first, then units of unknown type, then the type's mean.
      for (const std::string& tag : {std::string("|") + KeyTypeText(key.type), std::string("|?")}) {
        const auto s = by_succession.find(SuccessionKey(previous, p.code) + tag);
        const auto a = by_arriving.find(p.code.Text() + tag);
        if (s != by_succession.end()) {
          const double k = a != by_arriving.end() ? options.shrinkage_units : 0.0;
          const double code_mean = a != by_arriving.end() ? a->second.first / a->second.second : 0.0;
          p.target_s = p.a1_s + (s->second.first + k * code_mean) / (s->second.second + k);
          p.source = "dikey";
        } else if (a != by_arriving.end()) {
          p.target_s = p.a1_s + a->second.first / a->second.second;
          p.source = "code";
        }
        if (p.source != "global") break;
      }
      const auto t = by_type.find(std::string("|") + KeyTypeText(key.type));
      if (p.source == "global" && t != by_type.end()) {
        p.target_s = p.a1_s + t->second.first / t->second.second;
        p.source = "type";
      }
    }
    cued.push_back(p);
    previous = p.code;
  }

  // Strictly increasing targets, min_interval_s apart and each slot at least
  // min_slot_fraction of its succession's median unit duration.
  const double all_median = Median(all_durations);
  auto shortest_slot = [&](const KeyCode& from, const KeyCode& to) {
    const auto d = durations.find(SuccessionKey(from, to));
    const double median = d != durations.end() ? Median(d->second) : all_median;
    return std::max(options.min_interval_s, std::isfinite(median) ? options.min_slot_fraction * median : 0.0);
  };
  if (options.least_squares_spacing && cued.size() > 1) {
    // Minimise Σ (t_k − d_k)² subject to t_{k+1} − t_k ≥ g_k: with
    // c_k = Σ_{j<k} g_j and s_k = t_k − c_k the constraint is s
    // non-decreasing, an isotonic regression of d_k − c_k (pool adjacent
    // violators: blocks of equal s at their members' mean).
    const size_t n = cued.size();
    std::vector<double> offset(n, 0.0);
    for (size_t i = 1; i < n; ++i) offset[i] = offset[i - 1] + shortest_slot(cued[i - 1].code, cued[i].code);
    struct Block {
      double sum;
      size_t count;
      double Value() const { return sum / static_cast<double>(count); }
    };
    std::vector<Block> blocks;
    for (size_t i = 0; i < n; ++i) {
      blocks.push_back({cued[i].target_s - offset[i], 1});
      while (blocks.size() > 1 && blocks[blocks.size() - 2].Value() > blocks.back().Value()) {
        blocks[blocks.size() - 2].sum += blocks.back().sum;
        blocks[blocks.size() - 2].count += blocks.back().count;
        blocks.pop_back();
      }
    }
    size_t i = 0;
    for (const Block& b : blocks) {
      for (size_t m = 0; m < b.count; ++m, ++i) {
        const double t = b.Value() + offset[i];
        if (t > cued[i].target_s + 1e-9) cued[i].source += "+pushed";
        if (t < cued[i].target_s - 1e-9) cued[i].source += "+advanced";
        cued[i].target_s = t;
      }
    }
  } else {
    for (size_t i = 1; i < cued.size(); ++i) {
      const double earliest = cued[i - 1].target_s + shortest_slot(cued[i - 1].code, cued[i].code);
      if (cued[i].target_s < earliest) {
        cued[i].target_s = earliest;
        cued[i].source += "+pushed";
      }
    }
  }

  double first = cued.empty() ? 0.5 * audio_duration_s : cued.front().target_s;
  double last = cued.empty() ? 0.5 * audio_duration_s + options.min_interval_s : cued.back().target_s;
  plan.lead_in_s = std::max(0.0, leave - first);
  for (PlannedKey& p : cued) {
    p.target_s += plan.lead_in_s;
    p.a1_s += plan.lead_in_s;
  }
  first += plan.lead_in_s;
  last += plan.lead_in_s;
  PlannedKey rest_in;
  rest_in.a1_s = kNaN;
  rest_in.target_s = first - leave;
  rest_in.source = "rest";
  PlannedKey rest_out = rest_in;
  rest_out.target_s = last + reach;
  plan.keys.push_back(rest_in);
  plan.keys.insert(plan.keys.end(), cued.begin(), cued.end());
  plan.keys.push_back(rest_out);
  plan.duration_s = std::max(plan.lead_in_s + audio_duration_s, rest_out.target_s);
  return plan;
}

}  // namespace csw::dict
