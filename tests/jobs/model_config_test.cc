// Model configuration files (--config): defaults, every section, and errors
// that name the file and the key.
#include "workbench/jobs/model_config.h"

#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "core/error.h"
#include "tests/testing/testing.h"

namespace csw::jobs {
namespace {

std::string ErrorOf(const std::string& text, const std::string& file = "/cfg/model.json") {
  try {
    ParseModelConfig(text, file);
  } catch (const Error& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(ModelConfig, DefaultsWithoutAFile) {
  const ModelConfig c = LoadModelConfig("");
  EXPECT_EQ(c.markerset, "");
  EXPECT_EQ(c.face_components, 6);
  EXPECT_EQ(c.face_preset, "");
  EXPECT_EQ(c.angle_components, 20);  // docs/models.md: the default, 20 (the seed's 12 misfits by 1.8 mm)
  EXPECT_DOUBLE_EQ(c.ridge, 0.0);
  EXPECT_TRUE(c.gaussian_fill);
  EXPECT_DOUBLE_EQ(c.min_distance_mm, 2.0);
  EXPECT_EQ(c.throat_weight_rounds, 4);
  EXPECT_EQ(c.rigid.rigid.loss, RobustLoss::kCauchy);
  EXPECT_DOUBLE_EQ(c.rigid.motion_variance, 0.99);
}

TEST(ModelConfig, EverySection) {
  const ModelConfig c = ParseModelConfig(R"({"format": "csw-model-config", "version": 1, "markerset": "sets/a.json",
      "training": {"min_distance_mm": 1.5},
      "rigid": {"loss": "huber", "loss_scale_mm": 2.5, "motion_variance": 0.9},
      "face": {"throat_weight_rounds": 2,
               "steps": [{"name": "jaw", "markers": ["CHIN"], "components": 1}, {"markers": ["ULM", "LLM"]}]},
      "hand": {"angle_components": 20, "ridge": 0.5, "gaussian_fill": false}})",
                                         "/cfg/model.json");
  EXPECT_EQ(c.markerset, "/cfg/sets/a.json");  // relative to the config file
  EXPECT_DOUBLE_EQ(c.min_distance_mm, 1.5);
  EXPECT_EQ(c.rigid.rigid.loss, RobustLoss::kHuber);
  EXPECT_DOUBLE_EQ(c.rigid.rigid.loss_scale_mm, 2.5);
  EXPECT_DOUBLE_EQ(c.rigid.motion_variance, 0.9);
  EXPECT_EQ(ParseModelConfig(R"({"face": {"components": 4}})", "/cfg/model.json").face_components, 4);
  EXPECT_EQ(c.throat_weight_rounds, 2);
  ASSERT_EQ(c.face_steps.size(), 2u);
  EXPECT_EQ(c.face_steps[0].name, "jaw");
  EXPECT_EQ(c.face_steps[0].markers, (std::vector<std::string>{"CHIN"}));
  EXPECT_EQ(c.face_steps[1].name, "p2");  // default name: p<index + 1>
  EXPECT_EQ(c.face_steps[1].components, 1);
  EXPECT_EQ(c.angle_components, 20);
  EXPECT_DOUBLE_EQ(c.ridge, 0.5);
  EXPECT_FALSE(c.gaussian_fill);
  EXPECT_EQ(ParseModelConfig(R"({"markerset": "/abs/set.json"})", "/cfg/model.json").markerset, "/abs/set.json");
}

TEST(ModelConfig, UnknownKeysAreNamedWithTheFile) {
  EXPECT_EQ(ErrorOf(R"({"facee": {}})"), "/cfg/model.json: config: unknown key 'facee'");
  EXPECT_EQ(ErrorOf(R"({"face": {"componets": 3}})"), "/cfg/model.json: face: unknown key 'componets'");
  EXPECT_EQ(ErrorOf(R"({"face": {"groups": {"chin": []}}})"), "/cfg/model.json: face.groups: unknown key 'chin'");
  EXPECT_EQ(ErrorOf(R"({"face": {"steps": [{"name": "a", "marker": []}]}})"),
            "/cfg/model.json: face.steps[0]: unknown key 'marker'");
  EXPECT_EQ(ErrorOf(R"({"hand": {"ridge": 1, "angles": 3}})"), "/cfg/model.json: hand: unknown key 'angles'");
}

TEST(ModelConfig, WrongTypesAndValuesAreNamed) {
  EXPECT_EQ(ErrorOf(R"({"face": {"components": "six"}})"), "/cfg/model.json: face.components has the wrong type");
  EXPECT_EQ(ErrorOf(R"({"hand": {"gaussian_fill": 1}})"), "/cfg/model.json: hand.gaussian_fill has the wrong type");
  EXPECT_EQ(ErrorOf(R"({"face": []})"), "/cfg/model.json: face must be a JSON object");
  EXPECT_EQ(ErrorOf(R"({"face": {"steps": {}}})"), "/cfg/model.json: face.steps must be an array");
  EXPECT_EQ(ErrorOf(R"({"face": {"groups": {"jaw": [1]}}})"),
            "/cfg/model.json: face.groups.jaw must be an array of marker names");
  EXPECT_EQ(ErrorOf(R"({"face": {"components": 0}})"), "/cfg/model.json: face.components must be >= 1");
  EXPECT_EQ(ErrorOf(R"({"rigid": {"loss": "l2"}})"), "/cfg/model.json: rigid.loss must be cauchy, huber or none");
  EXPECT_EQ(ErrorOf(R"({"rigid": {"motion_variance": 1.5}})"),
            "/cfg/model.json: rigid.motion_variance must be in (0, 1]");
  EXPECT_EQ(ErrorOf(R"({"hand": {"ridge": -1}})"), "/cfg/model.json: hand.ridge must be >= 0");
  EXPECT_EQ(ErrorOf(R"({"format": "csw-markerset"})"), "/cfg/model.json: config: format must be \"csw-model-config\"");
  EXPECT_EQ(ErrorOf(R"({"version": 2})"), "/cfg/model.json: config: version newer than 1");
  EXPECT_NE(ErrorOf("{not json", "/cfg/broken.json").find("/cfg/broken.json"), std::string::npos);
}

FaceLayout Layout() {
  FaceLayout l;
  l.head = {"H1", "H2", "H3"};
  l.face = {"CHIN", "ULM", "LLM", "LC", "RC"};
  l.throat = {"TH1"};
  l.throat_weights = {0.5};
  return l;
}

TEST(ModelConfig, PresetWithGroups) {
  const ModelConfig c = ParseModelConfig(R"({"face": {"preset": "seed", "residual_components": 2, "groups": {
      "jaw": ["CHIN"], "lip_rounding": ["ULM", "LLM", "LC", "RC"], "lips_upper": ["ULM"], "lips_lower": ["LLM"],
      "lip_corners": ["LC", "RC"], "throat": ["TH1"]}}})",
                                         "/cfg/seed.json");
  EXPECT_EQ(c.face_preset, "seed");
  EXPECT_EQ(c.residual_components, 2);
  const std::vector<GuidedPcaStep> steps = FaceSteps(c, Layout(), "/cfg/seed.json");
  // Seed §3.1: jaw, lip rounding, upper lip, lower lip, corners, throat, then the residual.
  ASSERT_EQ(steps.size(), 7u);
  EXPECT_EQ(steps[0].markers, (std::vector<int>{0}));
  EXPECT_EQ(steps[1].markers, (std::vector<int>{1, 2, 3, 4}));
  EXPECT_EQ(steps[4].markers, (std::vector<int>{3, 4}));
  EXPECT_EQ(steps[5].markers, (std::vector<int>{5}));  // throat markers follow the face markers
  EXPECT_EQ(steps[6].name, "residual");
  EXPECT_EQ(steps[6].components, 2);
  EXPECT_EQ(ErrorOf(R"({"face": {"preset": "seed"}})"),
            "/cfg/model.json: face.preset needs face.groups (jaw, lip_rounding, lips_upper, ...)");
  EXPECT_EQ(ErrorOf(R"({"face": {"preset": "wild", "groups": {"jaw": []}}})"),
            "/cfg/model.json: face.preset must be \"seed\" or \"mother\"");
  EXPECT_EQ(ErrorOf(R"({"face": {"preset": "mother", "groups": {"jaw": ["A"]}, "steps": []}})"),
            "/cfg/model.json: face: give either preset or steps, not both");
  // components with a preset or steps would be ignored: refused with the key.
  EXPECT_EQ(ErrorOf(R"({"face": {"preset": "seed", "components": 4, "groups": {"jaw": ["A"]}}})"),
            "/cfg/model.json: face.components cannot be combined with face.preset (they set each step's components; "
            "see docs/models.md)");
  EXPECT_EQ(ErrorOf(R"({"face": {"components": 4, "steps": [{"markers": ["A"]}]}})"),
            "/cfg/model.json: face.components cannot be combined with face.steps (they set each step's components; "
            "see docs/models.md)");
  EXPECT_EQ(ErrorOf(R"({"face": {"preset": "mother", "residual_components": 2, "groups": {"jaw": ["A"]}}})"),
            "/cfg/model.json: face.residual_components applies to face.preset \"seed\" only");
  EXPECT_EQ(ErrorOf(R"({"face": {"components": 4}})"), "(no error)");
  // A group naming a marker the layout lacks: the file, the key and the marker.
  const ModelConfig bad = ParseModelConfig(R"({"face": {"preset": "mother", "groups": {"jaw": ["NOSE"]}}})", "m.json");
  try {
    FaceSteps(bad, Layout(), "m.json");
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_STREQ(e.what(), "m.json: face.groups.jaw: marker 'NOSE' is not a face or throat marker of the marker set");
  }
}

TEST(ModelConfig, FilesAreNamedInErrors) {
  testing::TempDir dir;
  const std::string path = (dir / "typo.json").string();
  std::ofstream(path) << R"({"hand": {"angle_component": 3}})";
  try {
    LoadModelConfig(path);
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(std::string(e.what()), path + ": hand: unknown key 'angle_component'");
  }
  const std::string missing = (dir / "missing.json").string();
  try {
    LoadModelConfig(missing);
    FAIL() << "expected IoError";
  } catch (const IoError& e) {
    EXPECT_EQ(std::string(e.what()).rfind(missing, 0), 0u) << e.what();
  }
}

}  // namespace
}  // namespace csw::jobs
