#include "workbench/jobs/model_config.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <set>

#include "core/error.h"
#include "core/file_util.h"
#include "core/json_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

ParseError ConfigError(const std::string& file, const std::string& what) {
  return ParseError(Location{file, std::nullopt, std::nullopt}, what);
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

}  // namespace

ModelConfig ParseModelConfig(const std::string& text, const std::string& path) {
  ModelConfig c;
  const json j = ParseJsonText(text, path);
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
        FaceStepSpec step;
        step.name = Get<std::string>(s, "name", "p" + std::to_string(i + 1), path, w);
        if (s.contains("markers")) step.markers = GetNames(s["markers"], path, w + ".markers");
        step.components = Get<int>(s, "components", 1, path, w);
        c.face_steps.push_back(step);
      }
      if (!c.face_preset.empty()) throw ConfigError(path, "face: give either preset or steps, not both");
    }
    // components sizes the one-step model only; a preset or explicit steps set every step's components,
    // so a components given with them would be silently ignored: refuse it (docs/models.md).
    if (f.contains("components") && (!c.face_preset.empty() || f.contains("steps"))) {
      throw ConfigError(path, std::string("face.components cannot be combined with face.") +
                                  (c.face_preset.empty() ? "steps" : "preset") +
                                  " (they set each step's components; see docs/models.md)");
    }
    if (f.contains("residual_components") && c.face_preset != "seed") {
      throw ConfigError(path, "face.residual_components applies to face.preset \"seed\" only");
    }
  }
  if (j.contains("hand")) {
    const json& h = j["hand"];
    CheckKeys(h, {"angle_components", "ridge", "gaussian_fill"}, path, "hand");
    c.gaussian_fill = Get<bool>(h, "gaussian_fill", true, path, "hand");
    c.angle_components = Get<int>(h, "angle_components", HandModelOptions().angle_components, path, "hand");
    c.ridge = Get<double>(h, "ridge", 0.0, path, "hand");
    if (c.angle_components < 1) throw ConfigError(path, "hand.angle_components must be >= 1");
    if (c.ridge < 0) throw ConfigError(path, "hand.ridge must be >= 0");
  }
  return c;
}

ModelConfig LoadModelConfig(const std::string& path) {
  if (path.empty()) return ModelConfig{};
  return ParseModelConfig(ReadTextFile(path), path);
}

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

}  // namespace csw::jobs
