#include "models/rigid_model.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/error.h"
#include "models/inversion.h"

namespace csw {
namespace {

Eigen::Matrix3Xd Cluster() {
  Eigen::Matrix3Xd s(3, 5);
  s << 60, -60, 0, 0, 45,  //
      0, 0, 80, -20, 50,   //
      10, 10, 30, 90, -40;
  return s;
}

// Frames where the cluster only translates along lab x by a known amount.
MarkerArray TranslatedTake(const Eigen::Matrix3Xd& shape, const std::vector<double>& dx) {
  MarkerArray m(static_cast<int64_t>(dx.size()), shape.cols());
  for (size_t f = 0; f < dx.size(); ++f) {
    for (Eigen::Index c = 0; c < shape.cols(); ++c) {
      float* p = m.at(static_cast<int64_t>(f), c);
      p[0] = static_cast<float>(shape(0, c) + dx[f]);
      p[1] = static_cast<float>(shape(1, c));
      p[2] = static_cast<float>(shape(2, c));
    }
  }
  return m;
}

TEST(RigidModel, ReferenceShapeAndOneMotionComponentFromTwoTakes) {
  const Eigen::Matrix3Xd shape = Cluster();
  std::vector<double> a, b;
  for (int f = 0; f < 40; ++f) a.push_back(0.5 * f);
  for (int f = 0; f < 30; ++f) b.push_back(-0.25 * f);
  std::vector<MarkerArray> takes{TranslatedTake(shape, a), TranslatedTake(shape, b)};
  takes[1].SetMissing(3, 2);  // a gap does not stop the fit (4 markers remain)
  const RigidModel model = FitRigidModel("head", {"A", "B", "C", "D", "E"}, takes);
  EXPECT_EQ(model.name, "head");
  EXPECT_EQ(model.info.training_frames, 70);
  EXPECT_EQ(model.info.selected_frames, 70);
  EXPECT_LT(model.info.training_rms_mm, 1e-4);  // float storage only
  // Same shape: every pairwise distance kept.
  for (int i = 0; i < 5; ++i)
    for (int j = i + 1; j < 5; ++j)
      EXPECT_NEAR((model.reference.col(i) - model.reference.col(j)).norm(), (shape.col(i) - shape.col(j)).norm(), 1e-4);
  // Only tx varies: one component along the tx axis (up to sign), explaining everything.
  ASSERT_EQ(model.motion.count(), 1);
  EXPECT_NEAR(std::abs(model.motion.components(3, 0)), 1.0, 1e-6);
  EXPECT_NEAR(model.motion.explained_fraction(0), 1.0, 1e-9);
  // Variance of tx over the 70 frames (translations of a rigid body are exact).
  std::vector<double> all = a;
  all.insert(all.end(), b.begin(), b.end());
  double mean = 0, var = 0;
  for (double v : all) mean += v / 70.0;
  for (double v : all) var += (v - mean) * (v - mean) / 69.0;
  EXPECT_NEAR(model.motion.variances(0), var, 1e-6 * var);
}

TEST(RigidModel, ErrorsNameTheModel) {
  const Eigen::Matrix3Xd shape = Cluster();
  EXPECT_THROW(FitRigidModel("head", {"A", "B"}, {}), InvalidInput);
  std::vector<MarkerArray> takes{TranslatedTake(shape, {0, 1, 2})};
  try {
    FitRigidModel("forearm", {"A", "B", "C", "D"}, takes);
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("forearm model"), std::string::npos) << e.what();
  }
  MarkerArray empty(4, 5);  // all missing
  try {
    FitRigidModel("head", {"A", "B", "C", "D", "E"}, {empty});
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("no training frame"), std::string::npos) << e.what();
  }
}

TEST(Inversion, SummariseErrorsKnownValues) {
  const double nan = std::nan("");
  Eigen::MatrixXd e(3, 3);
  e << 1, 2, nan,  //
      3, nan, 5,   //
      nan, 4, 6;
  const ErrorStats all = SummariseErrors(e);
  EXPECT_EQ(all.count, 6);
  EXPECT_DOUBLE_EQ(all.mean, 3.5);
  EXPECT_NEAR(all.sd, std::sqrt(17.5 / 5.0), 1e-12);
  EXPECT_DOUBLE_EQ(all.max, 6);
  const ErrorStats col0 = SummariseErrors(e, {0});
  EXPECT_EQ(col0.count, 2);
  EXPECT_DOUBLE_EQ(col0.mean, 2);
  const ErrorStats rows12 = SummariseErrors(e, {}, 1, 2);
  EXPECT_EQ(rows12.count, 4);
  EXPECT_DOUBLE_EQ(rows12.mean, 4.5);
  EXPECT_EQ(SummariseErrors(e, {}, 3).count, 0);
  EXPECT_THROW(SummariseErrors(e, {3}), InvalidInput);
  EXPECT_THROW(SummariseErrors(e, {}, 4), InvalidInput);
}

TEST(Inversion, MarkerDistancesKnownValues) {
  MarkerArray a(2, 2), b(2, 2);
  for (int f = 0; f < 2; ++f)
    for (int m = 0; m < 2; ++m) {
      float* p = a.at(f, m);
      float* q = b.at(f, m);
      p[0] = p[1] = p[2] = 1.0f;
      q[0] = 4.0f;
      q[1] = 5.0f;
      q[2] = 1.0f;
    }
  b.SetMissing(1, 1);
  const Eigen::MatrixXd d = MarkerDistances(a, b);
  EXPECT_DOUBLE_EQ(d(0, 0), 5.0);
  EXPECT_DOUBLE_EQ(d(1, 0), 5.0);
  EXPECT_TRUE(std::isnan(d(1, 1)));
  EXPECT_THROW(MarkerDistances(a, MarkerArray(3, 2)), InvalidInput);
}

}  // namespace
}  // namespace csw

namespace csw {
namespace {

TEST(Inversion, GapEdgeResidualsAreInterpolatedAcrossGaps) {
  // One marker, 10 frames; the model misses by (1, 0, 0) before a gap and by
  // (3, 0, 0) after it: inside, the correction goes linearly from 1 to 3.
  MarkerArray input(10, 1);
  InversionResult r;
  r.reconstructed = MarkerArray(10, 1);
  for (int f = 0; f < 10; ++f) {
    float* rec = r.reconstructed.at(f, 0);
    rec[0] = rec[1] = rec[2] = 0.0f;
    float* in = input.at(f, 0);
    in[0] = f < 5 ? 1.0f : 3.0f;
    in[1] = in[2] = 0.0f;
  }
  for (int f = 3; f < 6; ++f) input.SetMissing(f, 0);  // gap [3, 6): edges at 2 (misfit 1) and 6 (misfit 3)
  input.SetMissing(9, 0);                              // trailing gap: one edge (misfit 3 at frame 8)
  EXPECT_EQ(CorrectGapsWithEdgeResiduals(input, &r, 4), 4);
  EXPECT_FLOAT_EQ(r.reconstructed.at(3, 0)[0], 1.5f);
  EXPECT_FLOAT_EQ(r.reconstructed.at(4, 0)[0], 2.0f);
  EXPECT_FLOAT_EQ(r.reconstructed.at(5, 0)[0], 2.5f);
  EXPECT_FLOAT_EQ(r.reconstructed.at(9, 0)[0], 3.0f * 0.75f);  // fades over 4 frames
  EXPECT_FLOAT_EQ(r.reconstructed.at(2, 0)[0], 0.0f);          // visible samples untouched
  EXPECT_FLOAT_EQ(r.reconstructed.at(4, 0)[1], 0.0f);
  EXPECT_THROW(CorrectGapsWithEdgeResiduals(MarkerArray(9, 1), &r), InvalidInput);
}

}  // namespace
}  // namespace csw
