#pragma once
// Hand shape model of the seed (Gibert-Bailly-Elisei §3.2): joint angles →
// hand marker coordinates in the forearm frame, through the features
//   P = [1, cos(a_1) … cos(a_n), sin(a_1) … sin(a_n)]
// and a linear map `coefficients` (the seed's Xang): coordinates = P · Xang.
// (A pure joint rotation moves a skin marker on an ellipse.) Optionally the
// angles are themselves driven by a few principal components (AnglePca, the
// seed's naH parameters): ang = mean_A + paH · eigv_A.
//
// Estimating angles from visible markers (the inverse problem) is not here.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace csw {

struct HandRegressionOptions {
  // 0: exact least squares (minimum-norm when the features are rank-deficient,
  // via a complete orthogonal decomposition). > 0: ridge on the standardised
  // features, minimising ‖Z·β − Y‖² + ridge · frames · ‖β‖², solved as an
  // augmented QR (never forms normal equations).
  double ridge = 0;
  // Relative threshold below which a pivot of the decomposition counts as zero.
  double rank_tolerance = 1e-10;
  // Names of the n angles for warnings ("thumb1.twist"); empty: "angle i" (0-based).
  std::vector<std::string> angle_names;
};

struct HandRegression {
  Eigen::MatrixXd coefficients;  // (1 + 2n) × D, rows in feature order
  int num_angles = 0;
  int rank = 0;             // numerical rank of the non-constant features
  double rms_residual = 0;  // over the training coordinates
  std::vector<std::string> warnings;

  // One frame: n angles (radians) → D coordinates. Throws InvalidInput on a size mismatch.
  Eigen::VectorXd Predict(const Eigen::VectorXd& angles) const;
  // Frames × n → frames × D.
  Eigen::MatrixXd PredictFrames(const Eigen::MatrixXd& angles) const;
};

// [1, cos(a), sin(a)] for one frame.
Eigen::RowVectorXd AngleFeatures(const Eigen::VectorXd& angles);

// Fits frames × n angles to frames × D coordinates. Features are centred and
// scaled to unit RMS before solving (the intercept is recovered afterwards);
// a cos or sin column that is constant over the training frames (RMS
// deviation < 1e-9, e.g. an angle that never moves) is dropped — its effect is
// absorbed by the intercept — and one warning line names them all: an angle
// whose cos and sin are both dropped by its name, a lone feature as "cos(name)". Throws InvalidInput on fewer than
// 2 frames, mismatched row counts, no coordinates, or a non-finite value
// (drop frames with gaps first).
HandRegression FitHandRegression(const Eigen::MatrixXd& angles, const Eigen::MatrixXd& coordinates,
                                 const HandRegressionOptions& options = {});

// PCA of joint angles. Each angle's deviations from its circular mean are
// wrapped to (−π, π] (angles that cross ±π do not jump), then centred on their
// own mean; mean = circular mean + that shift.
struct AnglePca {
  Eigen::VectorXd mean;                    // n: centre of each angle (see above), (−π, π]
  Eigen::MatrixXd components;              // n × k, orthonormal columns, largest variance first
  Eigen::VectorXd variances;               // k: variance of each parameter (rad², divisor frames − 1)
  std::vector<double> variance_explained;  // k: fraction of the total angle variance

  int num_parameters() const { return static_cast<int>(components.cols()); }
  // mean + components · params (not wrapped; cos/sin do not care).
  Eigen::VectorXd Angles(const Eigen::VectorXd& params) const;
  // componentsᵀ · wrap(angles − mean).
  Eigen::VectorXd Params(const Eigen::VectorXd& angles) const;
};

// Throws InvalidInput on fewer than 2 frames, no angles, a non-finite value or
// components outside 1..n.
AnglePca FitAnglePca(const Eigen::MatrixXd& angles, int components);

// The seed's whole hand shape model: naH angle parameters → coordinates.
struct HandShapeModel {
  AnglePca angle_pca;
  HandRegression regression;
  Eigen::VectorXd Predict(const Eigen::VectorXd& params) const;
};

// Fits the angle PCA, then the regression on the angles the PCA predicts for
// each training frame (as in the seed: "the sin() and cos() of these predicted
// values"), so the regression matches what Predict will feed it.
HandShapeModel FitHandShapeModel(const Eigen::MatrixXd& angles, const Eigen::MatrixXd& coordinates,
                                 int angle_components, const HandRegressionOptions& options = {});

}  // namespace csw
