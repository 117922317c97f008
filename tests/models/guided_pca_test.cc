#include "models/guided_pca.h"

#include <gtest/gtest.h>

#include <Eigen/QR>
#include <Eigen/SVD>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "core/error.h"

namespace csw {
namespace {

// Largest principal angle (radians) between the column spans of a and b.
double SubspaceAngle(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  const Eigen::MatrixXd qa =
      Eigen::HouseholderQR<Eigen::MatrixXd>(a).householderQ() * Eigen::MatrixXd::Identity(a.rows(), a.cols());
  const Eigen::MatrixXd qb =
      Eigen::HouseholderQR<Eigen::MatrixXd>(b).householderQ() * Eigen::MatrixXd::Identity(b.rows(), b.cols());
  // sin of the largest angle = norm of the part of qb outside span(qa).
  const Eigen::MatrixXd outside = qb - qa * (qa.transpose() * qb);
  Eigen::JacobiSVD<Eigen::MatrixXd> svd(outside);
  return std::asin(std::min(1.0, svd.singularValues()(0)));
}

// Zero-mean, mutually orthogonal score columns (exactly, up to rounding).
Eigen::MatrixXd OrthogonalScores(int frames, const std::vector<double>& scales, std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  Eigen::MatrixXd s(frames, static_cast<Eigen::Index>(scales.size()) + 1);
  s.col(0).setOnes();
  for (Eigen::Index c = 1; c < s.cols(); ++c)
    for (int r = 0; r < frames; ++r) s(r, c) = n(rng);
  Eigen::MatrixXd q =
      Eigen::HouseholderQR<Eigen::MatrixXd>(s).householderQ() * Eigen::MatrixXd::Identity(frames, s.cols());
  Eigen::MatrixXd out = q.rightCols(static_cast<Eigen::Index>(scales.size()));
  for (size_t c = 0; c < scales.size(); ++c) out.col(static_cast<Eigen::Index>(c)) *= scales[c];
  return out;
}

// 8 markers: 0..2 jaw, 3..6 lips, 7 throat. A jaw component moves every
// marker (the jaw carries the lips); a lip component moves lips only; a throat
// component moves the throat only.
struct Synthetic {
  Eigen::MatrixXd data;
  Eigen::MatrixXd components;  // 24 × 3: jaw, lip, throat directions
  Eigen::MatrixXd scores;      // frames × 3
  Eigen::VectorXd mean;
};

Synthetic MakeSynthetic(int frames, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0, 1);
  Synthetic s;
  s.components = Eigen::MatrixXd::Zero(24, 3);
  for (int i = 0; i < 24; ++i) s.components(i, 0) = n(rng);
  for (int i = 9; i < 21; ++i) s.components(i, 1) = n(rng);
  for (int i = 21; i < 24; ++i) s.components(i, 2) = n(rng);
  s.scores = OrthogonalScores(frames, {40.0, 25.0, 5.0}, rng);
  s.mean = Eigen::VectorXd::LinSpaced(24, -50, 70);
  s.data = (s.scores * s.components.transpose()).rowwise() + s.mean.transpose();
  return s;
}

std::vector<GuidedPcaStep> Steps() { return {{"jaw", {0, 1, 2}, 1}, {"lip", {3, 4, 5, 6}, 1}, {"throat", {7}, 1}}; }

TEST(GuidedPca, RecoversKnownComponentsAndVarianceFractions) {
  const Synthetic s = MakeSynthetic(200, 1);
  const GuidedPcaModel m = FitGuidedPca(s.data, Steps());
  ASSERT_EQ(m.num_parameters(), 3);
  EXPECT_EQ(m.parameter_names, (std::vector<std::string>{"jaw", "lip", "throat"}));
  EXPECT_LT((m.mean - s.mean).norm(), 1e-10);
  for (int k = 0; k < 3; ++k) {
    const double angle = SubspaceAngle(m.loadings.col(k), s.components.col(k));
    EXPECT_LT(angle, 1e-6) << "component " << k;
    std::printf("component %d angle without noise: %.3g rad\n", k, angle);
  }
  // Variance of component k: ‖scores_k‖²‖C_k‖² / total (scores orthogonal).
  const Eigen::MatrixXd centred = s.data.rowwise() - s.data.colwise().mean();
  const double total = centred.squaredNorm();
  double sum = 0;
  for (int k = 0; k < 3; ++k) {
    const double expected = s.scores.col(k).squaredNorm() * s.components.col(k).squaredNorm() / total;
    EXPECT_NEAR(m.variance_explained[static_cast<size_t>(k)], expected, 1e-10);
    sum += m.variance_explained[static_cast<size_t>(k)];
  }
  EXPECT_NEAR(sum, 1.0, 1e-10);
  EXPECT_NEAR(m.residual_variance, 0.0, 1e-10);
  // Parameters are unit-variance scores: the training frames estimate to them.
  for (int f = 0; f < 5; ++f) {
    const Eigen::VectorXd p = m.Estimate(s.data.row(f).transpose());
    for (int k = 0; k < 3; ++k) {
      const double expected = s.scores(f, k) / (s.scores.col(k).norm() / std::sqrt(199.0));
      EXPECT_NEAR(std::abs(p(k)), std::abs(expected), 1e-8);
    }
  }
}

TEST(GuidedPca, FractionsAddUpWithNoiseAndResidualStep) {
  Synthetic s = MakeSynthetic(300, 2);
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0, 0.02);  // throat score std is 0.29
  for (Eigen::Index i = 0; i < s.data.size(); ++i) s.data.data()[i] += noise(rng);
  std::vector<GuidedPcaStep> steps = Steps();
  steps.push_back({"residual", {}, 2});
  const GuidedPcaModel m = FitGuidedPca(s.data, steps);
  ASSERT_EQ(m.num_parameters(), 5);
  EXPECT_EQ(m.parameter_names[3], "residual1");
  EXPECT_EQ(m.parameter_names[4], "residual2");
  double sum = m.residual_variance;
  for (double v : m.variance_explained) sum += v;
  EXPECT_NEAR(sum, 1.0, 1e-10);
  // Noise is small next to the components: they are still found closely.
  for (int k = 0; k < 3; ++k) {
    const double angle = SubspaceAngle(m.loadings.col(k), s.components.col(k));
    EXPECT_LT(angle, 0.05) << k;
    std::printf("component %d angle with noise: %.3g rad\n", k, angle);
  }
}

TEST(GuidedPca, PredictEstimateRoundTripWithHiddenCoordinates) {
  const Synthetic s = MakeSynthetic(100, 4);
  const GuidedPcaModel m = FitGuidedPca(s.data, Steps());
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1.5);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 20; ++trial) {
    Eigen::VectorXd params(3);
    for (int k = 0; k < 3; ++k) params(k) = n(rng);
    const Eigen::VectorXd x = m.Predict(params);
    // Hide 30% of the coordinates, keeping at least one of each group visible.
    std::vector<bool> visible(24, true);
    int hidden = 0;
    while (hidden < 7) {
      const int i = static_cast<int>(u(rng) * 24) % 24;
      if (visible[static_cast<size_t>(i)] && i != 0 && i != 10 && i != 22) {
        visible[static_cast<size_t>(i)] = false;
        ++hidden;
      }
    }
    Eigen::VectorXd observed = x;
    for (int i = 0; i < 24; ++i)
      if (!visible[static_cast<size_t>(i)]) observed(i) = NAN;
    const Eigen::VectorXd p = m.Estimate(observed, visible);
    EXPECT_LT((p - params).norm(), 1e-8 * (1 + params.norm()));
    EXPECT_LT((m.Predict(p) - x).norm(), 1e-8 * x.norm());
  }
}

TEST(GuidedPca, MarkerMaskExpandsToCoordinates) {
  EXPECT_EQ(CoordinateMaskFromMarkers({true, false}), (std::vector<bool>{true, true, true, false, false, false}));
}

TEST(GuidedPca, RejectsBadInput) {
  const Synthetic s = MakeSynthetic(50, 6);
  EXPECT_THROW(FitGuidedPca(s.data, {{"x", {8}, 1}}), InvalidInput);
  EXPECT_THROW(FitGuidedPca(s.data, {{"x", {1, 1}, 1}}), InvalidInput);
  EXPECT_THROW(FitGuidedPca(s.data, {{"x", {7}, 4}}), InvalidInput);
  EXPECT_THROW(FitGuidedPca(s.data, {{"x", {7}, 0}}), InvalidInput);
  EXPECT_THROW(FitGuidedPca(s.data, {}), InvalidInput);
  EXPECT_THROW(FitGuidedPca(s.data.leftCols(23), Steps()), InvalidInput);
  EXPECT_THROW(FitGuidedPca(s.data.topRows(1), Steps()), InvalidInput);
  Eigen::MatrixXd bad = s.data;
  bad(3, 4) = NAN;
  EXPECT_THROW(FitGuidedPca(bad, Steps()), InvalidInput);
  // After jaw, lip and throat the data has nothing left: a 4th step is empty.
  std::vector<GuidedPcaStep> steps = Steps();
  steps.push_back({"residual", {}, 1});
  EXPECT_THROW(FitGuidedPca(s.data, steps), InvalidInput);
  const GuidedPcaModel m = FitGuidedPca(s.data, Steps());
  EXPECT_THROW(m.Predict(Eigen::VectorXd::Zero(2)), InvalidInput);
  EXPECT_THROW(m.Estimate(Eigen::VectorXd::Zero(23)), InvalidInput);
  EXPECT_THROW(m.Estimate(Eigen::VectorXd::Zero(24), std::vector<bool>(24, false)), InvalidInput);
  Eigen::VectorXd x = Eigen::VectorXd::Zero(24);
  x(2) = INFINITY;
  EXPECT_THROW(m.Estimate(x), InvalidInput);
}

TEST(GuidedPca, FacePresetsFollowTheSeeds) {
  FaceMarkerGroups g;
  g.jaw = {0, 1};
  g.lip_rounding = {2, 3, 4, 5};
  g.lips_upper = {2, 3};
  g.lips_lower = {4, 5};
  g.lip_corners = {6, 7};
  g.throat = {8};
  const auto seed = SeedFaceSteps(g, 2);
  ASSERT_EQ(seed.size(), 7u);
  EXPECT_EQ(seed[0].name, "jaw");
  EXPECT_EQ(seed[4].markers, (std::vector<int>{6, 7}));
  EXPECT_EQ(seed[5].name, "throat");
  EXPECT_TRUE(seed[6].markers.empty());
  EXPECT_EQ(seed[6].components, 2);
  const auto mother = MotherFaceSteps(g);
  ASSERT_EQ(mother.size(), 4u);
  EXPECT_EQ(mother[1].markers, (std::vector<int>{2, 3, 4, 5, 6, 7}));
  EXPECT_EQ(mother[1].components, 3);
  EXPECT_EQ(mother[2].name, "jaw_advance");
  EXPECT_EQ(mother[2].markers, g.jaw);
  // Both presets fit data built on those groups; MOTHER gives 6 parameters.
  std::mt19937 rng(8);
  std::normal_distribution<double> n(0, 1);
  Eigen::MatrixXd data(120, 27);
  for (Eigen::Index i = 0; i < data.size(); ++i) data.data()[i] = n(rng);
  EXPECT_EQ(FitGuidedPca(data, mother).num_parameters(), 6);
  EXPECT_EQ(FitGuidedPca(data, seed).num_parameters(), 8);
}

}  // namespace
}  // namespace csw
