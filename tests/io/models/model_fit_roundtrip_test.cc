// Models fitted by the real fitters (FitRigidModel, FitFaceModel,
// FitHandModel) on synthetic takes survive a model file unchanged: every field
// is bitwise equal after loading, and the loaded models predict and invert
// exactly as the fitted ones do.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "io/models/model_file.h"
#include "tests/io/models/model_test_util.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

using testing::ExpectSameFace;
using testing::ExpectSameHand;
using testing::ExpectSameMatrix;
using testing::ExpectSameRigid;
using testing::TempDir;

// A smooth pose (a few degrees, a few mm) for frame f.
RigidTransform PoseAt(int f, double phase) {
  Eigen::Matrix<double, 6, 1> p;
  for (int c = 0; c < 6; ++c) {
    const double amp = c < 3 ? 0.05 : 5.0;
    p(c) = amp * std::sin(0.03 * (c + 1) * f + phase + c) + (c == 5 ? 1400.0 : 0.0);
  }
  return RigidTransform::FromParameters(p);
}

void SetColumn(MarkerArray& a, int64_t f, int64_t m, const Eigen::Vector3d& p) {
  for (int k = 0; k < 3; ++k) a.at(f, m)[k] = static_cast<float>(p(k));
}

// Face: 4 head markers, 5 face and 1 throat marker driven by 3 known
// components in the head frame, plus a little noise.
MarkerArray MakeFaceTake(const FaceLayout& layout, int frames, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.05);
  const Eigen::Matrix3Xd head = (Eigen::Matrix3Xd(3, 4) << 60, -60, 0, 0, 0, 0, 70, -20, 40, 40, 60, 90).finished();
  const int ns = layout.num_shape_markers();
  Eigen::MatrixXd mean(3, ns), comp[3];
  for (int j = 0; j < ns; ++j) mean.col(j) = Eigen::Vector3d(10.0 * j - 25, 90 - 3.0 * j, -40 - 15.0 * (j % 3));
  for (int k = 0; k < 3; ++k) {
    comp[k] = Eigen::MatrixXd(3, ns);
    for (int j = 0; j < ns; ++j)
      for (int a = 0; a < 3; ++a) comp[k](a, j) = 2.0 * std::sin(1.3 * k + 0.7 * j + 2.1 * a);
  }
  MarkerArray take(frames, layout.num_markers());
  for (int f = 0; f < frames; ++f) {
    const RigidTransform pose = PoseAt(f, 0.1 * seed);
    for (int i = 0; i < 4; ++i) SetColumn(take, f, i, pose.Apply(head.col(i)));
    Eigen::MatrixXd x = mean;
    for (int k = 0; k < 3; ++k) x += comp[k] * (std::sin(0.05 * (k + 1) * f + k) + 0.3 * noise(rng));
    for (int j = 0; j < ns; ++j) {
      Eigen::Vector3d p = pose.Apply(x.col(j));
      for (int a = 0; a < 3; ++a) p(a) += noise(rng);
      SetColumn(take, f, 4 + j, p);
    }
  }
  return take;
}

// Hand: 3 forearm markers; a palm (3 markers) turned by two wrist angles and
// one finger of two phalanges (2 markers each, sharing the middle one) flexed
// by two angles, all varying smoothly.
MarkerArray MakeHandTake(const HandLayout& layout, int frames, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> noise(0, 0.05);
  const Eigen::Matrix3Xd forearm = (Eigen::Matrix3Xd(3, 3) << -80, -60, -70, 20, -25, 0, 0, 5, 30).finished();
  MarkerArray take(frames, layout.num_markers());
  for (int f = 0; f < frames; ++f) {
    const double t = 0.04 * f + seed;
    const Eigen::Matrix3d wrist = (Eigen::AngleAxisd(0.4 * std::sin(t), Eigen::Vector3d::UnitZ()) *
                                   Eigen::AngleAxisd(0.2 * std::sin(1.7 * t + 1), Eigen::Vector3d::UnitY()))
                                      .toRotationMatrix();
    const double phi = 0.5 + 0.4 * std::sin(1.3 * t + 2), psi = 0.3 + 0.3 * std::sin(0.7 * t + 0.5);
    std::vector<Eigen::Vector3d> palm_local = {{20, -20, 0}, {20, 25, 0}, {70, 0, 8}};
    const Eigen::Vector3d joint(90, 5, 0);
    const Eigen::Vector3d mid = joint + Eigen::AngleAxisd(phi, Eigen::Vector3d::UnitY()) * Eigen::Vector3d(35, 0, 0);
    const Eigen::Vector3d tip =
        mid + Eigen::AngleAxisd(phi + psi, Eigen::Vector3d::UnitY()) * Eigen::Vector3d(25, 0, 0);
    std::vector<Eigen::Vector3d> hand = {palm_local[0], palm_local[1], palm_local[2], joint, mid, tip};
    const RigidTransform pose = PoseAt(f, 0.2 * seed);
    for (int i = 0; i < 3; ++i) SetColumn(take, f, i, pose.Apply(forearm.col(i)));
    for (size_t j = 0; j < hand.size(); ++j) {
      Eigen::Vector3d p = pose.Apply(wrist * hand[j]);
      for (int a = 0; a < 3; ++a) p(a) += noise(rng);
      SetColumn(take, f, 3 + static_cast<int64_t>(j), p);
    }
  }
  return take;
}

void ExpectSameInversion(const InversionResult& a, const InversionResult& b) {
  int64_t solved = 0;
  for (uint8_t s : a.solved) solved += s;
  EXPECT_GE(solved, a.frames() - 1) << "the fitted model should solve the synthetic frames";
  ExpectSameMatrix(a.pose, b.pose, "inversion pose");
  ExpectSameMatrix(a.params, b.params, "inversion params");
  ExpectSameMatrix(a.error_mm, b.error_mm, "inversion error_mm");
  EXPECT_EQ(a.solved, b.solved);
  EXPECT_EQ(a.converged, b.converged);
  ASSERT_EQ(a.reconstructed.data().size(), b.reconstructed.data().size());
  EXPECT_EQ(std::memcmp(a.reconstructed.data().data(), b.reconstructed.data().data(),
                        a.reconstructed.data().size() * sizeof(float)),
            0);
}

TEST(ModelFileFitted, FaceAndHeadModelsPredictAndInvertIdentically) {
  FaceLayout layout;
  layout.head = {"head_a", "head_b", "head_c", "head_d"};
  layout.face = {"jaw", "lip_up", "lip_low", "corner_l", "corner_r"};
  layout.throat = {"throat"};
  layout.throat_weights = {std::numeric_limits<double>::quiet_NaN()};
  const MarkerArray take = MakeFaceTake(layout, 240, 1);
  FaceModelOptions options;
  options.steps = {{"jaw", {0}, 1}, {"lips", {1, 2, 3, 4}, 1}, {"residual", {}, 1}};
  FaceModel face = FitFaceModel(layout, {take}, options);
  face.info.corpus = "synthetic";

  MarkerArray cluster(take.frames(), 4);
  for (int64_t f = 0; f < take.frames(); ++f)
    for (int m = 0; m < 4; ++m)
      for (int k = 0; k < 3; ++k) cluster.at(f, m)[k] = take.at(f, m)[k];
  RigidModel head = FitRigidModel("head", layout.head, {cluster});

  TempDir dir;
  const std::string path = (dir / "face.h5").string();
  ModelFile file;
  file.face = face;
  file.head = head;
  SaveModelFile(path, file);
  const ModelFile loaded = LoadModelFile(path);
  ASSERT_TRUE(loaded.face && loaded.head);
  ExpectSameFace(face, *loaded.face);
  ExpectSameRigid(head, *loaded.head, "head");

  Eigen::VectorXd params(face.num_parameters());
  for (Eigen::Index k = 0; k < params.size(); ++k) params(k) = 0.5 - 0.4 * static_cast<double>(k);
  const RigidTransform pose = PoseAt(17, 0.3);
  ExpectSameMatrix(face.ShapeMarkersInLab(pose, params), loaded.face->ShapeMarkersInLab(pose, params),
                   "face shape markers in the lab");
  ExpectSameMatrix(face.MarkersInLab(pose, params), loaded.face->MarkersInLab(pose, params), "face markers in the lab");

  MarkerArray test = MakeFaceTake(layout, 60, 2);
  for (int64_t f = 0; f < test.frames(); f += 3) test.SetMissing(f, 4 + f % 6);
  ExpectSameInversion(InvertFace(face, test), InvertFace(*loaded.face, test));
}

TEST(ModelFileFitted, HandModelPredictsAndInvertsIdentically) {
  HandLayout layout;
  layout.forearm = {"fa_1", "fa_2", "fa_3"};
  layout.hand = {"palm_1", "palm_2", "palm_3", "knuckle", "middle", "tip"};
  layout.segments = {{"palm", -1, {0, 1, 2}}, {"proximal", 0, {3, 4}}, {"distal", 1, {4, 5}}};
  const MarkerArray take = MakeHandTake(layout, 300, 1);
  HandModelOptions options;
  options.angle_components = 4;
  HandModel hand = FitHandModel(layout, {take}, options);
  hand.info.training_takes = {"synthetic"};

  TempDir dir;
  const std::string path = (dir / "hand.h5").string();
  ModelFile file;
  file.hand = hand;
  UpdateModelFile(path, file);
  const ModelFile loaded = LoadModelFile(path);
  ASSERT_TRUE(loaded.hand);
  ExpectSameHand(hand, *loaded.hand);

  Eigen::VectorXd params(hand.num_parameters());
  for (Eigen::Index k = 0; k < params.size(); ++k) params(k) = 0.1 * static_cast<double>(k + 1);
  const RigidTransform pose = PoseAt(23, 0.7);
  ExpectSameMatrix(hand.shape.Predict(params), loaded.hand->shape.Predict(params), "hand shape prediction");
  ExpectSameMatrix(hand.ShapeMarkersInLab(pose, params), loaded.hand->ShapeMarkersInLab(pose, params),
                   "hand shape markers in the lab");
  ExpectSameMatrix(hand.MarkersInLab(pose, params), loaded.hand->MarkersInLab(pose, params), "hand markers in the lab");

  MarkerArray test = MakeHandTake(layout, 60, 2);
  for (int64_t f = 0; f < test.frames(); f += 4) test.SetMissing(f, 3 + f % 6);
  ExpectSameInversion(InvertHand(hand, test), InvertHand(*loaded.hand, test));
}

}  // namespace
}  // namespace csw
