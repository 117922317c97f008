// The done-when of issue 14 for the duration models: fitted on virtual-signer
// transitions whose durations follow a known plane in the distances, SURFACE
// recovers the plane's coefficients within 5 % and beats SIMPLE and LINEAR in
// cross-validated error; and the distances the analysis measures are the ones
// the simulator's law used.
#include <gtest/gtest.h>

#include <cmath>

#include "datasets/virtual_signer.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/transitions_job.h"

namespace csw::jobs {
namespace {

TEST(VirtualSignerTransitions, SurfaceRecoversTheSimulatedPlaneAndBeatsTheOthers) {
  SignerOptions o;
  o.seed = 11;
  o.theta = {0.12, 0.8, 0.35};  // a plane that is not the seed's
  o.hand_offset_max_s = 0;      // the nominal tier's boundaries are both hands' (the law is on every joint)
  o.min_signs = 4;
  o.max_signs = 7;
  const int count = testing::kSanitized ? 12 : 40;
  Progress progress;
  const std::vector<SignerTake> sim = SimulateSigner(o, count, progress);
  std::vector<Take> takes;
  std::vector<TransitionTruth> truth;  // sign-to-sign transitions, in take order
  for (const SignerTake& s : sim) {
    takes.push_back(s.take);
    for (const TransitionTruth& t : s.transitions) {
      if (t.kind == "transition") truth.push_back(t);
    }
  }
  TransitionsOptions t;
  t.corpus = "virtual signer";
  t.tiers = {kSignsTier};
  t.types = kSignTypesTier;
  t.joints = "all";
  std::vector<signing::Transition> measured;
  const nlohmann::json r = AnalyseTransitions(takes, t, progress, &measured);
  ASSERT_EQ(measured.size(), truth.size());
  double worst_g = 0, worst_e = 0, worst_d = 0;
  for (size_t i = 0; i < truth.size(); ++i) {
    worst_d = std::max(worst_d, std::abs(measured[i].duration_s - truth[i].duration_s));
    worst_g = std::max(worst_g, std::abs(measured[i].geodesic - truth[i].geodesic));
    worst_e = std::max(worst_e, std::abs(measured[i].euclidean - truth[i].euclidean));
  }
  // Durations on the frame grid; G from exact orientations; E from positions
  // with 0.5 mm noise (a still joint's noisy distance is about 1 mm).
  EXPECT_LT(worst_d, 1e-6);
  EXPECT_LT(worst_g, 1e-4);
  EXPECT_LT(worst_e, 0.003);
  const nlohmann::json* surface = nullptr;
  double simple_cv = 0, linear_cv = 0;
  for (const nlohmann::json& m : r["models"]) {
    if (m["model"] == "surface") surface = &m;
    if (m["model"] == "simple") simple_cv = m["cv_mae_s"].get<double>();
    if (m["model"] == "linear") linear_cv = m["cv_mae_s"].get<double>();
  }
  ASSERT_NE(surface, nullptr);
  for (int i = 0; i < 3; ++i) {
    const double fitted = (*surface)["fit"]["theta"][static_cast<size_t>(i)].get<double>();
    EXPECT_NEAR(fitted, o.theta[static_cast<size_t>(i)], 0.05 * o.theta[static_cast<size_t>(i)]) << "theta " << i;
  }
  const double surface_cv = (*surface)["cv_mae_s"].get<double>();
  EXPECT_LT(surface_cv, 0.004);  // the frame grid's rounding: uniform ±5 ms, mean 2.5 ms
  EXPECT_LT(surface_cv, simple_cv);
  EXPECT_LT(surface_cv, linear_cv);
  EXPECT_EQ(r["best"], "surface");
  std::printf(
      "virtual signer: %zu transitions, SURFACE theta (%.4f, %.4f, %.4f), cv MAE surface %.2f ms, "
      "linear %.2f ms, simple %.2f ms; worst |dG| %.2e, |dE| %.2e\n",
      measured.size(), (*surface)["fit"]["theta"][0].get<double>(), (*surface)["fit"]["theta"][1].get<double>(),
      (*surface)["fit"]["theta"][2].get<double>(), surface_cv * 1000, linear_cv * 1000, simple_cv * 1000, worst_g,
      worst_e);
}

}  // namespace
}  // namespace csw::jobs
