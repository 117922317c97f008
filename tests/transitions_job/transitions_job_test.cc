// csw transitions on hand-built skeleton takes whose transition durations
// follow a known plane in the distances (the done-when's recovery lives in
// the virtual-signer tests; here the job's parsing, wiring and output).
#include "workbench/jobs/transitions_job.h"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>

#include "core/build_paths.h"
#include "core/error.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {
namespace {

// hips → spine → {neck, RightShoulder → RightElbow → RightWrist → RightTip,
// LeftShoulder → LeftElbow → LeftWrist → LeftTip}
std::vector<SkeletonJoint> Skeleton() {
  const char* names[] = {"hips",     "spine",        "neck",      "RightShoulder", "RightElbow", "RightWrist",
                         "RightTip", "LeftShoulder", "LeftElbow", "LeftWrist",     "LeftTip"};
  const int parents[] = {-1, 0, 1, 1, 3, 4, 5, 1, 7, 8, 9};
  std::vector<SkeletonJoint> s;
  for (int i = 0; i < 11; ++i) {
    SkeletonJoint j;
    j.name = names[i];
    j.parent = parents[i];
    j.end_site = i == 6 || i == 10;
    s.push_back(j);
  }
  return s;
}

// A take of `signs` signs on the right hand. During sign k every right-arm
// joint j (3..6) is still at x = 100·(j−2)·p_k mm, rotated by 0.1·(j−2)·r_k rad
// about z, with random amplitudes p_k, r_k; between signs the amplitudes move
// linearly. So a transition's mean Euclidean distance is 0.25 m·|Δp| and its
// mean geodesic distance 0.125·|Δr|, and its duration is set to
// d = 0.1 + 0.5 G + 0.3 E rounded to the frame grid.
Take PlaneTake(const std::string& name, int signs, uint32_t seed, std::vector<std::array<double, 3>>* truth) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> scale(0.3, 1.5);
  const double rate = 100;
  std::vector<double> amp(static_cast<size_t>(signs)), rot(static_cast<size_t>(signs));
  for (double& a : amp) a = scale(rng);
  for (double& a : rot) a = 3 * scale(rng);
  // Distances between posture k and k+1 (joint j: offset (j−2)·100 mm · Δa, angle (j−2)·0.1·Δa).
  std::vector<double> starts, ends;
  double t = 0.1;
  for (int k = 0; k < signs; ++k) {
    starts.push_back(t);
    t += 0.3;
    ends.push_back(t);
    if (k + 1 < signs) {
      const double e = std::abs(amp[static_cast<size_t>(k + 1)] - amp[static_cast<size_t>(k)]) * 0.25;
      const double g = std::abs(rot[static_cast<size_t>(k + 1)] - rot[static_cast<size_t>(k)]) * 0.125;
      const double d = std::round((0.1 + 0.5 * g + 0.3 * e) * rate) / rate;  // on the frame grid
      truth->push_back({d, g, e});
      t += d;
    }
  }
  const auto frames = static_cast<int64_t>(std::ceil((t + 0.1) * rate)) + 1;
  Take take;
  take.name = name;
  take.rate_hz = rate;
  take.skeleton = Skeleton();
  for (const SkeletonJoint& j : take.skeleton) take.marker_names.push_back(j.name);
  take.markers.Resize(frames, 11);
  take.orientations.Resize(frames, 11);
  for (int64_t f = 0; f < frames; ++f) {
    const double time = static_cast<double>(f) / rate;
    // The amplitude at this time: constant in signs, linear in transitions.
    double a = amp[0], r = rot[0];
    for (int k = 0; k < signs; ++k) {
      const auto uk = static_cast<size_t>(k);
      if (time >= starts[uk] - 1e-9) {
        a = amp[uk];
        r = rot[uk];
      }
      if (k + 1 < signs && time > ends[uk] && time < starts[uk + 1]) {
        const double u = (time - ends[uk]) / (starts[uk + 1] - ends[uk]);
        a = amp[uk] + u * (amp[uk + 1] - amp[uk]);
        r = rot[uk] + u * (rot[uk + 1] - rot[uk]);
      }
    }
    for (int j = 0; j < 11; ++j) {
      const double arm = (j >= 3 && j <= 6) ? (j - 2) : 0.0;
      float* p = take.markers.at(f, j);
      p[0] = static_cast<float>(100.0 * arm * a);
      p[1] = static_cast<float>(10.0 * j);
      p[2] = 0;
      const Eigen::Quaterniond q(Eigen::AngleAxisd(0.1 * arm * r, Eigen::Vector3d::UnitZ()));
      float* o = take.orientations.at(f, j);
      o[0] = static_cast<float>(q.w());
      o[1] = static_cast<float>(q.x());
      o[2] = static_cast<float>(q.y());
      o[3] = static_cast<float>(q.z());
    }
  }
  LabelTier right{"right_hand", LabelTier::Kind::kInterval, 0.0, take.duration_s(), {}};
  LabelTier types{"sign_types", LabelTier::Kind::kInterval, 0.0, take.duration_s(), {}};
  for (int k = 0; k < signs; ++k) {
    right.labels.push_back({starts[static_cast<size_t>(k)], ends[static_cast<size_t>(k)], "S" + std::to_string(k)});
    if (k + 1 < signs) right.labels.push_back({ends[static_cast<size_t>(k)], starts[static_cast<size_t>(k + 1)], ""});
    types.labels.push_back(
        {starts[static_cast<size_t>(k)], ends[static_cast<size_t>(k)], k % 2 ? "symmetric" : "one_hand"});
  }
  take.tiers = {right, types};
  return take;
}

TEST(TransitionsJob, OptionChecksNameTheProblem) {
  TransitionsOptions o;
  EXPECT_NE(o.Check().find("corpus"), std::string::npos);
  o.corpus = "c.h5";
  EXPECT_EQ(o.Check(), "");
  o.joints = "legs";
  EXPECT_NE(o.Check().find("--joints"), std::string::npos);
  o.joints = "arm";
  o.length_unit = "ft";
  EXPECT_NE(o.Check().find("--length-unit"), std::string::npos);
  o.length_unit = "cm";
  o.models = {"surface", "spline"};
  EXPECT_NE(o.Check().find("spline"), std::string::npos);
  o.models = {"surface"};
  o.wrists = {"right_hand"};
  EXPECT_NE(o.Check().find("TIER=JOINT"), std::string::npos);
  o.wrists = {"face=Nose"};
  EXPECT_NE(o.Check().find("'face'"), std::string::npos);
  o.wrists = {"right_hand=RWr"};
  o.folds = 1;
  EXPECT_NE(o.Check().find("--folds"), std::string::npos);
}

TEST(TransitionsJob, FindsWristsOfOtherLabsNames) {
  auto skeleton = [](std::vector<std::string> names) {
    std::vector<SkeletonJoint> s;
    for (const std::string& n : names) s.push_back({n, static_cast<int>(s.size()) - 1, {0, 0, 0}, {}, false});
    return s;
  };
  EXPECT_EQ(FindWrist(skeleton({"Hips", "RightArm", "RightForeArm", "RightHand", "RightHandIndex1"}), "right"), 3);
  EXPECT_EQ(FindWrist(skeleton({"pelvis", "l_wrist", "r_wrist"}), "right"), 2);
  EXPECT_EQ(FindWrist(skeleton({"pelvis", "LWrist", "RWrist"}), "left"), 1);
  EXPECT_EQ(FindWrist(skeleton({"pelvis", "rhand_thumb", "rhand"}), "right"), -1);  // "rhand": no side prefix form
  EXPECT_EQ(FindWrist(skeleton({"pelvis", "spine"}), "left"), -1);
}

TEST(TransitionsJob, RecoversAKnownPlaneAndReportsIt) {
  std::vector<Take> takes;
  std::vector<std::array<double, 3>> truth;  // duration, G, E per transition
  for (int i = 0; i < 4; ++i)
    takes.push_back(PlaneTake("t" + std::to_string(i), 8, 10u + static_cast<uint32_t>(i), &truth));
  TransitionsOptions o;
  o.corpus = "in-memory";
  Progress progress;
  std::vector<signing::Transition> ts;
  const nlohmann::json r = AnalyseTransitions(takes, o, progress, &ts);
  ASSERT_EQ(ts.size(), truth.size());
  for (size_t i = 0; i < ts.size(); ++i) {
    EXPECT_NEAR(ts[i].duration_s, truth[i][0], 1e-9);
    EXPECT_NEAR(ts[i].geodesic, truth[i][1], 1e-6);  // float storage of the quaternions
    EXPECT_NEAR(ts[i].euclidean, truth[i][2], 1e-6);
  }
  EXPECT_EQ(r["transitions"], 28);
  EXPECT_EQ(r["takes"][0]["tiers"][0]["wrist"], "RightWrist");
  EXPECT_EQ(r["takes"][0]["tiers"][0]["joints"], 4);  // RightShoulder, RightElbow, RightWrist, RightTip
  // Types alternate one hand / symmetric: only 0011 and 1100 occur, 14 each.
  ASSERT_EQ(r["per_type"].size(), 2u);
  EXPECT_EQ(r["per_type"][0]["type"], "0011");
  EXPECT_EQ(r["per_type"][0]["count"], 16);
  EXPECT_EQ(r["per_type"][1]["type"], "1100");
  EXPECT_EQ(r["per_type"][1]["count"], 12);
  // The durations are the plane rounded to frames (±5 ms): SURFACE recovers
  // it within what that rounding allows, and predicts within the rounding.
  const nlohmann::json& surface = r["models"][3];
  ASSERT_EQ(surface["model"], "surface");
  EXPECT_NEAR(surface["fit"]["theta"][0].get<double>(), 0.1, 0.01);
  EXPECT_NEAR(surface["fit"]["theta"][1].get<double>(), 0.5, 0.03);
  EXPECT_NEAR(surface["fit"]["theta"][2].get<double>(), 0.3, 0.03);
  EXPECT_LT(surface["cv_mae_s"].get<double>(), 0.0035);
  EXPECT_EQ(r["best"], "surface");
  const std::string text = TransitionsText(r);
  EXPECT_NE(text.find("0011"), std::string::npos) << text;
  EXPECT_NE(text.find("best (lowest cross-validated error): surface"), std::string::npos) << text;
}

#ifdef CSW_FIGURES_MODULE_FILE
TEST(TransitionsJob, DrawsTheDurationFigure) {
  ::setenv("CSW_FIGURES_MODULE", CSW_FIGURES_MODULE_FILE, 1);
  testing::TempDir dir;
  std::vector<Take> takes;
  std::vector<std::array<double, 3>> truth;
  for (int i = 0; i < 3; ++i)
    takes.push_back(PlaneTake("t" + std::to_string(i), 8, 20u + static_cast<uint32_t>(i), &truth));
  TransitionsOptions o;
  o.corpus = "in-memory";
  o.figures = (dir.path() / "figures").string();
  Progress progress;
  const nlohmann::json r = AnalyseTransitions(takes, o, progress);
  ASSERT_EQ(r["figures"].size(), 1u);
  // A PNG of a real size: four panels of points and lines (tens of kB; an
  // empty canvas compresses to a few kB).
  const std::filesystem::path png = r["figures"][0].get<std::string>();
  std::ifstream in(png, std::ios::binary);
  unsigned char h[24] = {};
  in.read(reinterpret_cast<char*>(h), 24);
  EXPECT_EQ(std::string(reinterpret_cast<char*>(h) + 1, 3), "PNG");
  const int width = (h[16] << 24) | (h[17] << 16) | (h[18] << 8) | h[19];
  EXPECT_GE(width, 900);
  EXPECT_GT(std::filesystem::file_size(png), 20000u);
  ::unsetenv("CSW_FIGURES_MODULE");
}
#endif

}  // namespace
}  // namespace csw::jobs
