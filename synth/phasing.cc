#include "synth/phasing.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <numbers>

#include "core/error.h"
#include "core/file_util.h"

namespace csw {
namespace {

struct NamedMovement {
  const char* name;
  MovementTiming PhasingModel::*member;
};

constexpr NamedMovement kMovements[] = {
    {"placement_cv", &PhasingModel::placement_cv},
    {"shape_cv", &PhasingModel::shape_cv},
    {"placement_v", &PhasingModel::placement_v},
    {"shape_v", &PhasingModel::shape_v},
    {"placement_c", &PhasingModel::placement_c},
    {"shape_c", &PhasingModel::shape_c},
    {"rest", &PhasingModel::rest},
};

bool Finite(double v) { return std::isfinite(v); }

std::string CheckMovement(const char* name, const MovementTiming& m) {
  const std::string n(name);
  if (!Finite(m.start_mean_s) || !Finite(m.start_sd_s) || !Finite(m.target_mean_s) || !Finite(m.target_sd_s))
    return n + ": not a finite number";
  if (m.start_sd_s < 0 || m.target_sd_s < 0) return n + ": negative standard deviation";
  if (m.start_sd_s > 1.0 || m.target_sd_s > 1.0) return n + ": standard deviation above 1 s";
  if (std::abs(m.start_mean_s) > 5.0 || std::abs(m.target_mean_s) > 5.0) return n + ": mean beyond ±5 s";
  if (m.target_mean_s <= m.start_mean_s) return n + ": target mean is not after start mean";
  return "";
}

// Uniform in (0, 1) from 53 random bits.
double Uniform01(std::mt19937_64& rng) { return (static_cast<double>(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0); }

// Applies the constraints to one movement: start >= lower (the previous key's
// target; -inf for none), target - start >= min_s. When only the duration is too
// short the pair is widened symmetrically around its midpoint (so that the rare
// repair does not bias one end), else the target moves.
void Constrain(double lower, double min_s, double& start, double& target) {
  if (target - start < min_s) {
    const double mid = 0.5 * (start + target);
    start = mid - 0.5 * min_s;
    target = mid + 0.5 * min_s;
  }
  if (start < lower) {
    start = lower;
    if (target < start + min_s) target = start + min_s;
  }
}

std::vector<KeyTiming> Timing(const std::vector<Key>& keys, const PhasingModel& model,
                              const std::function<double(double, double)>& draw, bool sequential = true) {
  if (std::string why = model.Check(); !why.empty()) throw InvalidInput("phasing model: " + why);
  std::vector<KeyTiming> out(keys.size());
  const double no_bound = -std::numeric_limits<double>::infinity();
  double placement_prev = no_bound;
  double shape_prev = no_bound;
  int first_cued = -1;
  double last_end = 0.0;
  for (size_t i = 0; i < keys.size(); ++i) {
    const Key& k = keys[i];
    KeyTiming& t = out[i];
    if (k.type == KeyType::kRest) {
      if (first_cued < 0) continue;  // leading rest, set below
      const MovementTiming& r = model.rest;
      const double ref = std::max(k.a1_s, last_end);
      t.placement_start_s = ref + draw(r.start_mean_s, r.start_sd_s);
      t.placement_target_s = ref + draw(r.target_mean_s, r.target_sd_s);
      t.shape_start_s = ref + draw(r.start_mean_s, r.start_sd_s);
      t.shape_target_s = ref + draw(r.target_mean_s, r.target_sd_s);
    } else {
      if (first_cued < 0) first_cued = static_cast<int>(i);
      const MovementTiming& p = PlacementTiming(model, k.type);
      const MovementTiming& s = ShapeTiming(model, k.type);
      t.placement_start_s = k.a1_s + draw(p.start_mean_s, p.start_sd_s);
      t.placement_target_s = k.a1_s + draw(p.target_mean_s, p.target_sd_s);
      t.shape_start_s = k.a1_s + draw(s.start_mean_s, s.start_sd_s);
      t.shape_target_s = k.a1_s + draw(s.target_mean_s, s.target_sd_s);
      last_end = k.end_s;
    }
    Constrain(placement_prev, model.min_movement_s, t.placement_start_s, t.placement_target_s);
    Constrain(shape_prev, model.min_movement_s, t.shape_start_s, t.shape_target_s);
    if (sequential) {
      placement_prev = t.placement_target_s;
      shape_prev = t.shape_target_s;
    }
  }
  // Leading rest keys: the hand is at rest until the first movement starts.
  const double leave = first_cued < 0 ? (keys.empty() ? 0.0 : keys.front().a1_s)
                                      : std::min(out[first_cued].placement_start_s, out[first_cued].shape_start_s);
  for (size_t i = 0; i < keys.size() && (first_cued < 0 || static_cast<int>(i) < first_cued); ++i)
    out[i] = {leave, leave, leave, leave};
  return out;
}

}  // namespace

std::string PhasingModel::Check() const {
  for (const NamedMovement& m : kMovements)
    if (std::string why = CheckMovement(m.name, this->*m.member); !why.empty()) return why;
  if (!Finite(truncate_sd) || truncate_sd <= 0.0 || truncate_sd > 10.0) return "truncate_sd must be in (0, 10]";
  if (!Finite(min_movement_s) || min_movement_s <= 0.0 || min_movement_s > 1.0)
    return "min_movement_s must be in (0, 1] s";
  return "";
}

nlohmann::json PhasingModelToJson(const PhasingModel& model) {
  nlohmann::json j;
  j["format"] = "csw-phasing-model";
  j["version"] = 1;
  for (const NamedMovement& m : kMovements) {
    const MovementTiming& t = model.*m.member;
    j[m.name] = {{"start_mean_ms", t.start_mean_s * 1e3},
                 {"start_sd_ms", t.start_sd_s * 1e3},
                 {"target_mean_ms", t.target_mean_s * 1e3},
                 {"target_sd_ms", t.target_sd_s * 1e3}};
  }
  j["truncate_sd"] = model.truncate_sd;
  j["min_movement_ms"] = model.min_movement_s * 1e3;
  return j;
}

PhasingModel PhasingModelFromJson(const nlohmann::json& json, const std::string& source) {
  const Location where{source, std::nullopt, std::nullopt};
  if (!json.is_object()) throw ParseError(where, "phasing model: not a JSON object");
  auto number = [&](const nlohmann::json& obj, const std::string& key, const std::string& path) {
    auto it = obj.find(key);
    if (it == obj.end()) throw ParseError(where, "phasing model: missing '" + path + key + "'");
    if (!it->is_number()) throw ParseError(where, "phasing model: '" + path + key + "' is not a number");
    return it->get<double>();
  };
  if (auto f = json.find("format"); f != json.end() && (!f->is_string() || *f != "csw-phasing-model"))
    throw ParseError(where, "phasing model: 'format' is not \"csw-phasing-model\"");
  PhasingModel model;
  for (const NamedMovement& m : kMovements) {
    auto it = json.find(m.name);
    if (it == json.end()) continue;
    if (!it->is_object()) throw ParseError(where, std::string("phasing model: '") + m.name + "' is not an object");
    const std::string path = std::string(m.name) + ".";
    MovementTiming& t = model.*m.member;
    t.start_mean_s = number(*it, "start_mean_ms", path) * 1e-3;
    t.start_sd_s = number(*it, "start_sd_ms", path) * 1e-3;
    t.target_mean_s = number(*it, "target_mean_ms", path) * 1e-3;
    t.target_sd_s = number(*it, "target_sd_ms", path) * 1e-3;
  }
  if (json.contains("truncate_sd")) model.truncate_sd = number(json, "truncate_sd", "");
  if (json.contains("min_movement_ms")) model.min_movement_s = number(json, "min_movement_ms", "") * 1e-3;
  if (std::string why = model.Check(); !why.empty()) throw ParseError(where, "phasing model: " + why);
  return model;
}

PhasingModel LoadPhasingModel(const std::string& path) {
  const std::string text = ReadTextFile(path);
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    throw ParseError({path, static_cast<int64_t>(e.byte), std::nullopt}, "invalid JSON");
  }
  return PhasingModelFromJson(j, path);
}

void SavePhasingModel(const PhasingModel& model, const std::string& path) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw IoError(path, "cannot open for writing");
  out << PhasingModelToJson(model).dump(2) << "\n";
  out.close();
  if (!out) throw IoError(path, "write failed");
}

const MovementTiming& PlacementTiming(const PhasingModel& model, KeyType type) {
  switch (type) {
    case KeyType::kCV:
      return model.placement_cv;
    case KeyType::kVowelAlone:
      return model.placement_v;
    case KeyType::kConsonantAlone:
      return model.placement_c;
    case KeyType::kRest:
      break;
  }
  return model.rest;
}

const MovementTiming& ShapeTiming(const PhasingModel& model, KeyType type) {
  switch (type) {
    case KeyType::kCV:
      return model.shape_cv;
    case KeyType::kVowelAlone:
      return model.shape_v;
    case KeyType::kConsonantAlone:
      return model.shape_c;
    case KeyType::kRest:
      break;
  }
  return model.rest;
}

double SampleTruncatedNormal(double mean, double sd, double k, std::mt19937_64& rng) {
  if (!(sd > 0.0) || !(k > 0.0)) return mean;
  // Box-Muller; rejection outside ±k (at k = 3, 0.3 % of draws).
  for (int attempt = 0; attempt < 1000; ++attempt) {
    const double u1 = Uniform01(rng);
    const double u2 = Uniform01(rng);
    const double z = std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
    if (std::abs(z) <= k) return mean + sd * z;
  }
  return mean;  // unreachable in practice for k > 0.1
}

std::vector<KeyTiming> SampleTiming(const std::vector<Key>& keys, const PhasingModel& model, std::mt19937_64& rng,
                                    TimingMode mode) {
  return Timing(
      keys, model, [&](double mean, double sd) { return SampleTruncatedNormal(mean, sd, model.truncate_sd, rng); },
      mode == TimingMode::kSequential);
}

PhasingMeans MeasurePhasing(const std::vector<Key>& keys, const std::vector<KeyTiming>& timing) {
  struct Acc {
    int n = 0;
    double sum[4] = {0, 0, 0, 0};
    double sum2[4] = {0, 0, 0, 0};
  };
  Acc acc[3];
  const size_t n = std::min(keys.size(), timing.size());
  for (size_t i = 0; i < n; ++i) {
    int slot = -1;
    switch (keys[i].type) {
      case KeyType::kCV:
        slot = 0;
        break;
      case KeyType::kVowelAlone:
        slot = 1;
        break;
      case KeyType::kConsonantAlone:
        slot = 2;
        break;
      case KeyType::kRest:
        break;
    }
    if (slot < 0) continue;
    const KeyTiming& t = timing[i];
    const double a1 = keys[i].a1_s;
    const double d[4] = {t.placement_start_s - a1, t.placement_target_s - a1, t.shape_start_s - a1,
                         t.shape_target_s - a1};
    Acc& a = acc[slot];
    ++a.n;
    for (int k = 0; k < 4; ++k) {
      a.sum[k] += d[k];
      a.sum2[k] += d[k] * d[k];
    }
  }
  PhasingMeans out;
  PhasingMeans::Entry* entries[3] = {&out.cv, &out.v, &out.c};
  for (int s = 0; s < 3; ++s) {
    const Acc& a = acc[s];
    PhasingMeans::Entry& e = *entries[s];
    e.count = a.n;
    if (a.n == 0) continue;
    double mean[4], sd[4];
    for (int k = 0; k < 4; ++k) {
      mean[k] = a.sum[k] / a.n;
      sd[k] = std::sqrt(std::max(0.0, a.sum2[k] / a.n - mean[k] * mean[k]));
    }
    e.placement = {mean[0], sd[0], mean[1], sd[1]};
    e.shape = {mean[2], sd[2], mean[3], sd[3]};
  }
  return out;
}

PhasingModel CalibratePhasing(const std::vector<Key>& keys, const PhasingModel& target, uint64_t seed, int iterations) {
  if (std::string why = target.Check(); !why.empty()) throw InvalidInput("phasing model: " + why);
  PhasingModel model = target;
  struct Pair {
    MovementTiming PhasingModel::*placement;
    MovementTiming PhasingModel::*shape;
    PhasingMeans::Entry PhasingMeans::*measured;
  };
  const Pair pairs[] = {{&PhasingModel::placement_cv, &PhasingModel::shape_cv, &PhasingMeans::cv},
                        {&PhasingModel::placement_v, &PhasingModel::shape_v, &PhasingMeans::v},
                        {&PhasingModel::placement_c, &PhasingModel::shape_c, &PhasingMeans::c}};
  auto adjust = [](MovementTiming& in, const MovementTiming& want, const MovementTiming& got) {
    MovementTiming next = in;
    next.start_mean_s += want.start_mean_s - got.start_mean_s;
    next.target_mean_s += want.target_mean_s - got.target_mean_s;
    if (next.target_mean_s > next.start_mean_s && std::abs(next.start_mean_s) <= 5.0 &&
        std::abs(next.target_mean_s) <= 5.0)
      in = next;
  };
  for (int it = 0; it < iterations; ++it) {
    std::mt19937_64 rng(seed);
    const PhasingMeans got = MeasurePhasing(keys, SampleTiming(keys, model, rng));
    for (const Pair& p : pairs) {
      const PhasingMeans::Entry& e = got.*p.measured;
      if (e.count == 0) continue;
      adjust(model.*p.placement, target.*p.placement, e.placement);
      adjust(model.*p.shape, target.*p.shape, e.shape);
    }
  }
  return model;
}

std::vector<KeyTiming> MeanTiming(const std::vector<Key>& keys, const PhasingModel& model) {
  return Timing(keys, model, [](double mean, double) { return mean; });
}

}  // namespace csw
