#include "datasets/face_model.h"

#include <gtest/gtest.h>

#include <cmath>

#include "synth/phonetics.h"

namespace csw {
namespace {

TEST(VirtualFace, SixtyThreeMarkersWithRigidHeadSetAndEighteenThroatMarkers) {
  VirtualFace face;
  EXPECT_EQ(face.num_markers(), 63);
  EXPECT_GE(face.rigid_markers().size(), 4u);
  EXPECT_EQ(face.throat_markers().size(), 18u);
  for (const auto& t : face.throat_markers()) {
    double w = face.head_weights()[face.MarkerIndex(t)];
    EXPECT_GT(w, 0.0);
    EXPECT_LT(w, 1.0);
  }
  // Rigid markers do not move with the articulators.
  for (const auto& r : face.rigid_markers())
    for (int k = 0; k < kNumArticulatory; ++k) EXPECT_EQ(face.basis(k).col(face.MarkerIndex(r)).norm(), 0.0);
}

TEST(VirtualFace, MarkersAreLinearInTheArticulatoryParameters) {
  VirtualFace face;
  ArticulatoryVector a, b;
  a << 10, 1, -3, 2, 1, 4;
  b << 2, -1, 5, 0, 3, -2;
  Eigen::Matrix3Xd sum = face.MarkersInHead(a + b) - face.neutral();
  Eigen::Matrix3Xd parts = (face.MarkersInHead(a) - face.neutral()) + (face.MarkersInHead(b) - face.neutral());
  EXPECT_LT((sum - parts).cwiseAbs().maxCoeff(), 1e-9);
  // Jaw opening: the chin goes down (and a little back), about 1 mm per unit.
  ArticulatoryVector jaw = ArticulatoryVector::Zero();
  jaw[kJawOpening] = 10.0;
  Eigen::Vector3d d =
      face.MarkersInHead(jaw).col(face.MarkerIndex("CHIN")) - face.neutral().col(face.MarkerIndex("CHIN"));
  EXPECT_LT(d.z(), -8.0);
  EXPECT_LT(d.y(), 0.0);
  EXPECT_NEAR(d.norm(), 10.0 * std::hypot(51.0, 94.0) / 100.0, 1e-9);  // chin − TMJ = (0, 94, −51)
}

TEST(VirtualFace, ThroatFollowsTheHeadWithItsWeight) {
  VirtualFace face;
  HeadMotion m;
  m.translation = Eigen::Vector3d(0.0, 10.0, 0.0);
  Eigen::Matrix3Xd moved = face.MarkersMoved(ArticulatoryVector::Zero(), m);
  for (int i = 0; i < face.num_markers(); ++i) {
    Eigen::Vector3d d = moved.col(i) - face.neutral().col(i);
    EXPECT_NEAR(d.y(), 10.0 * face.head_weights()[i], 1e-9) << face.marker_names()[static_cast<size_t>(i)];
  }
}

// Öhman coarticulation on a hand-built /aba/: vowel targets at the vowel
// centres, full lip closure (resistance 1) inside the /b/, a jaw value between
// the vowel's and the consonant's (resistance 0.4) inside the /b/.
TEST(VirtualFace, CoarticulationReachesVowelTargetsAndBilabialClosure) {
  std::vector<Phone> phones(5);
  const char* ipa[] = {"", "a", "b", "a", ""};
  const double t[] = {0.0, 0.3, 0.6, 0.7, 1.0, 1.3};
  for (int i = 0; i < 5; ++i) {
    phones[static_cast<size_t>(i)].ipa = ipa[i];
    phones[static_cast<size_t>(i)].start_s = t[i];
    phones[static_cast<size_t>(i)].end_s = t[i + 1];
  }
  const PhonemeTarget a = ArticulatoryTarget("a"), b = ArticulatoryTarget("b");
  ASSERT_TRUE(a.vowel);
  ASSERT_FALSE(b.vowel);
  std::vector<ArticulatoryVector> p = Coarticulate(phones, {0.45, 0.65, 0.85});
  // Vowel centres: 0.45 is 0.1 s before the /b/ plateau starts (0.61), outside its 70 ms window.
  for (int k = 0; k < kNumArticulatory; ++k) EXPECT_NEAR(p[0][k], a.target[k], 1e-9) << k;
  // /b/ centre: carrier is /a/ on both sides.
  EXPECT_NEAR(p[1][kLipClosure], b.target[kLipClosure], 1e-9);
  const double jaw =
      a.target[kJawOpening] + b.resistance[kJawOpening] * (b.target[kJawOpening] - a.target[kJawOpening]);
  EXPECT_NEAR(p[1][kJawOpening], jaw, 1e-9);
  EXPECT_NEAR(p[2][kJawOpening], a.target[kJawOpening], 1e-9);
}

}  // namespace
}  // namespace csw
