#include "workbench/jobs/model_jobs.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <numeric>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "core/error.h"
#include "core/json_util.h"
#include "core/markerset.h"
#include "core/take.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "io/models/model_file.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "models/rigid_model.h"
#ifdef CSW_HAVE_REPORT
#include "workbench/report/report.h"
#endif

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

std::string UtcNow() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

std::string ReadTextFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, "cannot open");
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// ---------------------------------------------------------------- take ranges

int64_t ParseBound(const std::string& text, const std::string& spec, bool* percent) {
  *percent = false;
  std::string t = text;
  if (!t.empty() && t.back() == '%') {
    *percent = true;
    t.pop_back();
  }
  if (t.empty() || t.find_first_not_of("0123456789") != std::string::npos || t.size() > 12) {
    throw InvalidInput("take range '" + spec + "': '" + text + "' is not a frame number or a percentage");
  }
  return std::stoll(t);
}

// Online mean / sd / max, mergeable (Chan et al.).
struct Accumulator {
  int64_t n = 0;
  double mean = 0, m2 = 0, max = 0;
  void Add(double x) {
    if (!std::isfinite(x)) return;
    ++n;
    const double d = x - mean;
    mean += d / static_cast<double>(n);
    m2 += d * (x - mean);
    max = std::max(max, x);
  }
  void Merge(const Accumulator& o) {
    if (o.n == 0) return;
    if (n == 0) {
      *this = o;
      return;
    }
    const double total = static_cast<double>(n + o.n);
    const double d = o.mean - mean;
    m2 += o.m2 + d * d * static_cast<double>(n) * static_cast<double>(o.n) / total;
    mean += d * static_cast<double>(o.n) / total;
    max = std::max(max, o.max);
    n += o.n;
  }
  double sd() const { return n > 1 ? std::sqrt(m2 / static_cast<double>(n - 1)) : 0.0; }
  json Json(const std::string& unit = "mm") const {
    if (n == 0) return json{{"count", 0}};
    return json{{"count", n}, {"mean_" + unit, mean}, {"sd_" + unit, sd()}, {"max_" + unit, max}};
  }
};

// ---------------------------------------------------------------- configuration

struct StepSpec {
  std::string name;
  std::vector<std::string> markers;
  int components = 1;
};

struct ModelConfig {
  json raw = json::object();
  std::string markerset;  // resolved path, "" = none
  RigidModelOptions rigid;
  double min_distance_mm = 2.0;
  // face
  int face_components = 6;
  std::string face_preset;  // "", "seed", "mother"
  std::map<std::string, std::vector<std::string>> face_groups;
  int residual_components = 0;
  std::vector<StepSpec> face_steps;
  int throat_weight_rounds = 4;
  // hand
  int angle_components = 12;
  double ridge = 0;
  bool gaussian_fill = true;
};

ParseError ConfigError(const std::string& file, const std::string& what) {
  return ParseError(Location{file, std::nullopt, std::nullopt}, what);
}

// Sets where a model came from, keeping its fit statistics (training frames,
// residual), which inversion uses (e.g. the hand's forearm weighting).
void WithProvenance(const ModelInfo& from, ModelInfo* to) {
  to->corpus = from.corpus;
  to->training_takes = from.training_takes;
  to->config_json = from.config_json;
  to->created_utc = from.created_utc;
  to->csw_version = from.csw_version;
}

void CheckKeys(const json& obj, const std::set<std::string>& allowed, const std::string& file,
               const std::string& where) {
  if (!obj.is_object()) throw ConfigError(file, where + " must be a JSON object");
  for (const auto& [k, v] : obj.items()) {
    (void)v;
    if (!allowed.count(k)) throw ConfigError(file, where + ": unknown key '" + k + "'");
  }
}

template <typename T>
T Get(const json& obj, const char* key, T fallback, const std::string& file, const std::string& where) {
  if (!obj.contains(key)) return fallback;
  try {
    return obj.at(key).get<T>();
  } catch (const json::exception&) {
    throw ConfigError(file, where + "." + key + " has the wrong type");
  }
}

std::vector<std::string> GetNames(const json& v, const std::string& file, const std::string& where) {
  if (!v.is_array()) throw ConfigError(file, where + " must be an array of marker names");
  std::vector<std::string> out;
  for (const auto& e : v) {
    if (!e.is_string()) throw ConfigError(file, where + " must be an array of marker names");
    out.push_back(e.get<std::string>());
  }
  return out;
}

ModelConfig LoadConfig(const std::string& path) {
  ModelConfig c;
  if (path.empty()) return c;
  const json j = ParseJsonText(ReadTextFile(path), path);
  c.raw = j;
  CheckKeys(j, {"format", "version", "markerset", "training", "rigid", "face", "hand"}, path, "config");
  if (j.contains("format") && j["format"] != "csw-model-config") {
    throw ConfigError(path, "config: format must be \"csw-model-config\"");
  }
  if (Get<int>(j, "version", 1, path, "config") > 1) throw ConfigError(path, "config: version newer than 1");
  const std::string ms = Get<std::string>(j, "markerset", "", path, "config");
  if (!ms.empty()) c.markerset = fs::path(ms).is_absolute() ? ms : (fs::path(path).parent_path() / ms).string();
  if (j.contains("training")) {
    CheckKeys(j["training"], {"min_distance_mm"}, path, "training");
    c.min_distance_mm = Get<double>(j["training"], "min_distance_mm", 2.0, path, "training");
    if (!(c.min_distance_mm > 0)) throw ConfigError(path, "training.min_distance_mm must be > 0");
  }
  if (j.contains("rigid")) {
    const json& r = j["rigid"];
    CheckKeys(r, {"loss", "loss_scale_mm", "motion_variance"}, path, "rigid");
    const std::string loss = Get<std::string>(r, "loss", "cauchy", path, "rigid");
    if (loss == "cauchy")
      c.rigid.rigid.loss = RobustLoss::kCauchy;
    else if (loss == "huber")
      c.rigid.rigid.loss = RobustLoss::kHuber;
    else if (loss == "none")
      c.rigid.rigid.loss = RobustLoss::kNone;
    else
      throw ConfigError(path, "rigid.loss must be cauchy, huber or none");
    c.rigid.rigid.loss_scale_mm = Get<double>(r, "loss_scale_mm", 1.0, path, "rigid");
    c.rigid.motion_variance = Get<double>(r, "motion_variance", 0.99, path, "rigid");
    if (!(c.rigid.rigid.loss_scale_mm > 0)) throw ConfigError(path, "rigid.loss_scale_mm must be > 0");
    if (!(c.rigid.motion_variance > 0 && c.rigid.motion_variance <= 1)) {
      throw ConfigError(path, "rigid.motion_variance must be in (0, 1]");
    }
  }
  if (j.contains("face")) {
    const json& f = j["face"];
    CheckKeys(f, {"components", "preset", "groups", "residual_components", "steps", "throat_weight_rounds"}, path,
              "face");
    c.face_components = Get<int>(f, "components", 6, path, "face");
    if (c.face_components < 1) throw ConfigError(path, "face.components must be >= 1");
    c.face_preset = Get<std::string>(f, "preset", "", path, "face");
    if (!c.face_preset.empty() && c.face_preset != "seed" && c.face_preset != "mother") {
      throw ConfigError(path, "face.preset must be \"seed\" or \"mother\"");
    }
    c.residual_components = Get<int>(f, "residual_components", 0, path, "face");
    c.throat_weight_rounds = Get<int>(f, "throat_weight_rounds", 4, path, "face");
    if (f.contains("groups")) {
      CheckKeys(f["groups"], {"jaw", "lip_rounding", "lips_upper", "lips_lower", "lip_corners", "throat"}, path,
                "face.groups");
      for (const auto& [k, v] : f["groups"].items()) c.face_groups[k] = GetNames(v, path, "face.groups." + k);
    }
    if (!c.face_preset.empty() && c.face_groups.empty()) {
      throw ConfigError(path, "face.preset needs face.groups (jaw, lip_rounding, lips_upper, ...)");
    }
    if (f.contains("steps")) {
      if (!f["steps"].is_array()) throw ConfigError(path, "face.steps must be an array");
      for (size_t i = 0; i < f["steps"].size(); ++i) {
        const json& s = f["steps"][i];
        const std::string w = "face.steps[" + std::to_string(i) + "]";
        CheckKeys(s, {"name", "markers", "components"}, path, w);
        StepSpec step;
        step.name = Get<std::string>(s, "name", "p" + std::to_string(i + 1), path, w);
        if (s.contains("markers")) step.markers = GetNames(s["markers"], path, w + ".markers");
        step.components = Get<int>(s, "components", 1, path, w);
        c.face_steps.push_back(step);
      }
      if (!c.face_preset.empty()) throw ConfigError(path, "face: give either preset or steps, not both");
    }
  }
  if (j.contains("hand")) {
    const json& h = j["hand"];
    CheckKeys(h, {"angle_components", "ridge", "gaussian_fill"}, path, "hand");
    c.gaussian_fill = Get<bool>(h, "gaussian_fill", true, path, "hand");
    c.angle_components = Get<int>(h, "angle_components", 12, path, "hand");
    c.ridge = Get<double>(h, "ridge", 0.0, path, "hand");
    if (c.angle_components < 1) throw ConfigError(path, "hand.angle_components must be >= 1");
    if (c.ridge < 0) throw ConfigError(path, "hand.ridge must be >= 0");
  }
  return c;
}

// ---------------------------------------------------------------- layouts

FaceLayout MakeFaceLayout(const MarkerSet& set, const std::string& set_file) {
  if (set.head_cluster.size() < 3) {
    throw InvalidInput(set_file + ": the face model needs a head_cluster of at least 3 markers");
  }
  if (set.face.empty() && set.throat.empty()) throw InvalidInput(set_file + ": the face model needs face markers");
  FaceLayout l;
  l.head = set.head_cluster;
  l.face = set.face;
  for (const ThroatMarker& t : set.throat) {
    l.throat.push_back(t.marker);
    l.throat_weights.push_back(t.head_weight ? *t.head_weight : kNaN);
  }
  return l;
}

HandLayout MakeHandLayout(const MarkerSet& set, const std::string& set_file) {
  if (set.forearm_cluster.size() < 3) {
    throw InvalidInput(set_file + ": the hand model needs a forearm_cluster of at least 3 markers");
  }
  if (set.hand_segments.empty()) throw InvalidInput(set_file + ": the hand model needs hand_segments");
  HandLayout l;
  l.forearm = set.forearm_cluster;
  std::map<std::string, int> index;
  auto add = [&](const std::string& m) {
    if (index.count(m)) return index[m];
    index[m] = static_cast<int>(l.hand.size());
    l.hand.push_back(m);
    return index[m];
  };
  std::map<std::string, int> segment_index;
  for (const HandSegment& s : set.hand_segments) {
    HandSegmentDef d;
    d.name = s.name;
    if (!s.parent.empty()) {
      auto it = segment_index.find(s.parent);
      if (it == segment_index.end()) {
        throw InvalidInput(set_file + ": hand segment '" + s.name + "' names parent '" + s.parent +
                           "' which is not defined before it");
      }
      d.parent = it->second;
    }
    for (const std::string& m : s.markers) d.markers.push_back(add(m));
    segment_index[s.name] = static_cast<int>(l.segments.size());
    l.segments.push_back(d);
  }
  for (const std::string& m : set.fingertips) add(m);
  for (const std::string& m : set.palm) add(m);
  return l;
}

std::vector<GuidedPcaStep> FaceSteps(const ModelConfig& c, const FaceLayout& layout, const std::string& file) {
  std::map<std::string, int> idx;
  for (size_t i = 0; i < layout.face.size(); ++i) idx[layout.face[i]] = static_cast<int>(i);
  for (size_t i = 0; i < layout.throat.size(); ++i) idx[layout.throat[i]] = static_cast<int>(layout.face.size() + i);
  auto indices = [&](const std::vector<std::string>& names, const std::string& where) {
    std::vector<int> out;
    for (const auto& n : names) {
      auto it = idx.find(n);
      if (it == idx.end()) {
        throw InvalidInput(file + ": " + where + ": marker '" + n +
                           "' is not a face or throat marker of the marker set");
      }
      out.push_back(it->second);
    }
    return out;
  };
  if (!c.face_steps.empty()) {
    std::vector<GuidedPcaStep> steps;
    for (size_t i = 0; i < c.face_steps.size(); ++i) {
      GuidedPcaStep s;
      s.name = c.face_steps[i].name;
      s.markers = indices(c.face_steps[i].markers, "face.steps[" + std::to_string(i) + "]");
      s.components = c.face_steps[i].components;
      steps.push_back(s);
    }
    return steps;
  }
  if (!c.face_preset.empty()) {
    FaceMarkerGroups g;
    auto group = [&](const char* key) {
      auto it = c.face_groups.find(key);
      return it == c.face_groups.end() ? std::vector<int>{} : indices(it->second, std::string("face.groups.") + key);
    };
    g.jaw = group("jaw");
    g.lip_rounding = group("lip_rounding");
    g.lips_upper = group("lips_upper");
    g.lips_lower = group("lips_lower");
    g.lip_corners = group("lip_corners");
    g.throat = group("throat");
    return c.face_preset == "seed" ? SeedFaceSteps(g, c.residual_components) : MotherFaceSteps(g);
  }
  return {};  // FitFaceModel: one step with default_components
}

// ---------------------------------------------------------------- takes

struct LoadedTake {
  TakeRange range;
  std::vector<std::string> labels;
  MarkerArray markers;  // model order, frames of the range
  double rate_hz = 0;
};

// Columns of `names` in a take, through the marker set (aliases, case, prefixes).
std::vector<int> BindNames(const MarkerSet& set, const std::vector<std::string>& labels,
                           const std::vector<std::string>& names, const std::string& where) {
  const MarkerBinding b = BindMarkerSet(set, labels, false, where);
  std::vector<int> cols;
  std::vector<std::string> missing;
  for (const auto& n : names) {
    auto it = b.index.find(n);
    if (it == b.index.end()) {
      missing.push_back(n);
      continue;
    }
    cols.push_back(it->second);
  }
  if (!missing.empty()) {
    std::string list;
    for (const auto& m : missing) list += (list.empty() ? "" : ", ") + m;
    throw InvalidInput(where + ": the take has no marker " + list + " (marker set \"" + set.name + "\")");
  }
  return cols;
}

MarkerArray Extract(const MarkerArray& all, const std::vector<int>& cols, int64_t first, int64_t count) {
  MarkerArray out(count, static_cast<int64_t>(cols.size()));
  for (int64_t f = 0; f < count; ++f) {
    for (size_t c = 0; c < cols.size(); ++c) {
      const float* p = all.at(first + f, cols[c]);
      std::copy(p, p + 3, out.at(f, static_cast<int64_t>(c)));
    }
  }
  return out;
}

std::vector<TakeRange> SelectTakes(const Corpus& corpus, const std::vector<std::string>& specs, bool skip_filled) {
  std::vector<TakeRange> out;
  if (specs.empty()) {
    for (const TakeSummary& s : corpus.Takes()) {
      if (skip_filled && s.name.find(".filled") != std::string::npos) continue;
      TakeRange r = ParseTakeRange(s.name);
      out.push_back(r);
    }
  } else {
    for (const auto& s : specs) out.push_back(ParseTakeRange(s));
  }
  for (TakeRange& r : out) {
    if (!corpus.HasTake(r.take)) throw InvalidInput(corpus.path() + ": no take named '" + r.take + "'");
    ResolveTakeRange(&r, corpus.Summary(r.take).frames);
  }
  if (out.empty()) throw InvalidInput(corpus.path() + ": no take to use");
  return out;
}

LoadedTake LoadRange(const Corpus& corpus, const TakeRange& range, const MarkerSet& set,
                     const std::vector<std::string>& names) {
  const Take take = corpus.LoadTake(range.take);
  LoadedTake t;
  t.range = range;
  t.labels = take.marker_names;
  t.rate_hz = take.rate_hz;
  const std::vector<int> cols = BindNames(set, take.marker_names, names, corpus.path() + ": take '" + range.take + "'");
  t.markers = Extract(take.markers, cols, range.first, range.count);
  return t;
}

std::string CombinedConfig(const ModelConfig& c, const MarkerSet& set) {
  json j;
  j["config"] = c.raw;
  j["markerset"] = json::parse(MarkerSetToJson(set));
  return j.dump();
}

MarkerSet MarkerSetOfModel(const ModelInfo& info, const std::string& model_file) {
  try {
    const json j = json::parse(info.config_json);
    return ParseMarkerSet(j.at("markerset").dump(), model_file);
  } catch (const json::exception&) {
    throw ConfigError(model_file, "model has no marker set in its configuration");
  }
}

#ifdef CSW_HAVE_REPORT
std::vector<std::pair<int, int>> SticksOf(const MarkerSet& set, const std::vector<std::string>& names) {
  std::map<std::string, int> idx;
  for (size_t i = 0; i < names.size(); ++i) idx[names[i]] = static_cast<int>(i);
  std::vector<std::pair<int, int>> out;
  for (const auto& [a, b] : set.sticks) {
    if (idx.count(a) && idx.count(b)) out.emplace_back(idx[a], idx[b]);
  }
  return out;
}

Eigen::Matrix3Xd AsPoints(const Eigen::VectorXd& coords) {
  return Eigen::Map<const Eigen::Matrix3Xd>(coords.data(), 3, coords.size() / 3);
}

void AddFigure(json& summary, const std::string& path) { summary["figures"].push_back(path); }
#endif

}  // namespace

// ---------------------------------------------------------------- public

TakeRange ParseTakeRange(const std::string& spec) {
  TakeRange r;
  r.spec = spec;
  const auto at = spec.rfind('@');
  r.take = spec.substr(0, at);
  if (r.take.empty()) throw InvalidInput("take range '" + spec + "': no take name");
  if (at == std::string::npos) return r;
  const std::string range = spec.substr(at + 1);
  const auto colon = range.find(':');
  if (colon == std::string::npos) {
    throw InvalidInput("take range '" + spec + "': expected name@first:end (frames or percentages)");
  }
  const std::string a = range.substr(0, colon), b = range.substr(colon + 1);
  // Encoded for Resolve: percentages as negative values below -1e6.
  bool pa = false, pb = false;
  int64_t va = a.empty() ? 0 : ParseBound(a, spec, &pa);
  int64_t vb = b.empty() ? -1 : ParseBound(b, spec, &pb);
  if ((pa && va > 100) || (pb && vb > 100)) throw InvalidInput("take range '" + spec + "': percentage above 100");
  r.first = pa ? -(1000000 + va) : va;
  r.count = b.empty() ? -1 : (pb ? -(1000000 + vb) : vb);  // end, fixed by Resolve
  if (!b.empty() && !pb && !pa && vb <= va) throw InvalidInput("take range '" + spec + "': end is not after first");
  return r;
}

void ResolveTakeRange(TakeRange* r, int64_t frames) {
  auto value = [&](int64_t v) {
    if (v <= -1000000) return (-(v + 1000000)) * frames / 100;  // percentage, floor
    return v;
  };
  const bool open_end = r->count == -1;
  const int64_t first = value(r->first);
  const int64_t end = open_end ? frames : value(r->count);
  if (first < 0 || end > frames || end <= first) {
    throw InvalidInput("take range '" + r->spec + "': frames [" + std::to_string(first) + ", " + std::to_string(end) +
                       ") are not inside the take's " + std::to_string(frames) + " frames");
  }
  r->first = first;
  r->count = end - first;
}

std::string FitOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (kind != "rigid" && kind != "face" && kind != "hand") return "model kind must be rigid, face or hand";
  if (output.empty()) return "no output model file given (-o)";
  return "";
}

json Fit(const FitOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  const ModelConfig config = LoadConfig(options.config);
  const std::string set_file = options.markerset.empty() ? config.markerset : options.markerset;
  if (set_file.empty()) {
    throw InvalidInput("no marker set: give --markerset SET.json (or \"markerset\" in the --config file)");
  }
  const MarkerSet set = LoadMarkerSet(set_file);
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectTakes(corpus, options.train, true);

  ModelInfo info;
  info.corpus = options.corpus;
  for (const auto& r : ranges) info.training_takes.push_back(r.spec);
  info.config_json = CombinedConfig(config, set);
  info.created_utc = UtcNow();
  info.csw_version = CSW_VERSION;

  auto load = [&](const std::vector<std::string>& names) {
    std::vector<MarkerArray> takes;
    for (size_t i = 0; i < ranges.size(); ++i) {
      progress.Update("loading takes", static_cast<double>(i) / static_cast<double>(ranges.size()));
      takes.push_back(LoadRange(corpus, ranges[i], set, names).markers);
    }
    return takes;
  };

  json summary;
  summary["corpus"] = options.corpus;
  summary["output"] = options.output;
  summary["kind"] = options.kind;
  summary["training_takes"] = info.training_takes;
  summary["figures"] = json::array();
  ModelFile update;
  if (options.kind == "rigid") {
    json models = json::array();
    auto fit_cluster = [&](const std::string& name, const std::vector<std::string>& markers) {
      RigidModel m = FitRigidModel(name, markers, load(markers), config.rigid, &progress);
      WithProvenance(info, &m.info);
      std::vector<double> ev(m.motion.explained_fraction.data(),
                             m.motion.explained_fraction.data() + m.motion.explained_fraction.size());
      models.push_back({{"name", name},
                        {"markers", markers},
                        {"motion_parameters", m.motion.count()},
                        {"variance_explained", ev},
                        {"training_frames", m.info.training_frames},
                        {"rms_mm", m.info.training_rms_mm}});
      return m;
    };
    if (set.head_cluster.size() >= 3) update.head = fit_cluster("head", set.head_cluster);
    if (set.forearm_cluster.size() >= 3) update.forearm = fit_cluster("forearm", set.forearm_cluster);
    if (!update.head && !update.forearm) {
      throw InvalidInput(set_file + ": the marker set has neither a head_cluster nor a forearm_cluster");
    }
    summary["rigid"] = models;
  } else if (options.kind == "face") {
    const FaceLayout layout = MakeFaceLayout(set, set_file);
    FaceModelOptions fo;
    fo.steps = FaceSteps(config, layout, options.config.empty() ? set_file : options.config);
    fo.default_components = config.face_components;
    fo.min_distance_mm = config.min_distance_mm;
    fo.head = config.rigid;
    fo.throat_weight_rounds = config.throat_weight_rounds;
    std::vector<std::string> names = layout.head;
    names.insert(names.end(), layout.face.begin(), layout.face.end());
    names.insert(names.end(), layout.throat.begin(), layout.throat.end());
    FaceModel m = FitFaceModel(layout, load(names), fo, &progress);
    WithProvenance(info, &m.info);
    WithProvenance(info, &m.head.info);
    json throat = json::array();
    for (size_t i = 0; i < layout.throat.size(); ++i) {
      throat.push_back({{"marker", layout.throat[i]},
                        {"head_weight", m.head_weights(static_cast<Eigen::Index>(layout.face.size() + i))},
                        {"fitted", std::isnan(layout.throat_weights[i])}});
    }
    summary["face"] = {{"parameters", m.shape.parameter_names},
                       {"variance_explained", m.shape.variance_explained},
                       {"residual_variance", m.shape.residual_variance},
                       {"training_frames", m.info.training_frames},
                       {"selected_frames", m.info.selected_frames},
                       {"training_rms_mm", m.info.training_rms_mm},
                       {"throat", throat}};
#ifdef CSW_HAVE_REPORT
    if (!options.figures.empty()) {
      fs::create_directories(options.figures);
      report::EnsureGuiApplication();
      std::vector<std::string> shape_names = layout.face;
      shape_names.insert(shape_names.end(), layout.throat.begin(), layout.throat.end());
      std::vector<report::ParameterEffect> effects;
      for (int k = 0; k < m.num_parameters(); ++k) {
        Eigen::VectorXd p = Eigen::VectorXd::Zero(m.num_parameters());
        p(k) = -2;
        const Eigen::Matrix3Xd low = AsPoints(m.shape.Predict(p));
        p(k) = 2;
        effects.push_back({m.shape.parameter_names[static_cast<size_t>(k)], low, AsPoints(m.shape.Predict(p))});
      }
      for (const char* ext : {".png", ".svg"}) {
        const std::string v = (fs::path(options.figures) / (std::string("face_variance") + ext)).string();
        report::SaveVarianceExplained(v, "Face model: variance explained", m.shape.parameter_names,
                                      m.shape.variance_explained);
        AddFigure(summary, v);
        const std::string e = (fs::path(options.figures) / (std::string("face_parameters") + ext)).string();
        report::SaveParameterEffects(e, "Face model: each parameter at -2 sd (blue) and +2 sd (red)",
                                     AsPoints(m.shape.mean), effects, SticksOf(set, shape_names));
        AddFigure(summary, e);
      }
    }
#endif
    update.face = std::move(m);
  } else {
    const HandLayout layout = MakeHandLayout(set, set_file);
    HandModelOptions ho;
    ho.angle_components = config.angle_components;
    ho.min_distance_mm = config.min_distance_mm;
    ho.regression.ridge = config.ridge;
    ho.gaussian_fill = config.gaussian_fill;
    ho.forearm = config.rigid;
    std::vector<std::string> names = layout.forearm;
    names.insert(names.end(), layout.hand.begin(), layout.hand.end());
    HandModel m = FitHandModel(layout, load(names), ho, &progress);
    WithProvenance(info, &m.info);
    WithProvenance(info, &m.forearm.info);
    summary["hand"] = {{"parameters", m.num_parameters()},
                       {"angles", m.angle_names.size()},
                       {"variance_explained", m.shape.angle_pca.variance_explained},
                       {"regression_rank", m.shape.regression.rank},
                       {"warnings", m.shape.regression.warnings},
                       {"training_frames", m.info.training_frames},
                       {"selected_frames", m.info.selected_frames},
                       {"training_rms_mm", m.info.training_rms_mm}};
    if (!m.fill.empty()) {
      summary["hand"]["gaussian_fill"] = {{"frames", m.fill.frames}, {"iterations", m.fill.iterations}};
    }
#ifdef CSW_HAVE_REPORT
    if (!options.figures.empty()) {
      fs::create_directories(options.figures);
      report::EnsureGuiApplication();
      std::vector<std::string> pnames;
      for (int k = 0; k < m.num_parameters(); ++k) pnames.push_back("naH" + std::to_string(k + 1));
      std::vector<report::ParameterEffect> effects;
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(m.num_parameters());
      for (int k = 0; k < m.num_parameters(); ++k) {
        Eigen::VectorXd p = zero;
        p(k) = -2 * m.param_scale(k);
        const Eigen::Matrix3Xd low = AsPoints(m.shape.Predict(p));
        p(k) = 2 * m.param_scale(k);
        effects.push_back({pnames[static_cast<size_t>(k)], low, AsPoints(m.shape.Predict(p))});
      }
      for (const char* ext : {".png", ".svg"}) {
        const std::string v = (fs::path(options.figures) / (std::string("hand_variance") + ext)).string();
        report::SaveVarianceExplained(v, "Hand model: joint-angle variance explained", pnames,
                                      m.shape.angle_pca.variance_explained);
        AddFigure(summary, v);
        const std::string e = (fs::path(options.figures) / (std::string("hand_parameters") + ext)).string();
        report::SaveParameterEffects(e, "Hand model: each parameter at -2 sd (blue) and +2 sd (red)",
                                     AsPoints(m.shape.Predict(zero)), effects, SticksOf(set, layout.hand));
        AddFigure(summary, e);
      }
    }
#endif
    update.hand = std::move(m);
  }
#ifndef CSW_HAVE_REPORT
  if (!options.figures.empty()) summary["warnings"].push_back("figures need the Qt build (CSW_BUILD_GUI=ON)");
#endif
  progress.Update("saving", 1.0);
  UpdateModelFile(options.output, update);
  return summary;
}

std::string FitText(const json& s) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(3);
  o << "fitted " << s.value("kind", "") << " model(s) into " << s.value("output", "") << " from "
    << s["training_takes"].size() << " take(s)\n";
  if (s.contains("rigid")) {
    for (const auto& m : s["rigid"]) {
      o << "  " << m["name"].get<std::string>() << " motion: " << m["motion_parameters"].get<int>()
        << " parameters over " << m["training_frames"].get<int64_t>() << " frames, cluster rms "
        << m["rms_mm"].get<double>() << " mm\n";
    }
  }
  auto variance = [&](const json& names, const json& ev) {
    double cum = 0;
    for (size_t k = 0; k < ev.size(); ++k) {
      cum += ev[k].get<double>();
      o << "    " << (names.is_array() ? names[k].get<std::string>() : "p" + std::to_string(k + 1)) << ": "
        << 100 * ev[k].get<double>() << " % (cumulated " << 100 * cum << " %)\n";
    }
  };
  if (s.contains("face")) {
    const json& f = s["face"];
    o << "  face: " << f["parameters"].size() << " parameters, " << f["selected_frames"].get<int64_t>() << " of "
      << f["training_frames"].get<int64_t>() << " frames selected, training rms " << f["training_rms_mm"].get<double>()
      << " mm\n";
    variance(f["parameters"], f["variance_explained"]);
    for (const auto& t : f["throat"]) {
      o << "    throat " << t["marker"].get<std::string>() << ": head weight " << t["head_weight"].get<double>()
        << (t["fitted"].get<bool>() ? " (fitted)" : " (fixed)") << "\n";
    }
  }
  if (s.contains("hand")) {
    const json& h = s["hand"];
    o << "  hand: " << h["parameters"].get<int>() << " parameters from " << h["angles"].get<size_t>() << " angles, "
      << h["selected_frames"].get<int64_t>() << " of " << h["training_frames"].get<int64_t>()
      << " frames selected, training rms " << h["training_rms_mm"].get<double>() << " mm\n";
    if (h.contains("gaussian_fill")) {
      o << "  hand gap filler: Gaussian, " << h["gaussian_fill"]["frames"].get<int64_t>()
        << " training frames (incomplete ones included), " << h["gaussian_fill"]["iterations"].get<int>()
        << " EM rounds\n";
    }
    variance(json(), h["variance_explained"]);
  }
  for (const auto& f : s["figures"]) o << "  figure: " << f.get<std::string>() << "\n";
  if (s.contains("warnings")) {
    for (const auto& w : s["warnings"]) o << "  warning: " << w.get<std::string>() << "\n";
  }
  return o.str();
}

// ---------------------------------------------------------------- invert

std::string InvertOptions::Check() const {
  if (corpus.empty()) return "no corpus given";
  if (models.empty()) return "no model file given (--models)";
  if (!only.empty() && only != "face" && only != "hand") return "--only must be face or hand";
  if (!(hide_fraction >= 0 && hide_fraction < 1)) return "--hide must be in [0, 1)";
  if (threads < 0) return "--threads must be >= 0";
  if (inversion.max_iterations < 1) return "--max-iterations must be >= 1";
  if (!(inversion.prior_mm >= 0)) return "--prior must be >= 0";
  return "";
}

namespace {

struct ModelRun {
  std::string kind;  // "face" or "hand"
  const FaceModel* face = nullptr;
  const HandModel* hand = nullptr;
  MarkerSet set;
  std::vector<std::string> names;   // model order
  int cluster = 0;                  // cluster markers first
  std::vector<TakeRange> training;  // parsed training specs
  double target_mm = 0;
  const RigidModel& rigid() const { return face ? face->head : hand->forearm; }
};

struct TakeJob {
  const ModelRun* run = nullptr;
  TakeRange range;
  MarkerArray original;                         // model order
  MarkerArray input;                            // after hiding
  std::vector<std::pair<int64_t, int>> hidden;  // (frame, column) hidden on purpose
  MarkerArray truth;                            // clean markers (model order), empty when none
  InversionResult result;
  MarkerArray model_only;  // reconstruction before the gap correction
  std::string role;
  std::atomic<double> fraction{0};
  std::exception_ptr error;
};

bool Overlaps(const TakeRange& a, const TakeRange& b) {
  return a.take == b.take && a.first < b.first + b.count && b.first < a.first + a.count;
}

std::string FilledName(const std::set<std::string>& existing, const std::string& take) {
  std::string name = take + ".filled";
  for (int k = 2; existing.count(name); ++k) name = take + ".filled-" + std::to_string(k);
  return name;
}

}  // namespace

json Invert(const InvertOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  const ModelFile models = LoadModelFile(options.models);
  const Corpus corpus = Corpus::Open(options.corpus);
  const std::vector<TakeRange> ranges = SelectTakes(corpus, options.takes, true);

  std::vector<std::unique_ptr<ModelRun>> runs;
  auto make_run = [&](const std::string& kind, const ModelInfo& info, std::vector<std::string> names, int cluster,
                      double target) {
    auto r = std::make_unique<ModelRun>();
    r->kind = kind;
    r->set = MarkerSetOfModel(info, options.models);
    r->names = std::move(names);
    r->cluster = cluster;
    r->target_mm = target;
    for (const auto& spec : info.training_takes) r->training.push_back(ParseTakeRange(spec));
    return r;
  };
  if (models.face && options.only != "hand") {
    const FaceLayout& l = models.face->layout;
    std::vector<std::string> names = l.head;
    names.insert(names.end(), l.face.begin(), l.face.end());
    names.insert(names.end(), l.throat.begin(), l.throat.end());
    auto r = make_run("face", models.face->info, names, static_cast<int>(l.head.size()), 1.0);
    r->face = &*models.face;
    runs.push_back(std::move(r));
  }
  if (models.hand && options.only != "face") {
    const HandLayout& l = models.hand->layout;
    std::vector<std::string> names = l.forearm;
    names.insert(names.end(), l.hand.begin(), l.hand.end());
    auto r = make_run("hand", models.hand->info, names, static_cast<int>(l.forearm.size()), 2.0);
    r->hand = &*models.hand;
    runs.push_back(std::move(r));
  }
  if (runs.empty()) {
    throw InvalidInput(options.models + ": no " + (options.only.empty() ? "face or hand" : options.only) +
                       " model in the file");
  }

  // Load every (model, take) pair; hide samples; read the truth.
  std::vector<std::unique_ptr<TakeJob>> jobs;
  std::map<std::string, Take> clean_cache;
  for (size_t i = 0; i < ranges.size(); ++i) {
    progress.Update("loading takes", static_cast<double>(i) / static_cast<double>(ranges.size()));
    const Take take = corpus.LoadTake(ranges[i].take);
    const std::string where = corpus.path() + ": take '" + ranges[i].take + "'";
    Take clean;
    if (!options.truth.empty()) {
      const fs::path p = fs::path(options.truth) / (ranges[i].take + ".clean.c3d");
      if (fs::exists(p)) clean = ReadC3d(p.string());
    }
    for (const auto& run : runs) {
      auto job = std::make_unique<TakeJob>();
      job->run = run.get();
      job->range = ranges[i];
      const std::vector<int> cols = BindNames(run->set, take.marker_names, run->names, where);
      job->original = Extract(take.markers, cols, ranges[i].first, ranges[i].count);
      job->input = job->original;
      if (options.hide_fraction > 0) {
        std::vector<std::pair<int64_t, int>> visible;
        for (int64_t f = 0; f < job->input.frames(); ++f)
          for (int c = run->cluster; c < static_cast<int>(run->names.size()); ++c)
            if (job->input.Visible(f, c)) visible.emplace_back(f, c);
        std::mt19937_64 rng(options.seed ^ std::hash<std::string>{}(ranges[i].spec + "/" + run->kind));
        std::shuffle(visible.begin(), visible.end(), rng);
        visible.resize(static_cast<size_t>(std::floor(options.hide_fraction * static_cast<double>(visible.size()))));
        for (const auto& [f, c] : visible) job->input.SetMissing(f, c);
        job->hidden = std::move(visible);
      }
      if (!clean.marker_names.empty()) {
        if (clean.frames() != take.frames()) {
          throw InvalidInput(options.truth + ": " + ranges[i].take + ".clean.c3d has " +
                             std::to_string(clean.frames()) + " frames, the take " + std::to_string(take.frames()));
        }
        const std::vector<int> tc =
            BindNames(run->set, clean.marker_names, run->names, options.truth + "/" + ranges[i].take + ".clean.c3d");
        job->truth = Extract(clean.markers, tc, ranges[i].first, ranges[i].count);
      }
      job->role = "held_out";
      for (TakeRange t : run->training) {
        if (t.take != ranges[i].take) continue;
        ResolveTakeRange(&t, take.frames());
        if (Overlaps(t, ranges[i])) job->role = "training";
      }
      jobs.push_back(std::move(job));
    }
  }

  // Invert in parallel over (model, take) pairs.
  const int threads = std::max(
      1, std::min<int>(options.threads > 0 ? options.threads : static_cast<int>(std::thread::hardware_concurrency()),
                       static_cast<int>(jobs.size())));
  std::atomic<size_t> next{0};
  std::atomic<int> running{threads};
  auto worker = [&]() {
    for (size_t j = next++; j < jobs.size(); j = next++) {
      TakeJob& job = *jobs[j];
      try {
        Progress child([&](const std::string&, double f) {
          job.fraction.store(f);
          if (progress.cancelled()) throw Cancelled();
        });
        job.result = job.run->face ? InvertFace(*job.run->face, job.input, options.inversion, &child)
                                   : InvertHand(*job.run->hand, job.input, options.inversion, &child);
        job.model_only = job.result.reconstructed;
        // The edge misfit is the shape model's; a hand whose gaps the Gaussian
        // filler reconstructed (not the shape model) is left as filled.
        const bool gaussian = job.run->hand && !job.run->hand->fill.empty() && options.inversion.gaussian_fill;
        if (options.edge_correction && !gaussian) CorrectGapsWithEdgeResiduals(job.input, &job.result);
        job.fraction.store(1.0);
      } catch (...) {
        job.error = std::current_exception();
        next.store(jobs.size());  // stop handing out work
      }
    }
    --running;
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  bool cancelled = false;
  while (running.load() > 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    double done = 0;
    for (const auto& j : jobs) done += j->fraction.load();
    try {
      progress.Update("inverting", done / static_cast<double>(jobs.size()));
    } catch (const Cancelled&) {
      cancelled = true;  // workers see progress.cancelled() and stop
    }
  }
  for (auto& t : pool) t.join();
  if (cancelled) throw Cancelled();
  for (const auto& j : jobs) {
    if (j->error) std::rethrow_exception(j->error);
  }

  // Scores.
  json summary;
  summary["corpus"] = options.corpus;
  summary["models"] = options.models;
  summary["figures"] = json::array();
  for (const auto& run : runs) {
    json takes = json::array();
    std::map<std::string, Accumulator> visible_by_role, hidden_by_role, occluded_by_role, hidden_model_by_role,
        occluded_model_by_role;
    Accumulator rot_err, trans_err;
    // Per model marker (cluster markers included), pooled over takes.
    const size_t n_markers = run->names.size();
    std::vector<Accumulator> marker_visible(n_markers), marker_hidden(n_markers), marker_occluded(n_markers);
#ifdef CSW_HAVE_REPORT
    std::vector<report::ErrorBar> bars;
#endif
    for (const auto& jp : jobs) {
      const TakeJob& job = *jp;
      if (job.run != run.get()) continue;
      const InversionResult& res = job.result;
      const int nm = static_cast<int>(run->names.size());
      Accumulator visible, hidden, occluded, hidden_model, occluded_model, rot, trans;
      auto distance = [](const float* a, const float* b) {
        return std::sqrt(std::pow(double(a[0]) - b[0], 2) + std::pow(double(a[1]) - b[1], 2) +
                         std::pow(double(a[2]) - b[2], 2));
      };
      for (int64_t f = 0; f < res.frames(); ++f) {
        for (int c = 0; c < nm; ++c) marker_visible[static_cast<size_t>(c)].Add(res.error_mm(f, c));
        for (int c = run->cluster; c < nm; ++c) visible.Add(res.error_mm(f, c));
      }
      for (const auto& [f, c] : job.hidden) {
        const float* r = res.reconstructed.at(f, c);
        const float* o = job.original.at(f, c);
        if (IsMissing(r[0])) continue;
        hidden.Add(distance(r, o));
        marker_hidden[static_cast<size_t>(c)].Add(distance(r, o));
        hidden_model.Add(distance(job.model_only.at(f, c), o));
      }
      if (!job.truth.empty()) {
        for (int64_t f = 0; f < res.frames(); ++f) {
          for (int c = run->cluster; c < nm; ++c) {
            const float* r = res.reconstructed.at(f, c);
            const float* t = job.truth.at(f, c);
            if (job.original.Visible(f, c) || IsMissing(r[0]) || IsMissing(t[0])) continue;
            occluded.Add(distance(r, t));
            marker_occluded[static_cast<size_t>(c)].Add(distance(r, t));
            occluded_model.Add(distance(job.model_only.at(f, c), t));
          }
          if (!res.solved[static_cast<size_t>(f)]) continue;
          Eigen::Matrix3Xd obs(3, run->cluster);
          for (int c = 0; c < run->cluster; ++c)
            for (int k = 0; k < 3; ++k) obs(k, c) = job.truth.at(f, c)[k];
          const RigidFit truth_pose = EstimateRigidKabsch(run->rigid().reference, obs);
          if (!truth_pose.valid) continue;
          const RigidTransform est = RigidTransform::FromParameters(res.pose.row(f).transpose().head<6>().eval());
          rot.Add(Eigen::AngleAxisd(est.rotation.transpose() * truth_pose.transform.rotation).angle() * 180.0 /
                  3.14159265358979323846);
          trans.Add((est.translation - truth_pose.transform.translation).norm());
        }
      }
      int64_t solved = std::count(res.solved.begin(), res.solved.end(), uint8_t{1});
      json t = {{"take", job.range.spec},
                {"frames", res.frames()},
                {"solved_frames", solved},
                {"role", job.role},
                {"visible", visible.Json()}};
      if (!job.hidden.empty()) {
        t["hidden"] = hidden.Json();
        t["hidden_model"] = hidden_model.Json();
      }
      if (!job.truth.empty()) {
        t["occluded"] = occluded.Json();
        t["occluded_model"] = occluded_model.Json();
        t["pose"] = {{"rotation_deg", rot.Json("deg")}, {"translation_mm", trans.Json()}};
      }
      takes.push_back(t);
      visible_by_role[job.role].Merge(visible);
      hidden_by_role[job.role].Merge(hidden);
      occluded_by_role[job.role].Merge(occluded);
      hidden_model_by_role[job.role].Merge(hidden_model);
      occluded_model_by_role[job.role].Merge(occluded_model);
      rot_err.Merge(rot);
      trans_err.Merge(trans);
#ifdef CSW_HAVE_REPORT
      bars.push_back({job.range.spec, visible.mean, visible.sd(), visible.max, job.role == "held_out"});
#endif
    }
    json m = {{"takes", takes}, {"target_mm", run->target_mm}};
    json per_marker = json::array();
    for (size_t c = 0; c < n_markers; ++c) {
      json e = {{"marker", run->names[c]},
                {"role", static_cast<int>(c) < run->cluster ? "cluster" : "shape"},
                {"visible", marker_visible[c].Json()}};
      if (options.hide_fraction > 0) e["hidden"] = marker_hidden[c].Json();
      if (!options.truth.empty()) e["occluded"] = marker_occluded[c].Json();
      per_marker.push_back(e);
    }
    m["markers"] = per_marker;
    for (const char* role : {"training", "held_out"}) {
      json r = {{"visible", visible_by_role[role].Json()}};
      if (options.hide_fraction > 0) {
        r["hidden"] = hidden_by_role[role].Json();
        r["hidden_model"] = hidden_model_by_role[role].Json();
      }
      if (!options.truth.empty()) {
        r["occluded"] = occluded_by_role[role].Json();
        r["occluded_model"] = occluded_model_by_role[role].Json();
      }
      m[role] = r;
    }
    Accumulator all_visible;
    for (const auto& [k, v] : visible_by_role) all_visible.Merge(v);
    m["overall"] = {{"visible", all_visible.Json()}};
    auto pooled = [](const std::map<std::string, Accumulator>& by_role) {
      Accumulator a;
      for (const auto& [k, v] : by_role) a.Merge(v);
      return a.Json();
    };
    if (options.hide_fraction > 0) {
      m["overall"]["hidden"] = pooled(hidden_by_role);
      m["overall"]["hidden_model"] = pooled(hidden_model_by_role);
    }
    if (!options.truth.empty()) {
      m["overall"]["occluded"] = pooled(occluded_by_role);
      m["overall"]["occluded_model"] = pooled(occluded_model_by_role);
      m["overall"]["pose"] = {{"rotation_deg", rot_err.Json("deg")}, {"translation_mm", trans_err.Json()}};
    }
#ifdef CSW_HAVE_REPORT
    if (!options.figures.empty()) {
      fs::create_directories(options.figures);
      report::EnsureGuiApplication();
      for (const char* ext : {".png", ".svg"}) {
        const std::string p = (fs::path(options.figures) / (run->kind + "_errors" + ext)).string();
        report::SaveErrorBars(
            p, run->kind == "face" ? "Face: reconstruction error per take" : "Hand: reconstruction error per take",
            bars, run->target_mm);
        AddFigure(summary, p);
      }
    }
#endif
    summary[run->kind] = m;
  }
#ifndef CSW_HAVE_REPORT
  if (!options.figures.empty()) summary["warnings"].push_back("figures need the Qt build (CSW_BUILD_GUI=ON)");
#endif

  // Write-back: one new take version per take, in one transaction.
  if (options.fill) {
    progress.Update("writing filled takes", 0.0);
    CorpusTransaction tx(options.corpus);
    std::set<std::string> existing;
    for (const auto& n : tx.TakeNames()) existing.insert(n);
    json filled = json::array();
    for (size_t i = 0; i < ranges.size(); ++i) {
      Take take = corpus.LoadTake(ranges[i].take);
      int64_t count = 0;
      std::vector<std::string> models_used;
      for (const auto& jp : jobs) {
        const TakeJob& job = *jp;
        if (job.range.spec != ranges[i].spec) continue;
        models_used.push_back(job.run->kind);
        const std::vector<int> cols = BindNames(job.run->set, take.marker_names, job.run->names, ranges[i].take);
        for (int64_t f = 0; f < job.result.frames(); ++f) {
          for (size_t c = 0; c < cols.size(); ++c) {
            float* dst = take.markers.at(ranges[i].first + f, cols[c]);
            const float* src = job.result.reconstructed.at(f, static_cast<int64_t>(c));
            if (!IsMissing(dst[0]) || IsMissing(src[0])) continue;
            std::copy(src, src + 3, dst);
            ++count;
          }
        }
      }
      take.name = FilledName(existing, ranges[i].take);
      existing.insert(take.name);
      std::string used;
      for (const auto& u : models_used) used += (used.empty() ? "" : "+") + u;
      take.provenance.warnings.push_back("gaps filled by csw invert (" + used + " model from " + options.models +
                                         ") from take '" + ranges[i].spec + "': " + std::to_string(count) + " samples");
      tx.WriteTake(take);
      filled.push_back({{"take", ranges[i].spec}, {"filled_take", take.name}, {"samples_filled", count}});
      progress.Update("writing filled takes", static_cast<double>(i + 1) / static_cast<double>(ranges.size()));
    }
    tx.Commit();
    summary["filled"] = filled;
  }
  return summary;
}

std::string InvertText(const json& s) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(3);
  auto stats = [&](const json& j) {
    if (j.value("count", 0) == 0) return std::string("no samples");
    std::ostringstream t;
    t.setf(std::ios::fixed);
    t.precision(3);
    t << j["mean_mm"].get<double>() << " ± " << j["sd_mm"].get<double>() << " mm (max " << j["max_mm"].get<double>()
      << ", n=" << j["count"].get<int64_t>() << ")";
    return t.str();
  };
  for (const char* kind : {"face", "hand"}) {
    if (!s.contains(kind)) continue;
    const json& m = s[kind];
    o << kind << " (target " << m["target_mm"].get<double>() << " mm):\n";
    for (const auto& t : m["takes"]) {
      o << "  " << t["take"].get<std::string>() << " [" << t["role"].get<std::string>() << "] "
        << t["solved_frames"].get<int64_t>() << "/" << t["frames"].get<int64_t>() << " frames, visible "
        << stats(t["visible"]);
      if (t.contains("hidden")) o << ", hidden " << stats(t["hidden"]);
      if (t.contains("occluded")) o << ", occluded " << stats(t["occluded"]);
      o << "\n";
    }
    for (const char* role : {"training", "held_out"}) {
      const json& r = m[role];
      if (r["visible"].value("count", 0) == 0) continue;
      o << "  " << role << ": visible " << stats(r["visible"]);
      if (r.contains("hidden")) {
        o << "; hidden " << stats(r["hidden"]) << " (model alone " << stats(r["hidden_model"]) << ")";
      }
      if (r.contains("occluded")) {
        o << "; occluded " << stats(r["occluded"]) << " (model alone " << stats(r["occluded_model"]) << ")";
      }
      o << "\n";
    }
    if (m["overall"].contains("pose")) {
      const json& p = m["overall"]["pose"];
      if (p["rotation_deg"].value("count", 0) > 0) {
        o << "  pose vs truth: " << p["rotation_deg"]["mean_deg"].get<double>() << "° and "
          << p["translation_mm"]["mean_mm"].get<double>() << " mm on average\n";
      }
    }
  }
  if (s.contains("filled")) {
    for (const auto& f : s["filled"]) {
      o << "filled " << f["samples_filled"].get<int64_t>() << " samples of " << f["take"].get<std::string>()
        << " into new take " << f["filled_take"].get<std::string>() << "\n";
    }
  }
  for (const auto& f : s["figures"]) o << "figure: " << f.get<std::string>() << "\n";
  if (s.contains("warnings")) {
    for (const auto& w : s["warnings"]) o << "warning: " << w.get<std::string>() << "\n";
  }
  return o.str();
}

}  // namespace csw::jobs
