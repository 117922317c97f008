// synth/marker_synthesis.h: parameter tracks back to markers, on face and
// hand models fitted to virtual-cuer sentences. Known answers: the models'
// own MarkersInLab with the composed pose (exact), the inversion's
// reconstruction of a take (the same numbers by another path), and the
// observed markers the parameters were inverted from (within the models'
// reconstruction accuracy).
#include "synth/marker_synthesis.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "io/models/model_file.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "synth/dictionary.h"
#include "tests/keys_job/cuer_corpus.h"
#include "tests/testing/testing.h"
#include "workbench/jobs/fit_job.h"
#include "workbench/jobs/model_config.h"
#include "workbench/jobs/take_data.h"

namespace csw {
namespace {

using Pose = Eigen::Matrix<double, 6, 1>;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Virtual-cuer sentences, face and hand models fitted on them, and sentence
// s0 inverted as csw dict build does.
struct Fixture : testing::CuerCorpus {
  ModelFile models;
  MarkerSet set;
  Take take;
  InversionResult face_inv, hand_inv;
  MarkerArray face_obs, hand_obs;
  Fixture() : CuerCorpus(testing::kSanitized ? 2 : 3) {
    const std::string path = (dir / "models.h5").string();
    Progress progress;
    for (const char* kind : {"face", "hand"}) {
      jobs::FitOptions fo;
      fo.corpus = corpus;
      fo.kind = kind;
      fo.output = path;
      jobs::Fit(fo, progress);
    }
    models = LoadModelFile(path);
    set = jobs::MarkerSetOfModel(models.face->info, path);
    take = Corpus::Open(corpus).LoadTake("s0");
    const FaceModel& face = *models.face;
    const HandModel& hand = *models.hand;
    std::vector<std::string> fn = face.layout.head, hn = hand.layout.forearm;
    fn.insert(fn.end(), face.layout.face.begin(), face.layout.face.end());
    fn.insert(fn.end(), face.layout.throat.begin(), face.layout.throat.end());
    hn.insert(hn.end(), hand.layout.hand.begin(), hand.layout.hand.end());
    face_obs = jobs::Extract(take.markers, jobs::BindNames(set, take.marker_names, fn, "s0"), 0, take.frames());
    hand_obs = jobs::Extract(take.markers, jobs::BindNames(set, take.marker_names, hn, "s0"), 0, take.frames());
    face_inv = InvertFace(face, face_obs);
    hand_inv = InvertHand(hand, hand_obs);
  }
  ParameterTracks Tracks() const {
    ParameterTracks t;
    t.rate_hz = take.rate_hz;
    t.face_params = face_inv.params;
    t.head_pose = face_inv.pose;
    t.hand_params = hand_inv.params;
    t.forearm_in_head.resize(take.frames(), 6);
    for (int64_t f = 0; f < take.frames(); ++f) {
      t.forearm_in_head.row(f) =
          dict::RelativePose(face_inv.pose.row(f).transpose(), hand_inv.pose.row(f).transpose()).transpose();
    }
    return t;
  }
};

class MarkerSynthesis : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { fixture_ = new Fixture(); }
  static void TearDownTestSuite() {
    delete fixture_;
    fixture_ = nullptr;
  }
  static Fixture* fixture_;
};
Fixture* MarkerSynthesis::fixture_ = nullptr;

TEST(ComposePose, UndoesRelativePose) {
  Pose head, rel;
  head << 0.2, -0.1, 0.3, 10, -20, 900;
  rel << -0.4, 0.25, 0.05, 40, -150, -80;
  const Pose lab = ComposePose(head, rel);
  const Pose back = dict::RelativePose(head, lab);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(back[k], rel[k], 1e-12) << k;
  // Hand-derived: a head translated by (1, 2, 3) without rotation adds its translation.
  Pose t = Pose::Zero();
  t << 0, 0, 0, 1, 2, 3;
  const Pose moved = ComposePose(t, rel);
  for (int k = 0; k < 3; ++k) EXPECT_NEAR(moved[k], rel[k], 1e-12);
  for (int k = 3; k < 6; ++k) EXPECT_NEAR(moved[k], rel[k] + (k - 2), 1e-12);
  head[4] = kNaN;
  EXPECT_TRUE(std::isnan(ComposePose(head, rel)[0]));
}

TEST_F(MarkerSynthesis, EqualsTheModelsMarkersWithTheComposedPose) {
  ASSERT_NE(fixture_, nullptr);
  const Fixture& fx = *fixture_;
  const FaceModel& face = *fx.models.face;
  const HandModel& hand = *fx.models.hand;
  // One frame's parameters, changed so that they come from no inversion.
  const int64_t f = fx.take.frames() / 2;
  ParameterTracks t = fx.Tracks();
  ParameterTracks one;
  one.rate_hz = 50;
  one.face_params = t.face_params.row(f) * 1.5;
  one.hand_params = t.hand_params.row(f) * 0.5;
  one.head_pose = t.head_pose.row(f);
  one.head_pose(0, 2) += 0.1;
  one.forearm_in_head = t.forearm_in_head.row(f);
  one.forearm_in_head(0, 4) -= 30;
  ASSERT_TRUE(one.face_params.allFinite() && one.hand_params.allFinite());
  const Take out = MarkersFromParameters(face, hand, one, "one");
  EXPECT_EQ(out.name, "one");
  EXPECT_DOUBLE_EQ(out.rate_hz, 50);
  ASSERT_EQ(out.frames(), 1);
  const std::vector<std::string> names = SynthesisMarkerNames(face, hand);
  ASSERT_EQ(out.marker_names, names);
  ASSERT_EQ(static_cast<int>(names.size()), face.layout.num_markers() + hand.layout.num_markers());
  EXPECT_EQ(names.front(), face.layout.head.front());
  EXPECT_EQ(names.back(), hand.layout.hand.back());

  const RigidTransform head = RigidTransform::FromParameters(one.head_pose.row(0).transpose());
  const Eigen::Matrix3Xd fm = face.MarkersInLab(head, one.face_params.row(0).transpose());
  const RigidTransform rel = RigidTransform::FromParameters(one.forearm_in_head.row(0).transpose());
  RigidTransform forearm;  // head ∘ rel by hand
  forearm.rotation = head.rotation * rel.rotation;
  forearm.translation = head.rotation * rel.translation + head.translation;
  const Eigen::Matrix3Xd hm = hand.MarkersInLab(forearm, one.hand_params.row(0).transpose());
  // float32 storage of ~1 m coordinates: 1e-3 mm.
  for (Eigen::Index j = 0; j < fm.cols(); ++j)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(out.markers.at(0, j)[k], fm(k, j), 1e-3) << names[j];
  for (Eigen::Index j = 0; j < hm.cols(); ++j)
    for (int k = 0; k < 3; ++k) EXPECT_NEAR(out.markers.at(0, fm.cols() + j)[k], hm(k, j), 1e-3) << j;
}

TEST_F(MarkerSynthesis, RoundTripThroughInversion) {
  ASSERT_NE(fixture_, nullptr);
  const Fixture& fx = *fixture_;
  const FaceModel& face = *fx.models.face;
  const HandModel& hand = *fx.models.hand;
  const Take out = MarkersFromParameters(face, hand, fx.Tracks(), "s0.synth");
  ASSERT_EQ(out.frames(), fx.take.frames());
  const int nf = face.layout.num_markers(), nh = hand.layout.num_markers();
  // 1. The inversion's reconstruction of the observed markers (the same
  //    model equations, the forearm pose through the head frame and back):
  //    equal to float precision.
  double max_vs_recon = 0;
  // 2. The observed markers: within the models' reconstruction accuracy.
  double face_sum = 0, hand_sum = 0, face_max = 0, hand_max = 0;
  int64_t face_n = 0, hand_n = 0, solved = 0;
  for (int64_t f = 0; f < out.frames(); ++f) {
    if (!fx.face_inv.solved[static_cast<size_t>(f)] || !fx.hand_inv.solved[static_cast<size_t>(f)]) {
      EXPECT_FALSE(out.markers.Visible(f, 0) && out.markers.Visible(f, nf)) << f;
      continue;
    }
    ++solved;
    for (int j = 0; j < nf + nh; ++j) {
      const bool is_face = j < nf;
      const int m = is_face ? j : j - nf;
      const MarkerArray& recon = is_face ? fx.face_inv.reconstructed : fx.hand_inv.reconstructed;
      const MarkerArray& obs = is_face ? fx.face_obs : fx.hand_obs;
      ASSERT_TRUE(out.markers.Visible(f, j));
      double d2 = 0, e2 = 0;
      for (int k = 0; k < 3; ++k) {
        d2 += std::pow(out.markers.at(f, j)[k] - recon.at(f, m)[k], 2);
        e2 += std::pow(out.markers.at(f, j)[k] - obs.at(f, m)[k], 2);
      }
      if (!obs.Visible(f, m)) continue;  // the hand inversion fills hidden markers with its Gaussian filler
      max_vs_recon = std::max(max_vs_recon, std::sqrt(d2));
      const double e = std::sqrt(e2);
      (is_face ? face_sum : hand_sum) += e;
      (is_face ? face_n : hand_n) += 1;
      double& mx = is_face ? face_max : hand_max;
      mx = std::max(mx, e);
    }
  }
  EXPECT_GT(solved, out.frames() * 9 / 10);
  EXPECT_LT(max_vs_recon, 1e-3);
  ASSERT_GT(face_n, 0);
  ASSERT_GT(hand_n, 0);
  const double face_mean = face_sum / static_cast<double>(face_n);
  const double hand_mean = hand_sum / static_cast<double>(hand_n);
  std::printf("regenerated vs observed: face mean %.3f max %.3f mm, hand mean %.3f max %.3f mm (%lld frames)\n",
              face_mean, face_max, hand_mean, hand_max, static_cast<long long>(solved));
  // Measured 0.32 mm (face) and 0.43 mm (hand) mean on 3 sentences; the
  // 20-parameter hand model's visible error is 1.0-1.3 mm on the full
  // virtual cuer (docs/models.md): limits 1 mm (face) and 2 mm (hand) on
  // the mean.
  EXPECT_LT(face_mean, 1.0);
  EXPECT_LT(hand_mean, 2.0);
}

TEST_F(MarkerSynthesis, NaNRowsGiveMissingMarkers) {
  ASSERT_NE(fixture_, nullptr);
  const Fixture& fx = *fixture_;
  const FaceModel& face = *fx.models.face;
  const HandModel& hand = *fx.models.hand;
  ParameterTracks t = fx.Tracks();
  const int nf = face.layout.num_markers();
  t.face_params(3, 0) = kNaN;      // face only
  t.hand_params(5, 1) = kNaN;      // hand only
  t.forearm_in_head(6, 3) = kNaN;  // hand only
  t.head_pose(7, 0) = kNaN;        // everything
  const Take out = MarkersFromParameters(face, hand, t, "nan");
  const int n = static_cast<int>(out.marker_names.size());
  for (int j = 0; j < n; ++j) {
    const bool is_face = j < nf;
    EXPECT_EQ(out.markers.Visible(3, j), !is_face) << j;
    EXPECT_EQ(out.markers.Visible(5, j), is_face) << j;
    EXPECT_EQ(out.markers.Visible(6, j), is_face) << j;
    EXPECT_FALSE(out.markers.Visible(7, j)) << j;
    EXPECT_TRUE(out.markers.Visible(8, j)) << j;
  }
}

TEST_F(MarkerSynthesis, BadTracksAreRejectedNamingTheTake) {
  ASSERT_NE(fixture_, nullptr);
  const Fixture& fx = *fixture_;
  const FaceModel& face = *fx.models.face;
  const HandModel& hand = *fx.models.hand;
  auto expect_error = [&](const ParameterTracks& t, const std::string& part) {
    try {
      MarkersFromParameters(face, hand, t, "bad");
      ADD_FAILURE() << "no error for " << part;
    } catch (const InvalidInput& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("synthesised take 'bad'"), std::string::npos) << what;
      EXPECT_NE(what.find(part), std::string::npos) << what;
    }
  };
  ParameterTracks t = fx.Tracks();
  t.rate_hz = 0;
  expect_error(t, "frame rate must be positive");
  t = fx.Tracks();
  t.face_params = t.face_params.leftCols(1).eval();
  expect_error(t, "face parameters " + std::to_string(t.face_params.rows()) + "×1");
  t = fx.Tracks();
  t.forearm_in_head = t.forearm_in_head.topRows(3).eval();
  expect_error(t, "forearm in head 3×6");
}

// Largest frame-to-frame jump of any marker.
double MaxMarkerJump(const MarkerArray& m) {
  std::vector<double> jumps;
  dict::AppendMarkerJumps(m, &jumps);
  return jumps.empty() ? 0.0 : *std::max_element(jumps.begin(), jumps.end());
}

// A still cuer: every track row the fixture's row `a` (finite).
void HoldStill(int64_t a, ParameterTracks* t) {
  for (Eigen::MatrixXd* m : {&t->face_params, &t->head_pose, &t->hand_params, &t->forearm_in_head}) {
    const Eigen::RowVectorXd row = m->row(a);
    ASSERT_TRUE(row.allFinite());
    m->rowwise() = row;
  }
}

TEST_F(MarkerSynthesis, SpeedLimitSpreadsAFastMovementAndKeepsItsEnds) {
  ASSERT_NE(fixture_, nullptr);
  const Fixture& fx = *fixture_;
  const FaceModel& face = *fx.models.face;
  const HandModel& hand = *fx.models.hand;
  ParameterTracks t = fx.Tracks();
  const int64_t n = t.frames();
  ASSERT_GE(n, 120);
  // A still cuer (every row the take's middle one), whose forearm then moves
  // 60 mm sideways (in the head frame) in 4 frames from frame a and stays
  // there: 15 mm per frame, against a limit of 5 mm.
  const int64_t a = n / 2;
  HoldStill(a, &t);
  const double limit = 5.0;
  for (int64_t f = a + 1; f < n; ++f) t.forearm_in_head(f, 3) += 60.0 * std::min<double>(1.0, (f - a) / 4.0);
  Take take = MarkersFromParameters(face, hand, t, "fast");
  const ParameterTracks unlimited = t;
  ASSERT_GT(MaxMarkerJump(take.markers), limit + 5.0);
  const SpeedLimitResult r = LimitMarkerSpeed(face, hand, limit, 500, &t, &take);
  EXPECT_GT(r.smoothings, 0);
  EXPECT_NEAR(r.max_jump_before_mm, MaxMarkerJump(MarkersFromParameters(face, hand, unlimited, "x").markers), 1e-9);
  // No marker moves further than the limit, and the markers are those of the
  // smoothed tracks.
  EXPECT_LE(MaxMarkerJump(take.markers), limit + 1e-6);
  EXPECT_NEAR(r.max_jump_after_mm, MaxMarkerJump(take.markers), 1e-9);
  const Take again = MarkersFromParameters(face, hand, t, "fast");
  for (int64_t f = 0; f < n; ++f)
    for (int64_t j = 0; j < take.markers.markers(); ++j)
      for (int k = 0; k < 3; ++k) ASSERT_EQ(take.markers.at(f, j)[k], again.markers.at(f, j)[k]) << f << " " << j;
  // Only the frames around the fast movement changed (60 mm at 5 mm per frame
  // needs 12 frames: the smoothing spreads it over at most 30 each side), and
  // the movement still goes the whole 60 mm.
  int64_t first = n, last = -1;
  for (int64_t f = 0; f < n; ++f)
    if (t.forearm_in_head.row(f) != unlimited.forearm_in_head.row(f) ||
        t.hand_params.row(f) != unlimited.hand_params.row(f)) {
      first = std::min(first, f);
      last = std::max(last, f);
    }
  EXPECT_GE(first, a - 30);
  EXPECT_LE(last, a + 4 + 30);
  const int64_t after = std::min(n - 1, a + 4 + 31);
  EXPECT_NEAR(t.forearm_in_head(after, 3) - t.forearm_in_head(a - 31, 3),
              unlimited.forearm_in_head(after, 3) - unlimited.forearm_in_head(a - 31, 3), 1e-9);

  EXPECT_THROW(LimitMarkerSpeed(face, hand, 0.0, 10, &t, &take), InvalidInput);
}

TEST_F(MarkerSynthesis, SpeedLimitSpreadsAMovementAtTheTakesEndAndALongSteadyOne) {
  ASSERT_NE(fixture_, nullptr);
  const Fixture& fx = *fixture_;
  const FaceModel& face = *fx.models.face;
  const HandModel& hand = *fx.models.hand;
  ParameterTracks t = fx.Tracks();
  const int64_t n = t.frames();
  ASSERT_GE(n, 120);
  const int64_t a = n / 3;
  HoldStill(a, &t);
  // The forearm moves (in the head frame) 6 mm per frame for 12 frames from
  // frame a: 72 mm, which at a limit of 5 mm per frame needs at least 15
  // transitions, more than the 14 around the movement; and 60 mm sideways in
  // the take's last 4 frames (15 mm per frame), ending on its last frame.
  for (int64_t f = a + 1; f < n; ++f)
    t.forearm_in_head(f, 4) += 6.0 * static_cast<double>(std::min<int64_t>(f - a, 12));
  for (int64_t f = n - 4; f < n; ++f) t.forearm_in_head(f, 3) += 15.0 * static_cast<double>(f - (n - 5));
  const double limit = 5.0;
  const ParameterTracks unlimited = t;
  Take take = MarkersFromParameters(face, hand, t, "fast");
  ASSERT_GT(MaxMarkerJump(take.markers), 14.0);
  const SpeedLimitResult r = LimitMarkerSpeed(face, hand, limit, 2000, &t, &take);
  EXPECT_LE(MaxMarkerJump(take.markers), limit + 1e-6);
  EXPECT_LE(r.max_jump_after_mm, limit + 1e-6);
  // Both movements still go their whole way (the frames far from them are
  // untouched), and the last frame was allowed to move toward its neighbour.
  EXPECT_EQ(t.forearm_in_head.row(0), unlimited.forearm_in_head.row(0));
  const int64_t mid = (a + 12 + n - 5) / 2;
  EXPECT_NEAR(t.forearm_in_head(mid, 4) - t.forearm_in_head(0, 4), 72.0, 1e-6);
  EXPECT_NEAR(t.forearm_in_head(mid, 3), unlimited.forearm_in_head(mid, 3), 1e-6);
  EXPECT_LT(t.forearm_in_head(n - 1, 3), unlimited.forearm_in_head(n - 1, 3) - 1.0);
}

}  // namespace
}  // namespace csw
