#pragma once
// Guided iterative PCA (Badin/Bailly/Revéret; MOTHER §2.2; seed
// Gibert-Bailly-Elisei §3.1): a linear articulatory model whose parameters are
// extracted one group of markers at a time.
//
// Data: frames × 3M coordinates (x, y, z of marker 0, then marker 1, ...),
// already in the head frame. The fit removes the mean. Then, for each step in
// order:
//   1. PCA of the current residual restricted to the step's marker subset;
//   2. its first n scores become the step's control parameters, normalised to
//      zero mean and unit variance over the training frames;
//   3. the residual of ALL coordinates is regressed on those scores, which
//      gives each parameter's loading on every marker ("each component
//      predicting all markers"); the prediction is subtracted.
// Every parameter's scores are orthogonal to every other's (each step's scores
// lie in the column space of a residual already orthogonal to earlier scores),
// so the variance fractions add up: Σ variance_explained + residual = 1.
//
// MOTHER's "second jaw component" (jaw advance) is read as the first component
// of a second PCA of the jaw subset taken after the lip steps.
#include <Eigen/Core>
#include <string>
#include <vector>

namespace csw {

struct GuidedPcaStep {
  std::string name;          // parameter names are name, or name1, name2, ... when components > 1
  std::vector<int> markers;  // marker indices (columns 3m, 3m+1, 3m+2); empty = all markers
  int components = 1;
};

struct GuidedPcaModel {
  Eigen::VectorXd mean;  // 3M
  std::vector<GuidedPcaStep> steps;
  Eigen::MatrixXd loadings;                  // 3M × P: coordinates = mean + loadings · params
  std::vector<std::string> parameter_names;  // P
  std::vector<double> variance_explained;    // P: fraction of the total variance about the mean
  double residual_variance = 0;              // fraction left unexplained after all steps
  // Relative ridge of Estimate: λ = kEstimateRidge · trace(AᵀA) / P.
  static constexpr double kEstimateRidge = 1e-12;

  int num_parameters() const { return static_cast<int>(loadings.cols()); }
  int num_coordinates() const { return static_cast<int>(loadings.rows()); }

  // mean + loadings · params. Throws InvalidInput on a size mismatch.
  Eigen::VectorXd Predict(const Eigen::VectorXd& params) const;
  // Least-squares parameters from the visible coordinates: solves
  // (AᵀA + λI) p = Aᵀ(x − mean) over the visible rows A of the loadings with
  // an LDLT; λ (above) only guards against visible sets that leave a parameter
  // undetermined, and shifts an exactly-fitting answer by ~1e-12 relative.
  // `visible` has one flag per coordinate (size 3M); hidden coordinates may
  // hold anything (NaN included). Throws InvalidInput on a size mismatch, a
  // non-finite visible coordinate, or no visible coordinate.
  Eigen::VectorXd Estimate(const Eigen::VectorXd& coordinates, const std::vector<bool>& visible) const;
  // Same with every coordinate visible.
  Eigen::VectorXd Estimate(const Eigen::VectorXd& coordinates) const;
};

// Fits the model. Throws InvalidInput when: fewer than 2 frames, a column
// count that is not a positive multiple of 3, a non-finite value, a marker
// index out of range or repeated within a step, a step asking for fewer than 1
// component or more than its subset can give, or a requested component whose
// variance is (numerically) zero — its parameter would be undefined.
GuidedPcaModel FitGuidedPca(const Eigen::MatrixXd& data, const std::vector<GuidedPcaStep>& steps);

// Per-marker flags → per-coordinate flags (each marker's x, y, z).
std::vector<bool> CoordinateMaskFromMarkers(const std::vector<bool>& marker_visible);

// Marker groups of a face marker set (marker indices). The caller maps the
// marker set's roles to indices.
struct FaceMarkerGroups {
  std::vector<int> jaw;           // jaw / chin ("LT" in MOTHER)
  std::vector<int> lip_rounding;  // markers showing rounding/spreading (usually all lip markers)
  std::vector<int> lips_upper;
  std::vector<int> lips_lower;
  std::vector<int> lip_corners;
  std::vector<int> throat;
};

// Seed §3.1: jaw, lip rounding, upper lip, lower lip, lip corners, throat —
// one component each — then `residual_components` over all markers (0 = no
// residual step). Groups that are empty are skipped.
std::vector<GuidedPcaStep> SeedFaceSteps(const FaceMarkerGroups& groups, int residual_components = 0);

// MOTHER §2.2: jaw opening (jaw, 1), lips (union of the four lip groups, 3:
// protrusion, closing, raising), jaw advance (jaw, 1), residual (all markers,
// 1). Empty groups are skipped.
std::vector<GuidedPcaStep> MotherFaceSteps(const FaceMarkerGroups& groups);

}  // namespace csw
