#pragma once
// Model configuration (docs/model-format.md, "Configuration"): the JSON file of
// `csw fit --config`, checked strictly (unknown keys and wrong types are
// errors naming the file and the key), and the model layouts made from a
// marker set.
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/markerset.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "models/rigid_model.h"

namespace csw::jobs {

struct FaceStepSpec {
  std::string name;
  std::vector<std::string> markers;
  int components = 1;
};

struct ModelConfig {
  nlohmann::json raw = nlohmann::json::object();
  std::string markerset;  // resolved path (relative to the config file), "" = none
  RigidModelOptions rigid;
  double min_distance_mm = 2.0;
  // face
  int face_components = 6;
  std::string face_preset;  // "", "seed", "mother"
  std::map<std::string, std::vector<std::string>> face_groups;
  int residual_components = 0;
  std::vector<FaceStepSpec> face_steps;
  int throat_weight_rounds = 4;
  // hand
  int angle_components = 20;  // HandModelOptions::angle_components
  double ridge = 0;
  bool gaussian_fill = true;
};

// Reads and checks a configuration file; "" = the defaults. ParseError naming
// the file (and the key) on anything it does not accept; IoError when unreadable.
ModelConfig LoadModelConfig(const std::string& path);
// The same from JSON text; `file` names it in errors and resolves "markerset".
ModelConfig ParseModelConfig(const std::string& text, const std::string& file);

// Layouts of the face and hand models from a marker set; InvalidInput naming
// `set_file` when the set lacks what the model needs.
FaceLayout MakeFaceLayout(const MarkerSet& set, const std::string& set_file);
HandLayout MakeHandLayout(const MarkerSet& set, const std::string& set_file);

// The guided-PCA steps of the face model (face.steps, or face.preset with
// face.groups); empty = one step with face.components. InvalidInput naming
// `file` and the key when a marker is not a face or throat marker of the layout.
std::vector<GuidedPcaStep> FaceSteps(const ModelConfig& config, const FaceLayout& layout, const std::string& file);

// What a model file stores as its configuration: the config and the marker set.
std::string CombinedConfig(const ModelConfig& config, const MarkerSet& set);
// The marker set stored in a model's configuration; ParseError naming the file when absent.
MarkerSet MarkerSetOfModel(const ModelInfo& info, const std::string& model_file);

}  // namespace csw::jobs
