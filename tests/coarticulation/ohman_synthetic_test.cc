// Öhman fitting (analysis/coarticulation/ohman.h) on parameter series made by
// the model itself with known vowel targets, rest value, w, c and k style:
// the fit must give them back exactly (to the grid of the k-style search).
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/coarticulation/ohman.h"
#include "core/error.h"

namespace csw::coarticulation {
namespace {

constexpr double kRate = 100.0;

Eigen::VectorXd V3(double a, double b, double c) { return Eigen::Vector3d(a, b, c); }

// The model that makes the data: 3 parameters, vowels a i u, consonants p
// (one parameter with w = 0: c not identifiable) and s.
OhmanFit TruthModel() {
  OhmanFit f;
  f.num_parameters = 3;
  f.vowels = {"a", "i", "u"};
  f.vowel_targets.resize(3, 3);
  f.vowel_targets << 4.0, -1.0, 0.5,  // a
      -2.0, 1.5, -1.0,                // i
      1.0, 3.0, 2.0;                  // u
  f.rest = V3(0.2, -0.3, 0.1);
  OhmanConsonant p;
  p.consonant = "p";
  p.w = V3(0.8, 0.3, 0.0);
  p.c = V3(-3.0, 2.0, std::nan(""));
  p.intercept = V3(0.8 * -3.0, 0.3 * 2.0, 0.0);
  p.measured_effect = Eigen::MatrixXd::Zero(3, 3);
  p.k_style.left_inset_s = 0.012;
  p.k_style.left_ramp_s = 0.064;
  p.k_style.right_inset_s = 0.02;
  p.k_style.right_ramp_s = 0.09;
  OhmanConsonant s = p;
  s.consonant = "s";
  s.w = V3(0.5, 1.0, 0.6);
  s.c = V3(1.0, -2.0, 4.0);
  s.intercept = s.w.cwiseProduct(s.c);
  s.k_style.left_inset_s = -0.01;
  s.k_style.left_ramp_s = 0.05;
  s.k_style.right_inset_s = 0.004;
  s.k_style.right_ramp_s = 0.04;
  f.consonants = {p, s};
  return f;
}

// A take: isolated a, i, u, then V C V for every consonant and vowel, each
// between 0.3 s pauses; phone boundaries on the frame grid.
ParameterSeries MakeTake(const OhmanFit& truth, const std::vector<std::string>& consonants, double c_duration) {
  std::vector<Label> phones;
  double t = 0.3;
  for (const char* v : {"a", "i", "u"}) {
    phones.push_back({t, t + 0.12, v});
    t += 0.12 + 0.3;
  }
  for (const std::string& c : consonants)
    for (const char* v : {"a", "i", "u"}) {
      phones.push_back({t, t + 0.12, v});
      phones.push_back({t + 0.12, t + 0.12 + c_duration, c});
      phones.push_back({t + 0.12 + c_duration, t + 0.24 + c_duration, v});
      t += 0.24 + c_duration + 0.3;
    }
  ParameterSeries s;
  s.name = "synthetic";
  s.rate_hz = kRate;
  s.phones = phones;
  const auto frames = static_cast<int>(std::lround(t * kRate));
  std::vector<double> times;
  for (int f = 0; f < frames; ++f) times.push_back(f / kRate);
  s.values = GenerateOhman(truth, NormalisePhones(phones, t), times);
  return s;
}

TEST(OhmanSynthetic, RecoversTargetsFactorsAndEmergenceExactly) {
  const OhmanFit truth = TruthModel();
  const ParameterSeries take = MakeTake(truth, {"p", "s"}, 0.1);
  const OhmanFit fit = FitOhman({take});
  ASSERT_EQ(fit.tokens.size(), 6u);  // 2 consonants × 3 vowels
  for (int v = 0; v < 3; ++v) {
    EXPECT_EQ(fit.vowel_source[static_cast<size_t>(v)], "isolated");
    for (int x = 0; x < 3; ++x) EXPECT_NEAR(fit.vowel_targets(v, x), truth.vowel_targets(v, x), 1e-9);
  }
  for (int x = 0; x < 3; ++x) EXPECT_NEAR(fit.rest[x], truth.rest[x], 1e-9);
  for (const OhmanConsonant& known : truth.consonants) {
    const OhmanConsonant* c = fit.Find(known.consonant);
    ASSERT_NE(c, nullptr) << known.consonant;
    EXPECT_EQ(c->tokens, 3);
    for (int x = 0; x < 3; ++x) {
      EXPECT_NEAR(c->w[x], known.w[x], 1e-9) << known.consonant << " x" << x;
      EXPECT_NEAR(c->residual[x], 0.0, 1e-9);
      if (std::isfinite(known.c[x])) {
        ASSERT_TRUE(c->Identifiable(x));
        EXPECT_NEAR(c->c[x], known.c[x], 1e-9) << known.consonant << " x" << x;
      } else {
        EXPECT_FALSE(c->Identifiable(x));  // w = 0: c is not identifiable
      }
      // The effect w (c − v_V) per context, fitted and measured.
      for (int j = 0; j < 3; ++j) {
        const double v = truth.vowel_targets(j, x);
        const double e = known.intercept[x] - known.w[x] * v;
        EXPECT_NEAR(c->effect(j, x), e, 1e-9);
        EXPECT_NEAR(c->measured_effect(j, x), e, 1e-9);
      }
    }
    EXPECT_NEAR(c->k_style.left_inset_s, known.k_style.left_inset_s, 1e-4) << known.consonant;
    EXPECT_NEAR(c->k_style.left_ramp_s, known.k_style.left_ramp_s, 1e-4) << known.consonant;
    EXPECT_NEAR(c->k_style.right_inset_s, known.k_style.right_inset_s, 1e-4) << known.consonant;
    EXPECT_NEAR(c->k_style.right_ramp_s, known.k_style.right_ramp_s, 1e-4) << known.consonant;
    EXPECT_LT(c->k_style.rms, 1e-6);
    // Mean k reaches 1 at the consonant centre.
    double k_centre = std::nan("");
    for (size_t i = 0; i < c->mean_k_times_s.size(); ++i)
      if (std::abs(c->mean_k_times_s[i]) < 1e-9) k_centre = c->mean_k[i];
    EXPECT_NEAR(k_centre, 1.0, 1e-9);
  }
  // Per-token k against the known style at every frame.
  for (const VcvToken& t : fit.tokens) {
    const KStyle& ks = truth.Find(t.consonant)->k_style;
    for (size_t i = 0; i < t.k.size(); ++i) {
      const double expected = ks.Evaluate(t.k_times_s[i], t.c_start_s, t.c_end_s);
      // Frames where every effect is below the threshold have no k; the
      // others must match.
      if (std::isfinite(t.k[i])) {
        EXPECT_NEAR(t.k[i], expected, 1e-9);
      }
    }
  }
  // Regenerating from the fit reproduces the data.
  std::vector<double> times;
  for (Eigen::Index f = 0; f < take.values.rows(); ++f) times.push_back(static_cast<double>(f) / kRate);
  const double duration = static_cast<double>(take.values.rows()) / kRate;
  const Eigen::MatrixXd again = GenerateOhman(fit, NormalisePhones(take.phones, duration), times);
  EXPECT_LT((again - take.values).cwiseAbs().maxCoeff(), 1e-3);
}

TEST(OhmanSynthetic, KStyleEvaluateHandValues) {
  KStyle k;
  k.left_inset_s = 0.01;
  k.left_ramp_s = 0.04;
  k.right_inset_s = 0.0;
  k.right_ramp_s = 0.1;
  // Interval [1.0, 1.2]: left ramp over [0.97, 1.01], plateau [1.01, 1.2], right ramp [1.2, 1.3].
  EXPECT_DOUBLE_EQ(k.Evaluate(0.96, 1.0, 1.2), 0.0);
  EXPECT_NEAR(k.Evaluate(0.99, 1.0, 1.2), 0.5, 1e-12);  // half way up: 0.5 (1 − cos(π/2))
  EXPECT_DOUBLE_EQ(k.Evaluate(1.1, 1.0, 1.2), 1.0);
  EXPECT_NEAR(k.Evaluate(1.25, 1.0, 1.2), 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(k.Evaluate(1.31, 1.0, 1.2), 0.0);
}

TEST(OhmanSynthetic, NotIdentifiableWithoutSpreadAndErrors) {
  OhmanFit truth = TruthModel();
  // Parameter 2 takes the same value in every vowel: the line through the
  // contexts has no slope, w is undefined and the effect is the measured one.
  truth.vowel_targets.col(2).setConstant(0.5);
  const ParameterSeries take = MakeTake(truth, {"s"}, 0.1);
  const OhmanFit fit = FitOhman({take});
  const OhmanConsonant* s = fit.Find("s");
  ASSERT_NE(s, nullptr);
  EXPECT_TRUE(std::isnan(s->w[2]));
  EXPECT_FALSE(s->Identifiable(2));
  for (int j = 0; j < 3; ++j) EXPECT_NEAR(s->effect(j, 2), 0.6 * (4.0 - 0.5), 1e-9);
  // A vowel never alone: its reference comes from VCV vowel centres, with a warning.
  ParameterSeries no_iso = take;
  no_iso.phones.erase(no_iso.phones.begin(), no_iso.phones.begin() + 3);
  const OhmanFit f2 = FitOhman({no_iso});
  EXPECT_EQ(f2.vowel_source[0], "vcv");
  EXPECT_FALSE(f2.warnings.empty());
  // No token at all; parameter counts differ; bad options.
  ParameterSeries empty = take;
  empty.phones = {{0.3, 0.42, "a"}};
  EXPECT_THROW(FitOhman({empty}), InvalidInput);
  ParameterSeries narrow = take;
  narrow.values = take.values.leftCols(2);
  try {
    FitOhman({take, narrow});
    ADD_FAILURE() << "no throw";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("has 2 parameters"), std::string::npos) << e.what();
  }
  OhmanOptions bad;
  bad.min_w = 0;
  EXPECT_NE(bad.Check(), "");
  EXPECT_THROW(GenerateOhman(fit, {{0.0, 0.1, "x"}}, {0.05}), InvalidInput);
  // Left out when asked: an unknown phone between [asa] and a pause changes nothing.
  GenerateOptions lenient;
  lenient.skip_unknown = true;
  const std::vector<Label> known = {
      {0.0, 0.3, ""}, {0.3, 0.42, "a"}, {0.42, 0.52, "s"}, {0.52, 0.64, "a"}, {0.64, 1.0, ""}};
  std::vector<Label> with_unknown = known;
  with_unknown.insert(with_unknown.begin() + 4, Label{0.64, 0.7, "x"});
  with_unknown.back().start_s = 0.7;
  const std::vector<double> times = {0.36, 0.47, 0.58, 0.8};
  const Eigen::MatrixXd a = GenerateOhman(fit, known, times, lenient);
  const Eigen::MatrixXd b = GenerateOhman(fit, with_unknown, times, lenient);
  EXPECT_LT((a - b).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(OhmanSynthetic, NormalisePhonesFillsGapsWithPauses) {
  const std::vector<Label> out = NormalisePhones({{0.5, 0.6, "p"}, {0.2, 0.5, "a"}, {0.7, 0.8, "sil"}}, 1.0);
  ASSERT_EQ(out.size(), 4u);
  EXPECT_EQ(out[0].text, "");
  EXPECT_DOUBLE_EQ(out[0].end_s, 0.2);
  EXPECT_EQ(out[1].text, "a");
  EXPECT_EQ(out[2].text, "p");
  EXPECT_EQ(out[3].text, "");  // gap 0.6-0.7 and "sil" 0.7-0.8 and the tail merge into one pause
  EXPECT_DOUBLE_EQ(out[3].start_s, 0.6);
  EXPECT_DOUBLE_EQ(out[3].end_s, 1.0);
}

}  // namespace
}  // namespace csw::coarticulation
