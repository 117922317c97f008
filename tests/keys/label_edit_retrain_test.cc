// Editing labels through the label model (core/labels.h: add, move, relabel,
// undo, redo), retraining the key model on the edited tier and scoring again:
// the GUI's label-edit loop without the GUI. Synthetic features: four
// well-separated hand postures of 15 frames each, so the answers are known:
// a class trained on one labelled frame has exactly that frame's features as
// its mean, the posterior argmax of a posture's frames is the class labelled
// there, and undo/redo give back the earlier posteriors bit for bit (training
// is deterministic).
#include <gtest/gtest.h>

#include <cmath>

#include "analysis/keys/key_model.h"
#include "core/labels.h"

namespace csw::keys {
namespace {

constexpr double kRateHz = 100.0;
constexpr int kFramesPerPosture = 15;
constexpr int kPostures = 4;
constexpr int kFrames = kFramesPerPosture * kPostures;

// Posture q (0-3): distances 40 + 25 q mm in every dimension (plus a ±0.6 mm
// deterministic wobble per frame and dimension), fingertips 30 q mm along x.
HandFeatures Features() {
  HandFeatures f;
  f.distances.resize(kFrames, kNumDistances);
  f.index_tip.resize(kFrames, 3);
  f.middle_tip.resize(kFrames, 3);
  for (int t = 0; t < kFrames; ++t) {
    const int q = t / kFramesPerPosture;
    for (int d = 0; d < kNumDistances; ++d) f.distances(t, d) = 40.0 + 25.0 * q + 0.6 * std::sin(1.7 * t + 0.9 * d);
    for (int d = 0; d < 3; ++d) {
      const double wobble = 0.6 * std::cos(1.3 * t + 0.7 * d);
      f.index_tip(t, d) = (d == 0 ? 30.0 * q : 10.0 * d) + wobble;
      f.middle_tip(t, d) = (d == 0 ? 30.0 * q : 10.0 * d) + 5.0 + wobble;
    }
  }
  return f;
}

double TimeOf(int frame) { return frame / kRateHz; }

// Retrains on the model's tier and scores every frame.
KeyPosteriors Retrain(const LabelModel& labels, const HandFeatures& features, KeyModel* model_out = nullptr) {
  const KeyLabels l = LabelsFromTargets(ReadKeyTargets({labels.tier()}, "synthetic"), kRateHz, kFrames, "synthetic");
  KeyModelOptions options;
  KeyTrainingSet set;
  set.Add(features, l, options);
  KeyModel model = TrainKeyModel(set, HandLayout{}, Eigen::Matrix3Xd(3, 0), options);
  KeyPosteriors p = ScoreFrames(model, features);
  if (model_out != nullptr) *model_out = std::move(model);
  return p;
}

const GaussianClass* ClassOf(const GaussianClassifier& g, int label) {
  for (const auto& c : g.classes())
    if (c.label == label) return &c;
  return nullptr;
}

int ArgMax(const Eigen::MatrixXd& p, int frame) {
  Eigen::Index best = 0;
  p.row(frame).maxCoeff(&best);
  return static_cast<int>(best);
}

TEST(LabelEditRetrain, EditsUndoAndRedoChangeThePosteriorsAsExpected) {
  const HandFeatures features = Features();
  // Postures 0-2 labelled twice each (shapes 1, 2, 3 at placements 1, 2, 3);
  // posture 3 (frames 45-59) unlabelled.
  LabelTier tier{"keys",
                 LabelTier::Kind::kPoint,
                 0.0,
                 TimeOf(kFrames - 1),
                 {{TimeOf(3), TimeOf(3), "11"},
                  {TimeOf(8), TimeOf(8), "11"},
                  {TimeOf(18), TimeOf(18), "22"},
                  {TimeOf(23), TimeOf(23), "22"},
                  {TimeOf(33), TimeOf(33), "33"},
                  {TimeOf(38), TimeOf(38), "33"}}};
  LabelModel labels(tier, true, "synthetic");
  LabelHistory history(&labels);

  KeyModel model;
  const KeyPosteriors p0 = Retrain(labels, features, &model);
  ASSERT_EQ(p0.shape.rows(), kFrames);
  EXPECT_EQ(ClassOf(model.shape, 4), nullptr);
  for (int q = 0; q < 3; ++q) EXPECT_EQ(ArgMax(p0.shape, q * kFramesPerPosture + 7), q + 1) << "posture " << q;

  // 1. Add "44" at frame 50: a one-sample class whose mean is frame 50's
  // features; it wins posture 3.
  history.Push(MakeAddLabel(TimeOf(50), "44"));
  const KeyPosteriors p1 = Retrain(labels, features, &model);
  const GaussianClass* s4 = ClassOf(model.shape, 4);
  ASSERT_NE(s4, nullptr);
  EXPECT_EQ(s4->count, 1);
  EXPECT_EQ(s4->mean.transpose(), features.distances.row(50));
  const GaussianClass* p4 = ClassOf(model.placement, 4);
  ASSERT_NE(p4, nullptr);
  EXPECT_EQ(p4->mean.transpose(), features.middle_tip.row(50));  // shape 4 points with the middle finger
  for (int t = 45; t < kFrames; ++t) {
    EXPECT_EQ(ArgMax(p1.shape, t), 4) << t;
    EXPECT_EQ(ArgMax(p1.placement, t), 4) << t;
  }
  for (int t = 0; t < 45; ++t) EXPECT_NE(ArgMax(p1.shape, t), 4) << t;

  // 2. Move it to frame 55: the class mean follows.
  const long added = labels.Find(TimeOf(50), 1e-9);
  ASSERT_EQ(added, 6);
  history.Push(MakeMoveLabel(static_cast<size_t>(added), TimeOf(55)));
  const KeyPosteriors p2 = Retrain(labels, features, &model);
  ASSERT_NE(ClassOf(model.shape, 4), nullptr);
  EXPECT_EQ(ClassOf(model.shape, 4)->mean.transpose(), features.distances.row(55));
  EXPECT_EQ(ArgMax(p2.shape, 47), 4);

  // 3. Relabel it "16": shape 4 and placement 4 vanish (posterior 0 at every
  // frame), shape 6 (an index-finger shape) and placement 1 take posture 3;
  // placement 1's class now has three samples.
  history.Push(MakeRelabel(static_cast<size_t>(labels.Find(TimeOf(55), 1e-9)), "16"));
  const KeyPosteriors p3 = Retrain(labels, features, &model);
  EXPECT_EQ(ClassOf(model.shape, 4), nullptr);
  EXPECT_EQ(ClassOf(model.placement, 4), nullptr);
  ASSERT_NE(ClassOf(model.shape, 6), nullptr);
  EXPECT_EQ(ClassOf(model.shape, 6)->mean.transpose(), features.distances.row(55));
  EXPECT_EQ(ClassOf(model.placement, 1)->count, 3);
  EXPECT_EQ(p3.shape.col(4).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_EQ(p3.placement.col(4).cwiseAbs().maxCoeff(), 0.0);
  for (int t = 45; t < kFrames; ++t) EXPECT_EQ(ArgMax(p3.shape, t), 6) << t;
  // Placement 1 is now the mean of three index tips (shapes 1 and 6 point with
  // the index), two of posture 0 and one of posture 3: analytic.
  const Eigen::RowVector3d place1 =
      (features.index_tip.row(3) + features.index_tip.row(8) + features.index_tip.row(55)) / 3.0;
  EXPECT_LT((ClassOf(model.placement, 1)->mean.transpose() - place1).norm(), 1e-12);

  // Undo, undo: exactly the posteriors after the add; undo: the original ones.
  history.Undo();
  EXPECT_EQ(Retrain(labels, features).shape, p2.shape);
  EXPECT_EQ(Retrain(labels, features).placement, p2.placement);
  history.Undo();
  EXPECT_EQ(Retrain(labels, features).shape, p1.shape);
  history.Undo();
  EXPECT_FALSE(history.CanUndo());
  ASSERT_EQ(labels.size(), tier.labels.size());
  for (size_t i = 0; i < labels.size(); ++i) {
    EXPECT_EQ(labels.at(i).start_s, tier.labels[i].start_s) << i;
    EXPECT_EQ(labels.at(i).text, tier.labels[i].text) << i;
  }
  EXPECT_EQ(Retrain(labels, features).shape, p0.shape);
  EXPECT_EQ(Retrain(labels, features).placement, p0.placement);
  // Redo all three: exactly the relabelled posteriors again.
  history.Redo();
  history.Redo();
  EXPECT_EQ(Retrain(labels, features).shape, p2.shape);
  history.Redo();
  EXPECT_FALSE(history.CanRedo());
  EXPECT_EQ(Retrain(labels, features).shape, p3.shape);
  EXPECT_EQ(Retrain(labels, features).placement, p3.placement);
}

}  // namespace
}  // namespace csw::keys
