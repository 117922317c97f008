#include "models/hand_model.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <Eigen/QR>
#include <cmath>
#include <cstdio>
#include <random>

#include "core/error.h"
#include "models/joint_angles.h"

namespace csw {
namespace {

Eigen::Matrix3d Ry(double a) { return Eigen::AngleAxisd(a, Eigen::Vector3d::UnitY()).toRotationMatrix(); }

// A hand of hinge segments, all children of the forearm: segment s has an
// origin and markers fixed in its own frame (m0 at the origin, m1 on +x, the
// others in the x-y plane with y > 0), and rotates about its y axis by its
// flexion. Positions are then exactly [1, cos f, sin f]-linear, and the
// segment frames measured on the markers are Ry(f): angles (f, 0, 0).
struct HingeHand {
  HandLayout layout;
  Eigen::Matrix3Xd forearm;               // cluster in the forearm frame
  std::vector<Eigen::Vector3d> origins;   // per segment
  std::vector<Eigen::Matrix3Xd> locals;   // per segment, 3 × markers
  std::vector<std::vector<int>> members;  // hand marker indices per segment

  int segments() const { return static_cast<int>(origins.size()); }
  int nh() const { return layout.num_shape_markers(); }
  int nf() const { return static_cast<int>(forearm.cols()); }

  // Hand markers in the forearm frame for per-segment flexions.
  Eigen::Matrix3Xd Local(const Eigen::VectorXd& flexion) const {
    Eigen::Matrix3Xd out(3, nh());
    for (int s = 0; s < segments(); ++s) {
      for (size_t j = 0; j < members[s].size(); ++j) {
        out.col(members[s][j]) = origins[s] + Ry(flexion(s)) * locals[s].col(static_cast<Eigen::Index>(j));
      }
    }
    return out;
  }

  // The exact regression coefficients of Local (3 angles per segment; only flexion used).
  Eigen::MatrixXd Coefficients() const {
    const int n = 3 * segments();
    Eigen::MatrixXd x = Eigen::MatrixXd::Zero(1 + 2 * n, 3 * nh());
    for (int s = 0; s < segments(); ++s) {
      for (size_t j = 0; j < members[s].size(); ++j) {
        const Eigen::Vector3d l = locals[s].col(static_cast<Eigen::Index>(j));
        const int c = 3 * members[s][j];
        x.block<1, 3>(0, c) = (origins[s] + Eigen::Vector3d(0, l(1), 0)).transpose();
        x.block<1, 3>(1 + 3 * s, c) = Eigen::RowVector3d(l(0), 0, l(2));
        x.block<1, 3>(1 + n + 3 * s, c) = Eigen::RowVector3d(l(2), 0, -l(0));
      }
    }
    return x;
  }
};

HingeHand MakeHingeHand(int segments, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  HingeHand h;
  h.forearm.resize(3, 5);
  h.forearm << 0, -24, 24, 2, -30,  //
      -80, -140, -150, -205, -60,   //
      29, 22, 20, 30, 6;
  for (int c = 0; c < 5; ++c) h.layout.forearm.push_back("FA" + std::to_string(c));
  int next = 0;
  for (int s = 0; s < segments; ++s) {
    const int k = 3 + s % 2;  // 3 or 4 markers
    h.origins.emplace_back(-40 + 20 * s, 30 + 5 * u(rng), 10 * u(rng));
    Eigen::Matrix3Xd l(3, k);
    l.col(0).setZero();
    l.col(1) << 25 + 5 * u(rng), 0, 0;
    for (int j = 2; j < k; ++j) l.col(j) << 15 * u(rng), 8 + 6 * j + 2 * u(rng), 0;
    h.locals.push_back(l);
    HandSegmentDef seg;
    seg.name = "seg" + std::to_string(s);
    seg.parent = -1;
    std::vector<int> idx;
    for (int j = 0; j < k; ++j) {
      idx.push_back(next);
      h.layout.hand.push_back("S" + std::to_string(s) + "M" + std::to_string(j));
      ++next;
    }
    seg.markers = idx;
    h.members.push_back(idx);
    h.layout.segments.push_back(seg);
  }
  return h;
}

// Random orthonormal n × k.
Eigen::MatrixXd Orthonormal(int n, int k, std::mt19937& rng) {
  std::normal_distribution<double> g;
  Eigen::MatrixXd a(n, k);
  for (Eigen::Index i = 0; i < a.size(); ++i) a.data()[i] = g(rng);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(a);
  return qr.householderQ() * Eigen::MatrixXd::Identity(n, k);
}

RigidTransform Pose(double t) {
  Eigen::Matrix<double, 6, 1> p;
  p << 0.3 + 0.2 * std::sin(0.05 * t), -0.5 + 0.1 * std::cos(0.07 * t), 0.1 * std::sin(0.03 * t),
      100 + 30 * std::sin(0.04 * t), -50 + 20 * std::cos(0.05 * t), 150 + 10 * std::sin(0.02 * t);
  return RigidTransform::FromParameters(p);
}

void Store(const Eigen::Matrix3Xd& lab, int64_t frame, MarkerArray* m) {
  for (Eigen::Index j = 0; j < lab.cols(); ++j) {
    float* p = m->at(frame, j);
    for (int c = 0; c < 3; ++c) p[c] = static_cast<float>(lab(c, j));
  }
}

// A HandModel built by hand from a hinge hand: angle PCA over the flexions
// with known components, plus a random non-rigid part of the map (skin
// sliding) so that the inversion sees a general [1, cos, sin] map.
HandModel KnownModel(const HingeHand& h, int p, std::mt19937& rng) {
  const int ns = h.segments();
  const int n = 3 * ns;
  HandModel m;
  m.layout = h.layout;
  m.forearm.name = "forearm";
  m.forearm.markers = h.layout.forearm;
  m.forearm.reference = h.forearm;
  std::uniform_real_distribution<double> u(-1, 1);
  AnglePca& pca = m.shape.angle_pca;
  pca.mean = Eigen::VectorXd::Zero(n);
  pca.components = Eigen::MatrixXd::Zero(n, p);
  const Eigen::MatrixXd c = Orthonormal(ns, p, rng);
  for (int s = 0; s < ns; ++s) {
    pca.mean(3 * s) = 0.5 * u(rng);
    pca.components.row(3 * s) = c.row(s);
  }
  m.param_scale.resize(p);
  pca.variances.resize(p);
  for (int k = 0; k < p; ++k) {
    m.param_scale(k) = 0.4 - 0.1 * k;
    pca.variances(k) = m.param_scale(k) * m.param_scale(k);
  }
  HandRegression& reg = m.shape.regression;
  reg.num_angles = n;
  reg.coefficients = h.Coefficients();
  for (int s = 0; s < ns; ++s) {
    for (int c2 = 0; c2 < 3 * h.nh(); ++c2) {
      reg.coefficients(1 + 3 * s, c2) += 1.0 * u(rng);
      reg.coefficients(1 + n + 3 * s, c2) += 1.0 * u(rng);
    }
  }
  for (int s = 0; s < ns; ++s) m.angle_names.push_back(h.layout.segments[s].name + ".flexion");
  return m;
}

Eigen::VectorXd TrueParams(const HandModel& m, double t) {
  Eigen::VectorXd q(m.num_parameters());
  for (int k = 0; k < q.size(); ++k) q(k) = m.param_scale(k) * std::sin(0.1 * t + k);
  return q;
}

TEST(HandModel, InversionRecoversKnownParametersPoseAndHiddenMarkers) {
  std::mt19937 rng(7);
  const HingeHand h = MakeHingeHand(5, rng);
  const HandModel model = KnownModel(h, 3, rng);
  const int nf = h.nf(), nh = h.nh(), nm = nf + nh;
  const int frames = 80;
  MarkerArray take(frames, nm);
  std::vector<Eigen::Matrix3Xd> truth;
  for (int f = 0; f < frames; ++f) {
    truth.push_back(model.MarkersInLab(Pose(f), TrueParams(model, f)));
    Store(truth.back(), f, &take);
    take.SetMissing(f, nf + (7 * f) % nh);
    take.SetMissing(f, nf + (3 * f + 1) % nh);
    if (f % 5 == 0) take.SetMissing(f, f % nf);
  }
  InversionOptions opt;
  opt.prior_mm = 0;
  const InversionResult r = InvertHand(model, take, opt);
  ASSERT_EQ(r.frames(), frames);
  ASSERT_EQ(r.params.cols(), 3);
  for (int f = 0; f < frames; ++f) {
    ASSERT_TRUE(r.solved[f]) << f;
    EXPECT_TRUE(r.converged[f]) << f;
    const Eigen::VectorXd q = TrueParams(model, f);
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.params(f, k), q(k), 1e-5) << f;
    const Eigen::Matrix<double, 6, 1> pose = Pose(f).Parameters();
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.pose(f, k), pose(k), 1e-6) << f;
    for (int k = 3; k < 6; ++k) EXPECT_NEAR(r.pose(f, k), pose(k), 1e-4) << f;
    for (int j = 0; j < nm; ++j) {
      const float* p = r.reconstructed.at(f, j);
      const Eigen::Vector3d rec(p[0], p[1], p[2]);
      // Float storage of the input and output limits this (≈ 1e-5 mm at 300 mm).
      EXPECT_LT((rec - truth[f].col(j)).norm(), 1e-4) << f << " " << j;
      if (take.Visible(f, j)) {
        EXPECT_LT(r.error_mm(f, j), 1e-4);
      } else {
        EXPECT_TRUE(std::isnan(r.error_mm(f, j)));
      }
    }
  }
  // Cold starts only (no warm start): same answer.
  opt.warm_start = false;
  const InversionResult cold = InvertHand(model, take, opt);
  EXPECT_LT((cold.params - r.params).cwiseAbs().maxCoeff(), 1e-5);
  // The default prior pulls the parameters a little towards 0, by much less than their sd.
  const InversionResult prior = InvertHand(model, take);
  EXPECT_LT((prior.params - r.params).cwiseAbs().maxCoeff(), 0.01);
  EXPECT_GT((prior.params - r.params).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(HandModel, UnsolvableFramesAreNaNAndTheNextFrameColdStarts) {
  std::mt19937 rng(3);
  const HingeHand h = MakeHingeHand(4, rng);
  const HandModel model = KnownModel(h, 2, rng);
  const int nf = h.nf(), nh = h.nh(), nm = nf + nh;
  MarkerArray take(6, nm);
  for (int f = 0; f < 6; ++f) Store(model.MarkersInLab(Pose(10.0 * f), TrueParams(model, 10.0 * f)), f, &take);
  for (int j = 0; j < 3; ++j) take.SetMissing(2, j);            // 2 forearm markers left
  for (int j = 0; j < nh - 2; ++j) take.SetMissing(4, nf + j);  // 2 hand markers left
  InversionOptions opt;
  opt.prior_mm = 0;
  const InversionResult r = InvertHand(model, take, opt);
  for (int f : {2, 4}) {
    EXPECT_FALSE(r.solved[f]);
    EXPECT_TRUE(r.params.row(f).array().isNaN().all());
    EXPECT_TRUE(r.pose.row(f).array().isNaN().all());
    EXPECT_FALSE(r.reconstructed.Visible(f, 0));
    EXPECT_TRUE(r.error_mm.row(f).array().isNaN().all());
  }
  for (int f : {0, 1, 3, 5}) {
    ASSERT_TRUE(r.solved[f]);
    EXPECT_LT((r.params.row(f).transpose() - TrueParams(model, 10.0 * f)).cwiseAbs().maxCoeff(), 1e-5) << f;
  }
  // Per-frame results (issue 13): unsolved for too few markers; cold after
  // them, warm otherwise; no retry on exact data.
  for (int f = 0; f < 6; ++f) {
    const size_t i = static_cast<size_t>(f);
    if (f == 2 || f == 4) {
      EXPECT_EQ(r.status[i], FrameStatus::kTooFewMarkers) << f;
      EXPECT_EQ(r.iterations[i], 0) << f;
      continue;
    }
    EXPECT_TRUE(r.status[i] == FrameStatus::kConverged || r.status[i] == FrameStatus::kMaxIterations) << f;
    EXPECT_EQ(r.cold_start[i], f == 1 ? 0 : 1) << f;
    EXPECT_EQ(r.cold_retry[i], 0) << f;
  }
  // One hand marker 50 mm off in frame 1: the warm start ends far above the
  // retry threshold (3 × training rms + 1 mm), so the frame is retried cold.
  MarkerArray bumped = take;
  bumped.at(1, nf)[0] += 50.0f;
  const InversionResult b = InvertHand(model, bumped, opt);
  EXPECT_EQ(b.cold_retry[1], 1);
  EXPECT_EQ(b.cold_retry[0], 0);
  EXPECT_TRUE(b.solved[1]);
  EXPECT_GE(b.iterations[1], 1);
  // Wrong column count.
  EXPECT_THROW(InvertHand(model, MarkerArray(3, nm - 1)), InvalidInput);
}

// A small kinematic chain: palm (4 markers) → f1 (2) → f2 (2) → f3 (3), and
// a second root t1 (3), each rotated by known joint angles relative to its parent.
struct Chain {
  HandLayout layout;
  std::vector<JointAngles> angles;
  Eigen::Matrix3Xd markers;
};

Chain MakeChain() {
  Chain c;
  c.layout.forearm = {"A", "B", "C"};
  const std::vector<int> parents = {-1, 0, 1, 2, -1};
  const std::vector<int> counts = {4, 2, 2, 3, 3};
  c.angles = {{0.3, -0.2, 0.4}, {0.5, 0.15, 0}, {0.7, -0.1, 0}, {0.4, 0.05, 0.3}, {-0.6, 0.3, -0.5}};
  std::vector<Eigen::Matrix3d> rot;
  std::vector<Eigen::Vector3d> cols;
  int next = 0;
  for (size_t s = 0; s < parents.size(); ++s) {
    const Eigen::Matrix3d parent = parents[s] < 0 ? Eigen::Matrix3d::Identity() : rot[parents[s]];
    rot.push_back(parent * RotationFromJointAngles(c.angles[s]));
    const Eigen::Vector3d origin(10.0 * s, 5.0 * s, -3.0 * s);
    const std::vector<Eigen::Vector3d> local = {{0, 0, 0}, {30, 0, 0}, {12, 9, 0}, {-5, 14, 0}};
    HandSegmentDef seg;
    seg.name = "s" + std::to_string(s);
    seg.parent = parents[s];
    for (int j = 0; j < counts[s]; ++j) {
      cols.push_back(origin + rot.back() * local[j]);
      seg.markers.push_back(next++);
      c.layout.hand.push_back(seg.name + "m" + std::to_string(j));
    }
    c.layout.segments.push_back(seg);
  }
  c.markers.resize(3, static_cast<Eigen::Index>(cols.size()));
  for (size_t j = 0; j < cols.size(); ++j) c.markers.col(static_cast<Eigen::Index>(j)) = cols[j];
  return c;
}

TEST(HandModel, AnglesOfAKnownKinematicChain) {
  const Chain c = MakeChain();
  ASSERT_EQ(CheckHandLayout(c.layout), "");
  HandModel model;
  model.layout = c.layout;
  const Eigen::VectorXd a = model.Angles(c.markers);
  ASSERT_EQ(a.size(), 15);
  for (size_t s = 0; s < c.angles.size(); ++s) {
    EXPECT_NEAR(a(3 * s), c.angles[s].flexion, 1e-12) << s;
    EXPECT_NEAR(a(3 * s + 1), c.angles[s].spread, 1e-12) << s;
    EXPECT_NEAR(a(3 * s + 2), c.angles[s].twist, 1e-12) << s;
  }
  // Twist of the 2-marker phalanges is exactly 0.
  EXPECT_EQ(a(5), 0.0);
  EXPECT_EQ(a(8), 0.0);
  // A missing marker of f2 makes f2 and its child f3 unknown; the rest stay.
  Eigen::Matrix3Xd m = c.markers;
  m.col(6).setConstant(std::nan(""));  // f2's second marker (palm 0-3, f1 4-5, f2 6-7)
  m.col(7).setConstant(std::nan(""));
  const Eigen::VectorXd b = model.Angles(m);
  for (int i = 0; i < 15; ++i) {
    if (i >= 6 && i < 12) {
      EXPECT_TRUE(std::isnan(b(i))) << i;
    } else {
      EXPECT_DOUBLE_EQ(b(i), a(i)) << i;
    }
  }
  // Collinear palm markers: no palm frame, nor for its descendants; t1 stays.
  m = c.markers;
  for (int j = 2; j < 4; ++j) m.col(j) = c.markers.col(0) + (j + 1.0) * (c.markers.col(1) - c.markers.col(0));
  const Eigen::VectorXd d = model.Angles(m);
  for (int i = 0; i < 12; ++i) EXPECT_TRUE(std::isnan(d(i))) << i;
  for (int i = 12; i < 15; ++i) EXPECT_NEAR(d(i), a(i), 1e-12);
  EXPECT_THROW(model.Angles(Eigen::Matrix3Xd::Zero(3, 4)), InvalidInput);
}

TEST(HandModel, FourMarkerSegmentFrameUsesThePlaneOfAllItsMarkers) {
  // A palm whose 3rd marker alone would tilt the frame: the plane of all four
  // (3rd and 4th symmetric about it) is the segment's x-y plane.
  HandLayout layout;
  layout.forearm = {"A", "B", "C"};
  layout.hand = {"m0", "m1", "m2", "m3"};
  layout.segments = {{"palm", -1, {0, 1, 2, 3}}};
  HandModel model;
  model.layout = layout;
  const Eigen::Matrix3d r = RotationFromJointAngles({0.2, 0.1, -0.3});
  Eigen::Matrix3Xd local(3, 4);
  local << 0, 30, 10, 20,  //
      0, 0, 10, 10,        //
      0, 0, 2, -2;
  const Eigen::Matrix3Xd lab = r * local;
  const Eigen::VectorXd a = model.Angles(lab);
  EXPECT_NEAR(a(0), 0.2, 1e-12);
  EXPECT_NEAR(a(1), 0.1, 1e-12);
  EXPECT_NEAR(a(2), -0.3, 1e-12);
}

// Takes generated by a hinge hand: known flexions on a 2-D affine subspace,
// a forearm moving around, some gaps.
std::vector<MarkerArray> HingeTakes(const HingeHand& h, const Eigen::VectorXd& mean, const Eigen::MatrixXd& c,
                                    int takes, int frames, std::mt19937& rng,
                                    std::vector<std::vector<Eigen::Matrix3Xd>>* truth) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<MarkerArray> out;
  const int nf = h.nf(), nh = h.nh();
  for (int t = 0; t < takes; ++t) {
    MarkerArray m(frames, nf + nh);
    std::vector<Eigen::Matrix3Xd> tt;
    const double phase = 10.0 * u(rng);
    for (int f = 0; f < frames; ++f) {
      const Eigen::Vector2d p(0.6 * std::sin(0.11 * f + phase), 0.4 * std::cos(0.07 * f + 2 * phase));
      const Eigen::VectorXd flex = mean + c * p;
      const RigidTransform pose = Pose(f + 37.0 * t);
      Eigen::Matrix3Xd all(3, nf + nh);
      for (int j = 0; j < nf; ++j) all.col(j) = pose.Apply(h.forearm.col(j));
      const Eigen::Matrix3Xd local = h.Local(flex);
      for (int j = 0; j < nh; ++j) all.col(nf + j) = pose.Apply(local.col(j));
      Store(all, f, &m);
      if (f % 9 == 4) m.SetMissing(f, nf + (f / 9) % nh);
      tt.push_back(all);
    }
    out.push_back(std::move(m));
    truth->push_back(std::move(tt));
  }
  return out;
}

TEST(HandModel, FitReproducesTheGeneratingModel) {
  std::mt19937 rng(11);
  const HingeHand h = MakeHingeHand(4, rng);
  const Eigen::VectorXd mean = (Eigen::VectorXd(4) << 0.2, -0.3, 0.5, 0.1).finished();
  const Eigen::MatrixXd c = Orthonormal(4, 2, rng);
  std::vector<std::vector<Eigen::Matrix3Xd>> truth;
  const std::vector<MarkerArray> takes = HingeTakes(h, mean, c, 3, 150, rng, &truth);
  HandModelOptions opt;
  opt.angle_components = 2;
  opt.min_distance_mm = 0.5;
  std::vector<std::string> stages;
  Progress progress([&](const std::string& stage, double) {
    if (stages.empty() || stages.back() != stage) stages.push_back(stage);
  });
  const HandModel model = FitHandModel(h.layout, {takes[0], takes[1]}, opt, &progress);
  EXPECT_FALSE(stages.empty());
  ASSERT_EQ(model.num_parameters(), 2);
  ASSERT_EQ(model.angle_names.size(), 12u);
  EXPECT_EQ(model.angle_names[0], "seg0.flexion");
  EXPECT_EQ(model.angle_names[5], "seg1.twist");
  EXPECT_EQ(model.forearm.markers, h.layout.forearm);
  ASSERT_EQ(model.rest.size(), 4u);
  EXPECT_EQ(model.info.training_frames, 300 - 2 * 17);  // frames with a hidden hand marker excluded
  EXPECT_GT(model.info.selected_frames, 50);
  EXPECT_LE(model.info.selected_frames, model.info.training_frames);
  EXPECT_LT(model.info.training_rms_mm, 1e-3);
  // The angle PCA spans the generating subspace: all variance in 2 components.
  double explained = 0;
  for (double v : model.shape.angle_pca.variance_explained) explained += v;
  EXPECT_NEAR(explained, 1.0, 1e-9);
  for (int k = 0; k < 2; ++k) EXPECT_NEAR(model.param_scale(k), std::sqrt(model.shape.angle_pca.variances(k)), 1e-12);
  // Components are orthonormal, parameters uncorrelated, whichever PCA.
  const Eigen::MatrixXd& comp = model.shape.angle_pca.components;
  EXPECT_LT((comp.transpose() * comp - Eigen::MatrixXd::Identity(2, 2)).cwiseAbs().maxCoeff(), 1e-12);
  HandModelOptions plain = opt;
  plain.weighted_angle_pca = false;
  const HandModel seed_model = FitHandModel(h.layout, {takes[0], takes[1]}, plain);
  EXPECT_LT(seed_model.info.training_rms_mm, 1e-3);
  // Same generating subspace: the projectors agree.
  const Eigen::MatrixXd& c2 = seed_model.shape.angle_pca.components;
  EXPECT_LT((comp * comp.transpose() - c2 * c2.transpose()).cwiseAbs().maxCoeff(), 1e-6);

  // Held-out take: reconstruction of visible and hidden markers matches the
  // truth (hidden ones from the exact shape model, not the Gaussian filler,
  // a linear approximation; gaussian_fill_test.cc tests that).
  EXPECT_FALSE(model.fill.empty());
  InversionOptions iopt;
  iopt.prior_mm = 0;
  iopt.gaussian_fill = false;
  const InversionResult r = InvertHand(model, takes[2], iopt);
  double worst = 0;
  for (int64_t f = 0; f < r.frames(); ++f) {
    ASSERT_TRUE(r.solved[f]);
    for (int j = 0; j < h.nf() + h.nh(); ++j) {
      const float* p = r.reconstructed.at(f, j);
      worst = std::max(worst, (Eigen::Vector3d(p[0], p[1], p[2]) - truth[2][f].col(j)).norm());
    }
    // Parameters are the PCA parameters of the true flexions (measured in the model's frames).
    Eigen::Matrix3Xd local(3, h.nh());
    const RigidTransform pose = RigidTransform::FromParameters(r.pose.row(f).transpose());
    for (int j = 0; j < h.nh(); ++j) local.col(j) = pose.Inverse().Apply(truth[2][f].col(h.nf() + j));
    const Eigen::VectorXd expected = model.shape.angle_pca.Params(model.Angles(local));
    EXPECT_LT((r.params.row(f).transpose() - expected).cwiseAbs().maxCoeff(), 1e-5) << f;
  }
  EXPECT_LT(worst, 1e-3);
  // The forearm pose equals the Kabsch pose of the fitted cluster on the true markers.
  for (int64_t f = 0; f < r.frames(); f += 7) {
    const RigidFit fit = EstimateRigidKabsch(model.forearm.reference, truth[2][f].leftCols(h.nf()));
    const Eigen::Matrix<double, 6, 1> expect = fit.transform.Parameters();
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(r.pose(f, k), expect(k), 1e-6);
    for (int k = 3; k < 6; ++k) EXPECT_NEAR(r.pose(f, k), expect(k), 1e-4);
  }

  // With the Gaussian gap filler (the default): the same solve, and every
  // hidden hand marker is the filler's conditional mean given the frame's
  // seen markers in the solved forearm frame.
  const InversionResult g = InvertHand(model, takes[2]);
  GaussianFiller filler(model.fill);
  int64_t filled = 0;
  for (int64_t f = 0; f < g.frames(); ++f) {
    ASSERT_TRUE(g.solved[f]);
    const RigidTransform pose = RigidTransform::FromParameters(g.pose.row(f).transpose());
    Eigen::Matrix3Xd local(3, h.nh());
    bool hidden = false;
    for (int j = 0; j < h.nh(); ++j) {
      const float* p = takes[2].at(f, h.nf() + j);
      hidden = hidden || IsMissing(p[0]);
      local.col(j) = IsMissing(p[0]) ? Eigen::Vector3d::Constant(std::nan(""))
                                     : pose.Inverse().Apply(Eigen::Vector3d(p[0], p[1], p[2]));
    }
    if (!hidden) continue;
    filler.Fill(&local);
    for (int j = 0; j < h.nh(); ++j) {
      if (!IsMissing(takes[2].at(f, h.nf() + j)[0])) continue;
      const float* p = g.reconstructed.at(f, h.nf() + j);
      EXPECT_LT((Eigen::Vector3d(p[0], p[1], p[2]) - pose.Apply(local.col(j))).norm(), 1e-3) << f << " " << j;
      ++filled;
    }
  }
  EXPECT_GT(filled, 0);
}

// Angles from 2 PCA components of the flexions (spreads and twists always 0): the training angles have
// rank 2, so a third component is warned about, and the constant angles are named in one line. The
// markers are stored in single precision, so the measured spreads and twists are 0 only to ~1e-7 rad:
// their sin varies by more than the 1e-9 threshold and is kept, their cos (1 - 5e-15) is constant.
// training_rms_mm is what inverting the training takes reaches: with 0.2 mm
// marker noise per coordinate, the RMS of the inversion's visible hand errors
// over every training frame (not only the selected ones) agrees with it
// within 20 %. Both are above the noise (the model is fitted on noisy angles
// and the forearm pose is noisy too): measured 0.50 mm.
TEST(HandModel, TrainingRmsIsWhatInvertingTheTrainingTakesReaches) {
  std::mt19937 rng(23);
  const HingeHand h = MakeHingeHand(4, rng);
  const Eigen::VectorXd mean = (Eigen::VectorXd(4) << 0.2, -0.3, 0.5, 0.1).finished();
  const Eigen::MatrixXd c = Orthonormal(4, 2, rng);
  std::vector<std::vector<Eigen::Matrix3Xd>> truth;
  std::vector<MarkerArray> takes = HingeTakes(h, mean, c, 2, 200, rng, &truth);
  std::normal_distribution<double> noise(0.0, 0.2);
  for (MarkerArray& t : takes) {
    for (int64_t f = 0; f < t.frames(); ++f)
      for (int64_t m = 0; m < t.markers(); ++m) {
        if (!t.Visible(f, m)) continue;
        for (int k = 0; k < 3; ++k) t.at(f, m)[k] = static_cast<float>(t.at(f, m)[k] + noise(rng));
      }
  }
  HandModelOptions opt;
  opt.angle_components = 2;
  opt.min_distance_mm = 0.5;
  opt.gaussian_fill = false;
  const HandModel model = FitHandModel(h.layout, takes, opt);
  const int nf = static_cast<int>(h.layout.forearm.size());
  double s2 = 0;
  int64_t n = 0;
  for (const MarkerArray& t : takes) {
    const InversionResult r = InvertHand(model, t);
    for (int64_t f = 0; f < r.frames(); ++f)
      for (int64_t m = nf; m < t.markers(); ++m) {
        if (!std::isfinite(r.error_mm(f, m))) continue;
        s2 += r.error_mm(f, m) * r.error_mm(f, m);
        ++n;
      }
  }
  const double inverted_rms = std::sqrt(s2 / static_cast<double>(n));
  EXPECT_NEAR(model.info.training_rms_mm, inverted_rms, 0.2 * inverted_rms);
  EXPECT_GT(model.info.training_rms_mm, 0.15);  // not below the noise
  EXPECT_LT(model.info.training_rms_mm, 1.0);
  std::printf("hand training rms %.3f mm, inverting the training takes %.3f mm\n", model.info.training_rms_mm,
              inverted_rms);
}

TEST(HandModel, WarnsAboutComponentsBeyondTheAnglesRankAndNamesConstantAngles) {
  std::mt19937 rng(11);
  const HingeHand h = MakeHingeHand(4, rng);
  const Eigen::VectorXd mean = (Eigen::VectorXd(4) << 0.2, -0.3, 0.5, 0.1).finished();
  const Eigen::MatrixXd c = Orthonormal(4, 2, rng);
  std::vector<std::vector<Eigen::Matrix3Xd>> truth;
  const std::vector<MarkerArray> takes = HingeTakes(h, mean, c, 2, 150, rng, &truth);
  HandModelOptions opt;
  opt.min_distance_mm = 0.5;
  opt.angle_components = 2;
  const HandModel exact = FitHandModel(h.layout, takes, opt);
  EXPECT_TRUE(exact.warnings.empty());
  ASSERT_GE(exact.shape.regression.warnings.size(), 1u);  // then the rank deficiency of 4 flexions on a plane
  EXPECT_EQ(exact.shape.regression.warnings[0],
            "8 angles constant over the training frames, dropped from the regression (the intercept holds them): "
            "cos(seg0.spread), cos(seg0.twist), cos(seg1.spread), cos(seg1.twist), cos(seg2.spread), "
            "cos(seg2.twist), cos(seg3.spread), cos(seg3.twist)");
  opt.angle_components = 3;
  const HandModel model = FitHandModel(h.layout, takes, opt);
  ASSERT_EQ(model.warnings.size(), 1u);
  EXPECT_EQ(model.warnings[0],
            "angle_components 3 exceeds the rank of the training angles (2 of 12 angles vary independently): "
            "parameters 3..3 have no variance; use at most 2");
}

TEST(HandModel, BadLayoutsAndColumnMismatchesAreRejected) {
  std::mt19937 rng(5);
  const HingeHand h = MakeHingeHand(3, rng);
  std::vector<std::vector<Eigen::Matrix3Xd>> truth;
  const Eigen::VectorXd mean = Eigen::VectorXd::Zero(3);
  const std::vector<MarkerArray> takes = HingeTakes(h, mean, Orthonormal(3, 2, rng), 1, 40, rng, &truth);
  ASSERT_EQ(CheckHandLayout(h.layout), "");

  auto expect_bad = [&](const HandLayout& layout, const std::string& fragment) {
    const std::string why = CheckHandLayout(layout);
    EXPECT_NE(why.find(fragment), std::string::npos) << why;
    try {
      FitHandModel(layout, takes);
      ADD_FAILURE() << "no error for " << fragment;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
    }
  };
  HandLayout l = h.layout;
  l.segments[0].parent = 1;  // parent after child
  expect_bad(l, "parents come first");
  l = h.layout;
  l.segments[1].parent = 0;
  l.segments[1].markers.resize(1);
  expect_bad(l, "needs at least 2");
  l = h.layout;
  l.segments[0].markers.pop_back();
  l.segments[0].markers.resize(2);  // root with 2 markers
  expect_bad(l, "needs at least 3");
  l = h.layout;
  l.segments[2].markers[0] = h.nh();
  expect_bad(l, "outside 0..");
  l = h.layout;
  l.segments[2].markers[1] = l.segments[2].markers[0];
  expect_bad(l, "listed twice");
  l = h.layout;
  l.forearm.resize(2);
  expect_bad(l, "at least 3 markers");
  l = h.layout;
  l.segments[1].name = l.segments[0].name;
  expect_bad(l, "name used twice");

  // Column mismatch names the take.
  HandModelOptions two;
  two.angle_components = 2;
  try {
    FitHandModel(h.layout, {takes[0], MarkerArray(10, h.nf() + h.nh() + 1)}, two);
    ADD_FAILURE();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("take 2"), std::string::npos) << e.what();
  }
  HandModelOptions opt;
  opt.angle_components = 10;  // 3 segments → 9 angles
  EXPECT_THROW(FitHandModel(h.layout, takes, opt), InvalidInput);
  EXPECT_THROW(FitHandModel(h.layout, {}), InvalidInput);
  // No frame with every hand marker visible.
  MarkerArray gappy = takes[0];
  for (int64_t f = 0; f < gappy.frames(); ++f) gappy.SetMissing(f, h.nf() + 1);
  EXPECT_THROW(FitHandModel(h.layout, {gappy}, two), InvalidInput);
}

TEST(HandModel, FitAndInversionCanBeCancelled) {
  std::mt19937 rng(9);
  const HingeHand h = MakeHingeHand(3, rng);
  std::vector<std::vector<Eigen::Matrix3Xd>> truth;
  const std::vector<MarkerArray> takes =
      HingeTakes(h, Eigen::VectorXd::Zero(3), Orthonormal(3, 2, rng), 1, 60, rng, &truth);
  HandModelOptions opt;
  opt.angle_components = 2;
  opt.min_distance_mm = 0.5;
  const HandModel model = FitHandModel(h.layout, takes, opt);
  Progress cancelled;
  cancelled.Cancel();
  EXPECT_THROW(FitHandModel(h.layout, takes, opt, &cancelled), Cancelled);
  EXPECT_THROW(InvertHand(model, takes[0], {}, &cancelled), Cancelled);
  // Cancel in the middle of the fit (at the regression stage).
  Progress* self = nullptr;
  Progress late([&](const std::string& stage, double) {
    if (stage.find("regression") != std::string::npos) self->Cancel();
  });
  self = &late;
  EXPECT_THROW(FitHandModel(h.layout, takes, opt, &late), Cancelled);
}

}  // namespace
}  // namespace csw
