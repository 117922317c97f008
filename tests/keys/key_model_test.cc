#include "analysis/keys/key_model.h"

#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "core/error.h"
#include "core/labels.h"

namespace csw::keys {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Analytic log density of N(mean, cov) at x (all dimensions observed).
double LogPdf(const Eigen::VectorXd& x, const Eigen::VectorXd& mean, const Eigen::MatrixXd& cov) {
  const Eigen::VectorXd e = x - mean;
  const double q = e.dot(cov.inverse() * e);
  return -0.5 * (x.size() * std::log(2 * std::numbers::pi) + std::log(cov.determinant()) + q);
}

Eigen::MatrixXd Cov3(double a, double b, double c, double ab, double ac, double bc) {
  Eigen::MatrixXd m(3, 3);
  m << a, ab, ac, ab, b, bc, ac, bc, c;
  return m;
}

GaussianOptions Exact() {
  GaussianOptions o;
  o.shrinkage_samples = 0;
  o.ridge_fraction = 0;
  o.min_variance = 1e-12;
  return o;
}

TEST(GaussianClassifier, FitRecoversMeansAndCovariancesOfSyntheticClasses) {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> n01;
  const Eigen::Vector3d mean0(10, -5, 3), mean1(-20, 4, 8);
  const Eigen::MatrixXd cov0 = Cov3(4, 9, 1, 2, 0.5, -1), cov1 = Cov3(1, 1, 16, 0.3, -2, 1);
  const Eigen::MatrixXd l0 = cov0.llt().matrixL(), l1 = cov1.llt().matrixL();
  const int per_class = 20000;
  Eigen::MatrixXd x(2 * per_class, 3);
  std::vector<int> y;
  for (int i = 0; i < 2 * per_class; ++i) {
    const Eigen::Vector3d z(n01(rng), n01(rng), n01(rng));
    const bool one = i % 2 == 1;
    x.row(i) = (one ? Eigen::Vector3d(mean1 + l1 * z) : Eigen::Vector3d(mean0 + l0 * z)).transpose();
    y.push_back(one ? 1 : 0);
  }
  const auto g = GaussianClassifier::Fit(x, y, 3, {"a", "b", "c"}, {"x", "y", "z"}, Exact());
  ASSERT_EQ(g.classes().size(), 2u);  // label 2 has no sample: absent
  const auto& c0 = g.classes()[0];
  const auto& c1 = g.classes()[1];
  EXPECT_EQ(c0.label, 0);
  EXPECT_EQ(c1.label, 1);
  EXPECT_EQ(c0.count, per_class);
  // Mean error sd = sqrt(var / n) <= 4 / 141 = 0.03: 5 sd = 0.15.
  EXPECT_LT((c0.mean - mean0).cwiseAbs().maxCoeff(), 0.15);
  EXPECT_LT((c1.mean - mean1).cwiseAbs().maxCoeff(), 0.15);
  // Covariance entries: relative sd ~ sqrt(2 / n) = 1 %; allow 5 % of the largest variance.
  EXPECT_LT((c0.covariance - cov0).cwiseAbs().maxCoeff(), 0.05 * 9);
  EXPECT_LT((c1.covariance - cov1).cwiseAbs().maxCoeff(), 0.05 * 16);
  EXPECT_DOUBLE_EQ(c0.prior, 0.5);

  // Posterior of a point = Bayes rule with the fitted densities.
  const Eigen::Vector3d p(-5, 0, 5);
  double post[3];
  g.Posterior(p.data(), post);
  const double l0p = LogPdf(p, c0.mean, c0.covariance), l1p = LogPdf(p, c1.mean, c1.covariance);
  EXPECT_NEAR(post[0], 1.0 / (1.0 + std::exp(l1p - l0p)), 1e-12);
  EXPECT_NEAR(post[0] + post[1], 1.0, 1e-12);
  EXPECT_EQ(post[2], 0.0);
}

TEST(GaussianClassifier, RegularisationAndCountPriorsAreAsStated) {
  // Two classes, samples chosen so the raw covariances are known exactly.
  Eigen::MatrixXd x(6, 2);
  x << 0, 0, 2, 0, 1, 3,       // class 0: mean (1, 1)
      10, 10, 12, 10, 11, 13;  // class 1: same spread, mean (11, 11)
  const std::vector<int> y = {0, 0, 0, 1, 1, 1};
  GaussianOptions o;
  o.shrinkage_samples = 0;
  o.ridge_fraction = 0.1;
  o.min_variance = 0.5;
  o.priors = PriorKind::kCounts;
  const auto g = GaussianClassifier::Fit(x, y, 2, {"a", "b"}, {"u", "v"}, o);
  // Raw covariance of {(0,0),(2,0),(1,3)} about (1,1), divided by n - 1 = 2:
  // xx = (1 + 1 + 0) / 2 = 1, yy = (1 + 1 + 4) / 2 = 3, xy = (1 - 1 + 0) / 2 = 0.
  // Ridge = 0.1 * (1 + 3) / 2 + 0.5 = 0.7.
  EXPECT_NEAR(g.classes()[0].covariance(0, 0), 1.7, 1e-12);
  EXPECT_NEAR(g.classes()[0].covariance(1, 1), 3.7, 1e-12);
  EXPECT_NEAR(g.classes()[0].covariance(0, 1), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(g.classes()[0].prior, 0.5);

  // Shrinkage τ = 2 towards the pooled covariance (equal to each class's here) keeps it.
  o.shrinkage_samples = 2;
  const auto s = GaussianClassifier::Fit(x, y, 2, {"a", "b"}, {"u", "v"}, o);
  EXPECT_NEAR(s.classes()[1].covariance(1, 1), 3.7, 1e-12);

  // A one-sample class borrows the pooled covariance entirely.
  Eigen::MatrixXd x3(7, 2);
  x3 << x, Eigen::RowVector2d(50, 50);
  std::vector<int> y3 = y;
  y3.push_back(2);
  o.priors = PriorKind::kCounts;
  const auto t = GaussianClassifier::Fit(x3, y3, 3, {"a", "b", "c"}, {"u", "v"}, o);
  EXPECT_NEAR(t.classes()[2].covariance(1, 1), 3.7, 1e-12);
  EXPECT_NEAR(t.classes()[2].prior, 1.0 / 7.0, 1e-12);
}

TEST(GaussianClassifier, MissingDimensionsAreMarginalisedExactly) {
  GaussianClass a, b;
  a.label = 0;
  a.name = "a";
  a.prior = 0.3;
  a.mean = Eigen::Vector3d(1, 2, 3);
  a.covariance = Cov3(4, 2, 3, 1, -0.5, 0.7);
  b.label = 2;
  b.name = "b";
  b.prior = 0.7;
  b.mean = Eigen::Vector3d(-1, 0, 5);
  b.covariance = Cov3(1, 5, 2, 0.2, 0.1, -1);
  const auto g = GaussianClassifier::FromClasses({a, b}, 3, {"x", "y", "z"}, Exact());

  // Complete frame (fast path) = the analytic density + log prior.
  const Eigen::Vector3d x(0.5, 1.5, 4);
  double out[3];
  g.LogJoint(x.data(), out);
  EXPECT_NEAR(out[0], LogPdf(x, a.mean, a.covariance) + std::log(0.3), 1e-10);
  EXPECT_NEAR(out[2], LogPdf(x, b.mean, b.covariance) + std::log(0.7), 1e-10);
  EXPECT_EQ(out[1], -std::numeric_limits<double>::infinity());

  // y missing: the analytic marginal over (x, z) keeps rows/columns 0 and 2.
  const double xm[3] = {0.5, kNaN, 4};
  g.LogJoint(xm, out);
  auto marginal = [](const GaussianClass& c) {
    Eigen::Vector2d m(c.mean(0), c.mean(2));
    Eigen::Matrix2d s;
    s << c.covariance(0, 0), c.covariance(0, 2), c.covariance(2, 0), c.covariance(2, 2);
    return LogPdf(Eigen::Vector2d(0.5, 4), m, s);
  };
  EXPECT_NEAR(out[0], marginal(a) + std::log(0.3), 1e-10);
  EXPECT_NEAR(out[2], marginal(b) + std::log(0.7), 1e-10);

  // One observed value: a 1D normal density.
  const double x1[3] = {kNaN, kNaN, 4};
  g.LogJoint(x1, out);
  const double expect_a = -0.5 * (std::log(2 * std::numbers::pi * 3) + (4 - 3) * (4 - 3) / 3.0) + std::log(0.3);
  EXPECT_NEAR(out[0], expect_a, 1e-12);

  // Nothing observed: the posteriors are the priors.
  const double none[3] = {kNaN, kNaN, kNaN};
  double post[3];
  g.Posterior(none, post);
  EXPECT_NEAR(post[0], 0.3, 1e-12);
  EXPECT_NEAR(post[2], 0.7, 1e-12);
}

TEST(GaussianClassifier, TrainingWithMissingValuesUsesAvailableCases) {
  // Dimension 1 is missing on half of the samples: the mean of dim 0 uses all,
  // that of dim 1 the others.
  Eigen::MatrixXd x(4, 2);
  x << 2, 10, 0, kNaN, 4, 14, 6, kNaN;
  const auto g = GaussianClassifier::Fit(x, {0, 0, 0, 0}, 1, {"a"}, {"u", "v"}, Exact());
  EXPECT_DOUBLE_EQ(g.classes()[0].mean(0), 3.0);
  EXPECT_DOUBLE_EQ(g.classes()[0].mean(1), 12.0);
  // var(u) over 4 samples = (1 + 9 + 1 + 9) / 3; var(v) over 2 = (4 + 4) / 1;
  // cov(u, v) over rows 0, 2: ((2-3)(10-12) + (4-3)(14-12)) / 1 = 4.
  EXPECT_NEAR(g.classes()[0].covariance(0, 0), 20.0 / 3.0, 1e-9);
  EXPECT_NEAR(g.classes()[0].covariance(1, 1), 8.0, 1e-9);
  EXPECT_NEAR(g.classes()[0].covariance(0, 1), 4.0, 1e-9);

  // An indefinite pairwise matrix is clipped to positive semi-definite: with
  // rows (0,10), (4,14) and u alone elsewhere at 2 and 6 the pairwise matrix is
  // [[20/3, 8], [8, 8]] (determinant < 0); clipping leaves the rank-1 part, so
  // cov(u,v)^2 = var(u) var(v) up to the tiny floor.
  Eigen::MatrixXd z(4, 2);
  z << 0, 10, 2, kNaN, 4, 14, 6, kNaN;
  const auto h = GaussianClassifier::Fit(z, {0, 0, 0, 0}, 1, {"a"}, {"u", "v"}, Exact());
  const Eigen::MatrixXd& c = h.classes()[0].covariance;
  EXPECT_NEAR(c(0, 1) * c(0, 1), c(0, 0) * c(1, 1), 1e-6);
  EXPECT_NEAR(c.trace(), 20.0 / 3.0 + 8.0 + 0.694, 0.01);  // trace minus the clipped eigenvalue -0.694
}

TEST(GaussianClassifier, RejectsBadInput) {
  Eigen::MatrixXd x(2, 2);
  x << 0, 0, 1, 1;
  EXPECT_THROW(GaussianClassifier::Fit(x, {0, 5}, 2, {"a", "b"}, {"u", "v"}, {}), InvalidInput);
  GaussianOptions bad;
  bad.min_variance = 0;
  EXPECT_THROW(GaussianClassifier::Fit(x, {0, 1}, 2, {"a", "b"}, {"u", "v"}, bad), InvalidInput);
  GaussianClass c;
  c.label = 0;
  c.name = "a";
  c.prior = 1;
  c.mean = Eigen::Vector2d(0, 0);
  c.covariance = Eigen::Matrix2d::Identity() * -1;
  EXPECT_THROW(GaussianClassifier::FromClasses({c}, 1, {"u", "v"}, {}), InvalidInput);
}

TEST(KeyCodes, TargetFramesFromTheLabelTiers) {
  EXPECT_EQ(KeyCode(2, 5), "25");
  LabelTier keys{"keys", LabelTier::Kind::kPoint, 0, 2, {{0.1, 0.1, "00"}, {0.5, 0.5, "25"}, {1.0, 1.0, "31"}}};
  LabelTier places{"placement_targets", LabelTier::Kind::kPoint, 0, 2, {{0.52, 0.52, "25"}, {1.05, 1.05, "31"}}};
  const KeyLabels l = LabelsFromTargets(ReadKeyTargets({keys, places}, "take1"), 100.0, 200, "take1");
  EXPECT_EQ(l.shape_frames, (std::vector<int64_t>{10, 50, 100}));
  EXPECT_EQ(l.shapes, (std::vector<int>{0, 5, 1}));
  EXPECT_EQ(l.placement_frames, (std::vector<int64_t>{52, 105}));
  EXPECT_EQ(l.placements, (std::vector<int>{2, 3}));
  EXPECT_EQ(l.placement_shapes, (std::vector<int>{5, 1}));
  const KeyLabels same = LabelsFromTargets(ReadKeyTargets({keys}, "take1"), 100.0, 200, "take1");
  EXPECT_EQ(same.placement_frames, same.shape_frames);
  EXPECT_EQ(same.placements, (std::vector<int>{0, 2, 3}));
  // Times past the take's end land on its last frame.
  const KeyLabels clipped = LabelsFromTargets(ReadKeyTargets({keys}, "take1"), 100.0, 60, "take1");
  EXPECT_EQ(clipped.shape_frames, (std::vector<int64_t>{10, 50, 59}));
  EXPECT_THROW(LabelsFromTargets(ReadKeyTargets({keys}, "take1"), 0.0, 60, "take1"), InvalidInput);
}

}  // namespace
}  // namespace csw::keys
