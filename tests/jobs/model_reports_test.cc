// The default text output of `csw fit` and `csw invert`: FitText and
// InvertText on known JSON summaries, line by line; StatsJson of known stats.
#include "workbench/jobs/model_reports.h"

#include <gtest/gtest.h>

#include <string>

namespace csw::jobs {
namespace {

using nlohmann::json;

json Stats(int64_t n, double mean, double sd, double max) {
  return {{"count", n}, {"mean_mm", mean}, {"sd_mm", sd}, {"max_mm", max}};
}

TEST(ModelReports, StatsJsonOfKnownValues) {
  ErrorStats s;
  for (double v : {1.0, 2.0, 6.0}) s.Add(v);
  const json j = StatsJson(s);
  EXPECT_EQ(j["count"], 3);
  EXPECT_DOUBLE_EQ(j["mean_mm"].get<double>(), 3.0);
  EXPECT_DOUBLE_EQ(j["sd_mm"].get<double>(), std::sqrt(7.0));  // deviations -2, -1, 3: 14 / 2
  EXPECT_DOUBLE_EQ(j["max_mm"].get<double>(), 6.0);
  EXPECT_DOUBLE_EQ(StatsJson(s, "deg")["mean_deg"].get<double>(), 3.0);
  EXPECT_EQ(StatsJson(ErrorStats{}), json({{"count", 0}}));
}

TEST(ModelReports, FitTextRigid) {
  const json s = {{"kind", "rigid"},
                  {"output", "models.h5"},
                  {"training_takes", {"t1", "t2@:50%"}},
                  {"figures", {"f/head_residuals.png"}},
                  {"rigid",
                   {{{"name", "head"},
                     {"motion_parameters", 4},
                     {"training_frames", 1200},
                     {"rms_mm", 0.2104},
                     {"takes",
                      {{{"take", "t1"}, {"residual", Stats(3600, 0.2, 0.05, 0.61)}},
                       {{"take", "t2@:50%"}, {"residual", json{{"count", 0}}}}}}}}}};
  EXPECT_EQ(FitText(s),
            "fitted rigid model(s) into models.h5 from 2 take(s)\n"
            "  head motion: 4 parameters over 1200 frames, cluster rms 0.210 mm\n"
            "    t1: residual 0.200 ± 0.050 mm (max 0.610, n=3600)\n"
            "    t2@:50%: residual no samples\n"
            "  figure: f/head_residuals.png\n");
}

TEST(ModelReports, FitTextFace) {
  const json s = {{"kind", "face"},
                  {"output", "m.h5"},
                  {"training_takes", {"a"}},
                  {"figures", json::array()},
                  {"face",
                   {{"parameters", {"jaw", "lips"}},
                    {"variance_explained", {0.6, 0.25}},
                    {"selected_frames", 80},
                    {"training_frames", 100},
                    {"training_rms_mm", 0.3},
                    {"throat",
                     {{{"marker", "TH1"}, {"head_weight", 0.5}, {"fitted", true}},
                      {{"marker", "TH2"}, {"head_weight", 0.25}, {"fitted", false}}}}}}};
  EXPECT_EQ(FitText(s),
            "fitted face model(s) into m.h5 from 1 take(s)\n"
            "  face: 2 parameters, 80 of 100 frames selected, training rms 0.300 mm\n"
            "    jaw: 60.000 % (cumulated 60.000 %)\n"
            "    lips: 25.000 % (cumulated 85.000 %)\n"
            "    throat TH1: head weight 0.500 (fitted)\n"
            "    throat TH2: head weight 0.250 (fixed)\n");
}

TEST(ModelReports, FitTextHandWithGapFillerAndWarnings) {
  const json s = {{"kind", "hand"},
                  {"output", "m.h5"},
                  {"training_takes", {"a", "b", "c"}},
                  {"figures", json::array()},
                  {"warnings", {"something odd"}},
                  {"hand",
                   {{"parameters", 2},
                    {"angles", 22},
                    {"variance_explained", {0.5, 0.125}},
                    {"selected_frames", 90},
                    {"training_frames", 95},
                    {"training_rms_mm", 0.4567},
                    {"warnings",
                     {"1 angle constant over the training frames, dropped from the regression (the "
                      "intercept holds them): thumb1.twist"}},
                    {"gaussian_fill", {{"frames", 400}, {"iterations", 12}}}}}};
  EXPECT_EQ(FitText(s),
            "fitted hand model(s) into m.h5 from 3 take(s)\n"
            "  hand: 2 parameters from 22 angles, 90 of 95 frames selected, training rms 0.457 mm\n"
            "  hand gap filler: Gaussian, 400 training frames (incomplete ones included), 12 EM rounds\n"
            "    p1: 50.000 % (cumulated 50.000 %)\n"
            "    p2: 12.500 % (cumulated 62.500 %)\n"
            "  hand warning: 1 angle constant over the training frames, dropped from the regression (the intercept "
            "holds them): thumb1.twist\n"
            "  warning: something odd\n");
}

TEST(ModelReports, InvertTextWithTruthHiddenAndFill) {
  json face;
  face["target_mm"] = 1.0;
  face["takes"] = {{{"take", "s1"},
                    {"role", "training"},
                    {"solved_frames", 100},
                    {"frames", 100},
                    {"visible", Stats(900, 0.32, 0.1, 0.9)},
                    {"hidden", Stats(100, 0.5, 0.2, 1.25)},
                    {"occluded", Stats(10, 0.127, 0.05, 0.3)}},
                   {{"take", "s2@50%:"},
                    {"role", "held_out"},
                    {"solved_frames", 48},
                    {"frames", 50},
                    {"visible", Stats(400, 0.3226, 0.1, 1.0)}}};
  face["training"] = {{"visible", Stats(900, 0.32, 0.1, 0.9)},
                      {"hidden", Stats(100, 0.5, 0.2, 1.25)},
                      {"hidden_model", Stats(100, 0.6, 0.2, 1.5)},
                      {"occluded", Stats(10, 0.127, 0.05, 0.3)},
                      {"occluded_model", Stats(10, 0.2, 0.05, 0.4)}};
  face["held_out"] = {{"visible", Stats(400, 0.3226, 0.1, 1.0)}};
  face["overall"] = {{"pose",
                      {{"rotation_deg", {{"count", 150}, {"mean_deg", 0.067}, {"sd_deg", 0.01}, {"max_deg", 0.1}}},
                       {"translation_mm", Stats(150, 0.073, 0.01, 0.1)}}}};
  json hand;
  hand["target_mm"] = 2.0;
  hand["takes"] = json::array();
  hand["training"] = {{"visible", json{{"count", 0}}}};  // no training take: no role line
  hand["held_out"] = {{"visible", Stats(5, 1.362, 0.5, 2.0)}};
  hand["overall"] = json::object();
  const json s = {{"face", face},
                  {"hand", hand},
                  {"filled", {{{"take", "s1"}, {"filled_take", "s1.filled"}, {"samples_filled", 42}}}},
                  {"figures", {"fig/face_errors.png"}}};
  EXPECT_EQ(InvertText(s),
            "face (target 1.000 mm):\n"
            "  s1 [training] 100/100 frames, visible 0.320 ± 0.100 mm (max 0.900, n=900), hidden 0.500 ± 0.200 mm "
            "(max 1.250, n=100), occluded 0.127 ± 0.050 mm (max 0.300, n=10)\n"
            "  s2@50%: [held_out] 48/50 frames, visible 0.323 ± 0.100 mm (max 1.000, n=400)\n"
            "  training: visible 0.320 ± 0.100 mm (max 0.900, n=900); hidden 0.500 ± 0.200 mm (max 1.250, n=100) "
            "(model alone 0.600 ± 0.200 mm (max 1.500, n=100)); occluded 0.127 ± 0.050 mm (max 0.300, n=10) "
            "(model alone 0.200 ± 0.050 mm (max 0.400, n=10))\n"
            "  held_out: visible 0.323 ± 0.100 mm (max 1.000, n=400)\n"
            "  pose vs truth: 0.067° and 0.073 mm on average\n"
            "hand (target 2.000 mm):\n"
            "  held_out: visible 1.362 ± 0.500 mm (max 2.000, n=5)\n"
            "filled 42 samples of s1 into new take s1.filled\n"
            "figure: fig/face_errors.png\n");
}

TEST(ModelReports, StatsJsonOfSamplesHasExactPercentiles) {
  ErrorSamples s;
  for (double v : {4.0, 1.0, 2.0, 3.0, 10.0}) s.Add(v);
  const json j = StatsJson(s);
  EXPECT_EQ(j["count"], 5);
  EXPECT_DOUBLE_EQ(j["mean_mm"].get<double>(), 4.0);
  EXPECT_DOUBLE_EQ(j["max_mm"].get<double>(), 10.0);
  // Sorted 1 2 3 4 10; h = 4 × 0.99 = 3.96: 4 + 0.96 × 6 = 9.76; h = 3.996: 4 + 0.996 × 6 = 9.976.
  EXPECT_NEAR(j["p99_mm"].get<double>(), 9.76, 1e-12);
  EXPECT_NEAR(j["p99_9_mm"].get<double>(), 9.976, 1e-12);
  EXPECT_NEAR(StatsJson(s, "deg")["p99_deg"].get<double>(), 9.76, 1e-12);
  EXPECT_EQ(StatsJson(ErrorSamples{}), json({{"count", 0}}));
}

TEST(ModelReports, InvertTextPercentilesAndWorstFrames) {
  json visible = Stats(900, 0.32, 0.1, 3.5);
  visible["p99_mm"] = 1.25;
  visible["p99_9_mm"] = 2.5;
  json face;
  face["target_mm"] = 1.0;
  face["takes"] = {
      {{"take", "s1"}, {"role", "held_out"}, {"solved_frames", 99}, {"frames", 100}, {"visible", visible}}};
  face["training"] = {{"visible", json{{"count", 0}}}};
  face["held_out"] = {{"visible", visible}};
  face["overall"] = {{"visible", visible}};
  // Ranked by p99.9 among shape markers; cluster markers and markers without samples are left out.
  auto marker = [](const std::string& name, const std::string& role, double p999) {
    json v = Stats(10, 0.3, 0.1, p999 + 0.5);
    v["p99_mm"] = p999 - 0.5;
    v["p99_9_mm"] = p999;
    return json{{"marker", name}, {"role", role}, {"visible", v}};
  };
  face["markers"] = {
      marker("NAS", "cluster", 9.0), marker("LIP1", "shape", 1.5),
      marker("TH2", "shape", 2.5),   marker("JAW", "shape", 0.5),
      marker("TH1", "shape", 2.0),   {{"marker", "TH9"}, {"role", "shape"}, {"visible", json{{"count", 0}}}}};
  face["worst_frames"] = {{{"take", "s1"},
                           {"frame", 42},
                           {"time_s", 0.42},
                           {"model", "face"},
                           {"max_error_mm", 3.5},
                           {"mean_error_mm", 0.75},
                           {"max_error_marker", "TH2"},
                           {"status", "converged"},
                           {"iterations", 7},
                           {"cold_retry", false}},
                          {{"take", "s1"},
                           {"frame", 3},
                           {"time_s", 0.03},
                           {"model", "face"},
                           {"max_error_mm", 2.0},
                           {"mean_error_mm", 0.5},
                           {"max_error_marker", "LIP1"},
                           {"status", "max_iterations"},
                           {"iterations", 30},
                           {"cold_retry", true}}};
  const json s = {{"face", face}, {"figures", json::array()}};
  EXPECT_EQ(InvertText(s),
            "face (target 1.000 mm):\n"
            "  s1 [held_out] 99/100 frames, visible 0.320 ± 0.100 mm (p99 1.250, p99.9 2.500, max 3.500, n=900)\n"
            "  held_out: visible 0.320 ± 0.100 mm (p99 1.250, p99.9 2.500, max 3.500, n=900)\n"
            "  largest p99.9 visible: TH2 2.500 mm, TH1 2.000 mm, LIP1 1.500 mm\n"
            "  worst frames: s1 frame 42 (0.420 s): max 3.500 mm at TH2, mean 0.750 mm, converged, 7 iterations\n"
            "                s1 frame 3 (0.030 s): max 2.000 mm at LIP1, mean 0.500 mm, max_iterations, 30 "
            "iterations, cold retry\n");
}

}  // namespace
}  // namespace csw::jobs
