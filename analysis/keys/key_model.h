#pragma once
// Gaussian key models (seed §4): one full-covariance Gaussian per hand shape
// (0-8) on the seven distances, one per placement (0-5) on the 3D placement
// feature (hand_features.h). Per-frame posteriors are the gestural score.
//
// Covariance regularisation (GaussianOptions), in this order (n_k: the
// class's samples minus one, per covariance entry when samples miss values):
//   1. shrinkage towards the pooled within-class covariance S_w:
//        Σ_k = (n_k Σ̂_k + τ S_w) / (n_k + τ)       (τ = shrinkage_samples)
//      so a class seen a few times borrows the common spread;
//   2. a ridge: Σ_k += (ridge_fraction · tr(Σ_k) / d + min_variance) I.
// Class priors: uniform over the trained classes, or proportional to counts.
// A class without training samples is absent (posterior 0).
//
// Missing dimensions (NaN) are marginalised: the class likelihood is that of
// the observed sub-vector under the sub-mean and sub-covariance. A frame with
// every dimension missing gets the priors. Complete frames take a fast path
// (precomputed inverse Cholesky factors).
#include <Eigen/Core>
#include <cstdint>
#include <string>
#include <vector>

#include "analysis/keys/hand_features.h"
#include "core/take.h"
#include "models/rigid_model.h"

namespace csw {
struct KeyTargets;  // core/labels.h
}  // namespace csw

namespace csw::keys {

inline constexpr int kNumShapes = 9;      // 0 = rest, 1-8
inline constexpr int kNumPlacements = 6;  // 0 = rest / free space, 1-5

enum class PriorKind { kUniform, kCounts };
const char* PriorKindName(PriorKind kind);  // "uniform", "counts"
bool ParsePriorKind(const std::string& name, PriorKind* kind);

struct GaussianOptions {
  double shrinkage_samples = 5.0;  // τ above (0 = none)
  double ridge_fraction = 0.01;    // of the mean variance
  double min_variance = 0.25;      // feature units² (mm²): 0.5 mm sd floor
  PriorKind priors = PriorKind::kUniform;
  std::string Check() const;
};

struct GaussianClass {
  int label = 0;
  std::string name;
  int64_t count = 0;  // training samples
  double prior = 0.0;
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;  // regularised
};

class GaussianClassifier {
 public:
  GaussianClassifier() = default;
  // One Gaussian per label present in `labels`. Samples may have missing
  // (NaN) dimensions: means and covariance entries are available-case
  // estimates (each over the samples observing that dimension / pair), the
  // shrunk covariance has its negative eigenvalues clipped to 0 before the
  // ridge; rows with nothing observed are skipped. num_labels: labels are
  // 0..num_labels-1; class_names one per label. Throws InvalidInput when no class has a sample or a label is out of
  // range.
  static GaussianClassifier Fit(const Eigen::MatrixXd& samples, const std::vector<int>& labels, int num_labels,
                                const std::vector<std::string>& class_names,
                                const std::vector<std::string>& feature_names, const GaussianOptions& options);
  // From stored parameters (a model file); throws InvalidInput when a
  // covariance is not positive definite or sizes disagree.
  static GaussianClassifier FromClasses(std::vector<GaussianClass> classes, int num_labels,
                                        std::vector<std::string> feature_names, const GaussianOptions& options);

  int dims() const { return static_cast<int>(feature_names_.size()); }
  int num_labels() const { return num_labels_; }
  const std::vector<GaussianClass>& classes() const { return classes_; }
  const std::vector<std::string>& feature_names() const { return feature_names_; }
  const GaussianOptions& options() const { return options_; }

  // log p(x | class) + log prior of every label (-inf for absent labels); x has
  // dims() values, NaN = missing (marginalised). out: num_labels() values.
  void LogJoint(const double* x, double* out) const;
  // frames × num_labels() posteriors (rows sum to 1).
  Eigen::MatrixXd Posteriors(const Eigen::MatrixXd& features) const;
  // One frame's posteriors into out (num_labels() values).
  void Posterior(const double* x, double* out) const;
  // Closeness of x to each class mean: minus the squared Mahalanobis distance
  // over the observed dimensions divided by their number (0 at the mean; NaN
  // for absent labels and frames with nothing observed). Unlike the posterior
  // it does not saturate, so it peaks where the posture is reached.
  void Closeness(const double* x, double* out) const;
  Eigen::MatrixXd Closeness(const Eigen::MatrixXd& features) const;

 private:
  void Prepare();
  void Evaluate(const double* x, double* log_joint, double* closeness) const;
  GaussianOptions options_;
  int num_labels_ = 0;
  std::vector<std::string> feature_names_;
  std::vector<GaussianClass> classes_;
  // Fast path, per class: mean (d), inverse Cholesky factor (d × d, row-major
  // lower triangle), log normaliser + log prior.
  std::vector<double> fast_mean_, fast_inv_, fast_const_;
};

// A key code "PS" (core/labels.h KeyCode::Text).
std::string KeyCode(int placement, int shape);

// Labelled target frames of one take.
struct KeyLabels {
  std::vector<int64_t> shape_frames;
  std::vector<int> shapes;
  std::vector<int64_t> placement_frames;
  std::vector<int> placements;
  std::vector<int> placement_shapes;  // the shape of the key each placement target belongs to
};

// The target frames of the targets read from the label tiers
// (core/labels.h ReadKeyTargets, which parses and checks the key codes):
// frame = round(time × rate_hz), kept inside the take. Throws InvalidInput
// naming `where` when rate_hz is not > 0.
KeyLabels LabelsFromTargets(const KeyTargets& targets, double rate_hz, int64_t frames, const std::string& where);

struct KeyModelOptions {
  GaussianOptions shape;
  GaussianOptions placement;
  std::vector<int> index_shapes = {1, 6};  // shapes whose longest extended finger is the index
  int target_window_frames = 0;            // also train on ± this many frames around each target
  std::string Check() const;
};

struct KeyModel {
  static constexpr int kVersion = 1;
  GaussianClassifier shape;      // 9 labels on the 7 distances
  GaussianClassifier placement;  // 6 labels on the placement feature (x, y, z in the head frame)
  std::vector<int> index_shapes;
  HandLayout layout;
  Eigen::Matrix3Xd head_reference;  // 3 × layout.head.size()
  ModelInfo info;                   // provenance (corpus, training takes, options as JSON)
  bool IndexFinger(int shape) const;
};

// Training samples gathered over takes.
struct KeyTrainingSet {
  Eigen::MatrixXd shape_samples;  // n × 7
  std::vector<int> shape_labels;
  Eigen::MatrixXd placement_samples;  // m × 3
  std::vector<int> placement_labels;
  // Adds the labelled frames of one take (window as in the options).
  void Add(const HandFeatures& features, const KeyLabels& labels, const KeyModelOptions& options);
};

KeyModel TrainKeyModel(const KeyTrainingSet& set, const HandLayout& layout, const Eigen::Matrix3Xd& head_reference,
                       const KeyModelOptions& options);

// The gestural score of a take.
struct KeyPosteriors {
  Eigen::MatrixXd shape;                // frames × 9
  Eigen::MatrixXd placement;            // frames × 6
  Eigen::MatrixXd placement_features;   // frames × 3: the chosen fingertip in the head frame
  Eigen::MatrixXd shape_closeness;      // frames × 9 (GaussianClassifier::Closeness); may be empty
  Eigen::MatrixXd placement_closeness;  // frames × 6
  int64_t frames() const { return shape.rows(); }
};

// Shape posteriors first; the placement feature of a frame is the tip of the
// finger of its most probable shape; then placement posteriors.
KeyPosteriors ScoreFrames(const KeyModel& model, const HandFeatures& features);

}  // namespace csw::keys
