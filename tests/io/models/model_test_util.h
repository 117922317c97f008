#pragma once
// Exact comparison of models (bitwise for doubles, NaN equal to NaN) for the
// model file tests.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "io/models/model_file.h"

namespace csw::testing {

inline bool SameDouble(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

template <typename A, typename B>
inline void ExpectSameMatrix(const A& a, const B& b, const std::string& what) {
  ASSERT_EQ(a.rows(), b.rows()) << what;
  ASSERT_EQ(a.cols(), b.cols()) << what;
  for (Eigen::Index c = 0; c < a.cols(); ++c)
    for (Eigen::Index r = 0; r < a.rows(); ++r)
      EXPECT_TRUE(SameDouble(a(r, c), b(r, c)))
          << what << " (" << r << ", " << c << "): " << a(r, c) << " vs " << b(r, c);
}

inline void ExpectSameDoubles(const std::vector<double>& a, const std::vector<double>& b, const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  for (size_t i = 0; i < a.size(); ++i) EXPECT_TRUE(SameDouble(a[i], b[i])) << what << " [" << i << "]";
}

inline void ExpectSameInfo(const ModelInfo& a, const ModelInfo& b, const std::string& what) {
  EXPECT_EQ(a.corpus, b.corpus) << what;
  EXPECT_EQ(a.training_takes, b.training_takes) << what;
  EXPECT_EQ(a.config_json, b.config_json) << what;
  EXPECT_EQ(a.created_utc, b.created_utc) << what;
  EXPECT_EQ(a.csw_version, b.csw_version) << what;
  EXPECT_EQ(a.training_frames, b.training_frames) << what;
  EXPECT_EQ(a.selected_frames, b.selected_frames) << what;
  EXPECT_TRUE(SameDouble(a.training_rms_mm, b.training_rms_mm)) << what;
}

inline void ExpectSameRigid(const RigidModel& a, const RigidModel& b, const std::string& what) {
  EXPECT_EQ(a.name, b.name) << what;
  EXPECT_EQ(a.markers, b.markers) << what;
  ExpectSameMatrix(a.reference, b.reference, what + ".reference");
  ExpectSameMatrix(a.motion.mean, b.motion.mean, what + ".motion.mean");
  ExpectSameMatrix(a.motion.components, b.motion.components, what + ".motion.components");
  ExpectSameMatrix(a.motion.variances, b.motion.variances, what + ".motion.variances");
  ExpectSameMatrix(a.motion.explained_fraction, b.motion.explained_fraction, what + ".motion.explained_fraction");
  EXPECT_TRUE(SameDouble(a.motion.total_variance, b.motion.total_variance)) << what;
  ExpectSameInfo(a.info, b.info, what + ".info");
}

inline void ExpectSameFace(const FaceModel& a, const FaceModel& b) {
  EXPECT_EQ(a.layout.head, b.layout.head);
  EXPECT_EQ(a.layout.face, b.layout.face);
  EXPECT_EQ(a.layout.throat, b.layout.throat);
  ExpectSameDoubles(a.layout.throat_weights, b.layout.throat_weights, "face.layout.throat_weights");
  ExpectSameRigid(a.head, b.head, "face.head");
  ExpectSameMatrix(a.head_weights, b.head_weights, "face.head_weights");
  ExpectSameMatrix(a.rest_pose.rotation, b.rest_pose.rotation, "face.rest_pose.rotation");
  ExpectSameMatrix(a.rest_pose.translation, b.rest_pose.translation, "face.rest_pose.translation");
  ExpectSameMatrix(a.rotation_offsets, b.rotation_offsets, "face.rotation_offsets");
  ExpectSameMatrix(a.shape.mean, b.shape.mean, "face.shape.mean");
  ExpectSameMatrix(a.shape.loadings, b.shape.loadings, "face.shape.loadings");
  EXPECT_EQ(a.shape.parameter_names, b.shape.parameter_names);
  ExpectSameDoubles(a.shape.variance_explained, b.shape.variance_explained, "face.shape.variance_explained");
  EXPECT_TRUE(SameDouble(a.shape.residual_variance, b.shape.residual_variance));
  ASSERT_EQ(a.shape.steps.size(), b.shape.steps.size());
  for (size_t i = 0; i < a.shape.steps.size(); ++i) {
    EXPECT_EQ(a.shape.steps[i].name, b.shape.steps[i].name) << i;
    EXPECT_EQ(a.shape.steps[i].markers, b.shape.steps[i].markers) << i;
    EXPECT_EQ(a.shape.steps[i].components, b.shape.steps[i].components) << i;
  }
  ExpectSameInfo(a.info, b.info, "face.info");
}

inline void ExpectSameHand(const HandModel& a, const HandModel& b) {
  EXPECT_EQ(a.layout.forearm, b.layout.forearm);
  EXPECT_EQ(a.layout.hand, b.layout.hand);
  ASSERT_EQ(a.layout.segments.size(), b.layout.segments.size());
  for (size_t i = 0; i < a.layout.segments.size(); ++i) {
    EXPECT_EQ(a.layout.segments[i].name, b.layout.segments[i].name) << i;
    EXPECT_EQ(a.layout.segments[i].parent, b.layout.segments[i].parent) << i;
    EXPECT_EQ(a.layout.segments[i].markers, b.layout.segments[i].markers) << i;
  }
  ASSERT_EQ(a.rest.size(), b.rest.size());
  for (size_t i = 0; i < a.rest.size(); ++i) ExpectSameMatrix(a.rest[i], b.rest[i], "hand.rest " + std::to_string(i));
  ExpectSameRigid(a.forearm, b.forearm, "hand.forearm");
  EXPECT_EQ(a.angle_names, b.angle_names);
  const AnglePca& pa = a.shape.angle_pca;
  const AnglePca& pb = b.shape.angle_pca;
  ExpectSameMatrix(pa.mean, pb.mean, "hand.angle_pca.mean");
  ExpectSameMatrix(pa.components, pb.components, "hand.angle_pca.components");
  ExpectSameMatrix(pa.variances, pb.variances, "hand.angle_pca.variances");
  ExpectSameDoubles(pa.variance_explained, pb.variance_explained, "hand.angle_pca.variance_explained");
  const HandRegression& ra = a.shape.regression;
  const HandRegression& rb = b.shape.regression;
  ExpectSameMatrix(ra.coefficients, rb.coefficients, "hand.regression.coefficients");
  EXPECT_EQ(ra.num_angles, rb.num_angles);
  EXPECT_EQ(ra.rank, rb.rank);
  EXPECT_TRUE(SameDouble(ra.rms_residual, rb.rms_residual));
  EXPECT_EQ(ra.warnings, rb.warnings);
  ExpectSameMatrix(a.param_scale, b.param_scale, "hand.param_scale");
  EXPECT_EQ(a.fill.empty(), b.fill.empty());
  ExpectSameMatrix(a.fill.mean, b.fill.mean, "hand.fill.mean");
  ExpectSameMatrix(a.fill.covariance, b.fill.covariance, "hand.fill.covariance");
  EXPECT_TRUE(SameDouble(a.fill.ridge_mm2, b.fill.ridge_mm2));
  EXPECT_EQ(a.fill.frames, b.fill.frames);
  EXPECT_EQ(a.fill.iterations, b.fill.iterations);
  ExpectSameInfo(a.info, b.info, "hand.info");
}

inline void ExpectSameFile(const ModelFile& a, const ModelFile& b) {
  ASSERT_EQ(a.head.has_value(), b.head.has_value());
  ASSERT_EQ(a.forearm.has_value(), b.forearm.has_value());
  ASSERT_EQ(a.face.has_value(), b.face.has_value());
  ASSERT_EQ(a.hand.has_value(), b.hand.has_value());
  if (a.head) ExpectSameRigid(*a.head, *b.head, "head");
  if (a.forearm) ExpectSameRigid(*a.forearm, *b.forearm, "forearm");
  if (a.face) ExpectSameFace(*a.face, *b.face);
  if (a.hand) ExpectSameHand(*a.hand, *b.hand);
}

}  // namespace csw::testing
