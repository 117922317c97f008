#include "analysis/keys/key_model.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "core/error.h"
#include "core/labels.h"

namespace csw::keys {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kNegInf = -std::numeric_limits<double>::infinity();

void Regularise(Eigen::MatrixXd* cov, const GaussianOptions& o) {
  const auto d = cov->rows();
  const double ridge = o.ridge_fraction * cov->trace() / static_cast<double>(d) + o.min_variance;
  cov->diagonal().array() += ridge;
}

}  // namespace

const char* PriorKindName(PriorKind kind) { return kind == PriorKind::kUniform ? "uniform" : "counts"; }

bool ParsePriorKind(const std::string& name, PriorKind* kind) {
  if (name == "uniform") {
    *kind = PriorKind::kUniform;
    return true;
  }
  if (name == "counts") {
    *kind = PriorKind::kCounts;
    return true;
  }
  return false;
}

std::string GaussianOptions::Check() const {
  if (!(shrinkage_samples >= 0)) return "shrinkage_samples must be >= 0";
  if (!(ridge_fraction >= 0)) return "ridge_fraction must be >= 0";
  if (!(min_variance > 0)) return "min_variance must be > 0";
  return "";
}

GaussianClassifier GaussianClassifier::Fit(const Eigen::MatrixXd& samples, const std::vector<int>& labels,
                                           int num_labels, const std::vector<std::string>& class_names,
                                           const std::vector<std::string>& feature_names,
                                           const GaussianOptions& options) {
  const std::string reason = options.Check();
  if (!reason.empty()) throw InvalidInput("Gaussian model: " + reason);
  const auto d = static_cast<Eigen::Index>(feature_names.size());
  if (samples.cols() != d || samples.rows() != static_cast<Eigen::Index>(labels.size()))
    throw InvalidInput("Gaussian model: sample matrix and labels disagree");
  if (static_cast<int>(class_names.size()) != num_labels) throw InvalidInput("Gaussian model: one name per label");
  std::vector<std::vector<Eigen::Index>> rows(static_cast<size_t>(num_labels));
  for (Eigen::Index i = 0; i < samples.rows(); ++i) {
    const int y = labels[static_cast<size_t>(i)];
    if (y < 0 || y >= num_labels)
      throw InvalidInput("Gaussian model: label " + std::to_string(y) + " out of 0-" + std::to_string(num_labels - 1));
    if (!samples.row(i).array().isFinite().any()) continue;
    rows[static_cast<size_t>(y)].push_back(i);
  }
  // Available-case estimates: each mean over the samples where that dimension
  // is observed, each covariance entry over the samples where both are.
  Eigen::VectorXd global_sum = Eigen::VectorXd::Zero(d), global_n = Eigen::VectorXd::Zero(d);
  for (Eigen::Index i = 0; i < samples.rows(); ++i)
    for (Eigen::Index a = 0; a < d; ++a)
      if (std::isfinite(samples(i, a))) {
        global_sum(a) += samples(i, a);
        global_n(a) += 1;
      }
  std::vector<GaussianClass> classes;
  std::vector<Eigen::MatrixXd> scatters, pair_counts;
  Eigen::MatrixXd pooled_scatter = Eigen::MatrixXd::Zero(d, d), pooled_dof = Eigen::MatrixXd::Zero(d, d);
  int64_t total = 0;
  for (int y = 0; y < num_labels; ++y) {
    const auto& r = rows[static_cast<size_t>(y)];
    if (r.empty()) continue;
    GaussianClass c;
    c.label = y;
    c.name = class_names[static_cast<size_t>(y)];
    c.count = static_cast<int64_t>(r.size());
    c.mean = Eigen::VectorXd::Zero(d);
    for (Eigen::Index a = 0; a < d; ++a) {
      double sum = 0, n = 0;
      for (auto i : r)
        if (std::isfinite(samples(i, a))) {
          sum += samples(i, a);
          n += 1;
        }
      c.mean(a) = n > 0 ? sum / n : (global_n(a) > 0 ? global_sum(a) / global_n(a) : 0.0);
    }
    Eigen::MatrixXd scatter = Eigen::MatrixXd::Zero(d, d), count = Eigen::MatrixXd::Zero(d, d);
    for (auto i : r) {
      const Eigen::VectorXd e = samples.row(i).transpose() - c.mean;
      for (Eigen::Index a = 0; a < d; ++a)
        for (Eigen::Index b = 0; b < d; ++b)
          if (std::isfinite(e(a)) && std::isfinite(e(b))) {
            scatter(a, b) += e(a) * e(b);
            count(a, b) += 1;
          }
    }
    const Eigen::MatrixXd dof = (count.array() - 1).max(0).matrix();
    pooled_scatter += scatter;
    pooled_dof += dof;
    total += c.count;
    scatters.push_back(scatter);
    pair_counts.push_back(dof);
    classes.push_back(std::move(c));
  }
  if (classes.empty()) throw InvalidInput("Gaussian model: no class has a training sample");
  const Eigen::MatrixXd pooled =
      (pooled_dof.array() > 0).select(pooled_scatter.array() / pooled_dof.array().max(1), 0.0).matrix();
  const double tau = options.shrinkage_samples;
  for (size_t k = 0; k < classes.size(); ++k) {
    auto& c = classes[k];
    const Eigen::ArrayXXd n = pair_counts[k].array();
    // Σ_ij = (scatter_ij + τ S_ij) / (dof_ij + τ), i.e. (dof Σ̂ + τ S) / (dof + τ).
    Eigen::MatrixXd cov =
        ((n + tau) > 0).select((scatters[k].array() + tau * pooled.array()) / (n + tau).max(1e-300), 0.0);
    // Pairwise estimates need not be positive semi-definite: clip eigenvalues at 0.
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (cov + cov.transpose()));
    cov = eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).asDiagonal() * eig.eigenvectors().transpose();
    c.covariance = cov;
    Regularise(&c.covariance, options);
    c.prior = options.priors == PriorKind::kUniform ? 1.0 / static_cast<double>(classes.size())
                                                    : static_cast<double>(c.count) / static_cast<double>(total);
  }
  return FromClasses(std::move(classes), num_labels, feature_names, options);
}

GaussianClassifier GaussianClassifier::FromClasses(std::vector<GaussianClass> classes, int num_labels,
                                                   std::vector<std::string> feature_names,
                                                   const GaussianOptions& options) {
  GaussianClassifier g;
  g.options_ = options;
  g.num_labels_ = num_labels;
  g.feature_names_ = std::move(feature_names);
  g.classes_ = std::move(classes);
  const auto d = static_cast<Eigen::Index>(g.feature_names_.size());
  for (const auto& c : g.classes_) {
    if (c.label < 0 || c.label >= num_labels)
      throw InvalidInput("Gaussian model: class label " + std::to_string(c.label) + " out of range");
    if (c.mean.size() != d || c.covariance.rows() != d || c.covariance.cols() != d)
      throw InvalidInput("Gaussian model: class " + c.name + " has the wrong dimensions");
    if (!(c.prior > 0) || !std::isfinite(c.prior))
      throw InvalidInput("Gaussian model: class " + c.name + " has a non-positive prior");
  }
  g.Prepare();
  return g;
}

void GaussianClassifier::Prepare() {
  const int d = dims();
  fast_mean_.assign(classes_.size() * static_cast<size_t>(d), 0.0);
  fast_inv_.assign(classes_.size() * static_cast<size_t>(d * d), 0.0);
  fast_const_.assign(classes_.size(), 0.0);
  for (size_t k = 0; k < classes_.size(); ++k) {
    const auto& c = classes_[k];
    Eigen::LLT<Eigen::MatrixXd> llt(c.covariance);
    if (llt.info() != Eigen::Success || !c.covariance.allFinite())
      throw InvalidInput("Gaussian model: the covariance of class " + c.name + " is not positive definite");
    const Eigen::MatrixXd l = llt.matrixL();
    const Eigen::MatrixXd inv = l.triangularView<Eigen::Lower>().solve(Eigen::MatrixXd::Identity(d, d));
    for (int i = 0; i < d; ++i) {
      fast_mean_[k * d + i] = c.mean(i);
      for (int j = 0; j <= i; ++j) fast_inv_[k * d * d + i * d + j] = inv(i, j);
    }
    fast_const_[k] = -0.5 * d * std::log(2 * std::numbers::pi) - l.diagonal().array().log().sum() + std::log(c.prior);
  }
}

void GaussianClassifier::LogJoint(const double* x, double* out) const { Evaluate(x, out, nullptr); }

void GaussianClassifier::Closeness(const double* x, double* out) const {
  std::vector<double> tmp(static_cast<size_t>(num_labels_));
  Evaluate(x, tmp.data(), out);
}

void GaussianClassifier::Evaluate(const double* x, double* out, double* close) const {
  const int d = dims();
  for (int y = 0; y < num_labels_; ++y) out[y] = kNegInf;
  if (close != nullptr)
    for (int y = 0; y < num_labels_; ++y) close[y] = kNaN;
  int observed = 0;
  for (int i = 0; i < d; ++i) observed += std::isnan(x[i]) ? 0 : 1;
  if (observed == d) {
    double diff[16];
    for (size_t k = 0; k < classes_.size(); ++k) {
      const double* m = &fast_mean_[k * d];
      const double* inv = &fast_inv_[k * d * d];
      for (int i = 0; i < d; ++i) diff[i] = x[i] - m[i];
      double q = 0;
      for (int i = 0; i < d; ++i) {
        double s = 0;
        for (int j = 0; j <= i; ++j) s += inv[i * d + j] * diff[j];
        q += s * s;
      }
      out[classes_[k].label] = fast_const_[k] - 0.5 * q;
      if (close != nullptr) close[classes_[k].label] = -q / d;
    }
    return;
  }
  if (observed == 0) {
    for (const auto& c : classes_) out[c.label] = std::log(c.prior);
    return;
  }
  // Marginal over the observed dimensions.
  std::vector<int> idx;
  for (int i = 0; i < d; ++i)
    if (!std::isnan(x[i])) idx.push_back(i);
  const auto o = static_cast<Eigen::Index>(idx.size());
  Eigen::VectorXd e(o);
  Eigen::MatrixXd sub(o, o);
  for (const auto& c : classes_) {
    for (Eigen::Index a = 0; a < o; ++a) {
      e(a) = x[idx[a]] - c.mean(idx[a]);
      for (Eigen::Index b = 0; b < o; ++b) sub(a, b) = c.covariance(idx[a], idx[b]);
    }
    Eigen::LLT<Eigen::MatrixXd> llt(sub);
    const Eigen::VectorXd y = llt.matrixL().solve(e);
    const double logdet = 2 * Eigen::MatrixXd(llt.matrixL()).diagonal().array().log().sum();
    out[c.label] = -0.5 * (o * std::log(2 * std::numbers::pi) + logdet + y.squaredNorm()) + std::log(c.prior);
    if (close != nullptr) close[c.label] = -y.squaredNorm() / static_cast<double>(o);
  }
}

void GaussianClassifier::Posterior(const double* x, double* out) const {
  LogJoint(x, out);
  double mx = kNegInf;
  for (int y = 0; y < num_labels_; ++y) mx = std::max(mx, out[y]);
  double sum = 0;
  for (int y = 0; y < num_labels_; ++y) {
    out[y] = out[y] == kNegInf ? 0.0 : std::exp(out[y] - mx);
    sum += out[y];
  }
  for (int y = 0; y < num_labels_; ++y) out[y] /= sum;
}

Eigen::MatrixXd GaussianClassifier::Closeness(const Eigen::MatrixXd& features) const {
  if (features.cols() != dims()) throw InvalidInput("Gaussian model: features have the wrong number of columns");
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> out(features.rows(), num_labels_);
  std::vector<double> x(static_cast<size_t>(dims()));
  for (Eigen::Index t = 0; t < features.rows(); ++t) {
    for (int i = 0; i < dims(); ++i) x[i] = features(t, i);
    Closeness(x.data(), out.row(t).data());
  }
  return out;
}

Eigen::MatrixXd GaussianClassifier::Posteriors(const Eigen::MatrixXd& features) const {
  if (features.cols() != dims()) throw InvalidInput("Gaussian model: features have the wrong number of columns");
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> out(features.rows(), num_labels_);
  std::vector<double> x(static_cast<size_t>(dims()));
  for (Eigen::Index t = 0; t < features.rows(); ++t) {
    for (int i = 0; i < dims(); ++i) x[i] = features(t, i);
    Posterior(x.data(), out.row(t).data());
  }
  return out;
}

std::string KeyCode(int placement, int shape) { return ::csw::KeyCode{placement, shape}.Text(); }

KeyLabels LabelsFromTargets(const KeyTargets& targets, double rate_hz, int64_t frames, const std::string& where) {
  if (!(rate_hz > 0)) throw InvalidInput(where + ": frame rate must be > 0");
  auto frame_of = [&](double t) {
    return std::clamp<int64_t>(static_cast<int64_t>(std::llround(t * rate_hz)), 0, std::max<int64_t>(frames - 1, 0));
  };
  KeyLabels labels;
  for (const ComponentTarget& t : targets.shape) {
    labels.shape_frames.push_back(frame_of(t.time_s));
    labels.shapes.push_back(t.value);
  }
  for (const ComponentTarget& t : targets.placement) {
    labels.placement_frames.push_back(frame_of(t.time_s));
    labels.placements.push_back(t.value);
    labels.placement_shapes.push_back(t.code.shape);
  }
  return labels;
}

std::string KeyModelOptions::Check() const {
  std::string r = shape.Check();
  if (!r.empty()) return "shape model: " + r;
  r = placement.Check();
  if (!r.empty()) return "placement model: " + r;
  for (int s : index_shapes)
    if (s < 0 || s >= kNumShapes) return "index_shapes: shape " + std::to_string(s) + " out of 0-8";
  if (target_window_frames < 0) return "target_window_frames must be >= 0";
  return "";
}

bool KeyModel::IndexFinger(int shape) const {
  return std::find(index_shapes.begin(), index_shapes.end(), shape) != index_shapes.end();
}

void KeyTrainingSet::Add(const HandFeatures& features, const KeyLabels& labels, const KeyModelOptions& options) {
  const int64_t n = features.frames();
  const int w = options.target_window_frames;
  auto append = [](Eigen::MatrixXd* m, const Eigen::RowVectorXd& row) {
    m->conservativeResize(m->rows() + 1, row.size());
    m->row(m->rows() - 1) = row;
  };
  for (size_t i = 0; i < labels.shape_frames.size(); ++i) {
    for (int64_t t = labels.shape_frames[i] - w; t <= labels.shape_frames[i] + w; ++t) {
      if (t < 0 || t >= n) continue;
      append(&shape_samples, features.distances.row(t));
      shape_labels.push_back(labels.shapes[i]);
    }
  }
  for (size_t i = 0; i < labels.placement_frames.size(); ++i) {
    const bool use_index = std::find(options.index_shapes.begin(), options.index_shapes.end(),
                                     labels.placement_shapes[i]) != options.index_shapes.end();
    for (int64_t t = labels.placement_frames[i] - w; t <= labels.placement_frames[i] + w; ++t) {
      if (t < 0 || t >= n) continue;
      append(&placement_samples, use_index ? features.index_tip.row(t) : features.middle_tip.row(t));
      placement_labels.push_back(labels.placements[i]);
    }
  }
}

KeyModel TrainKeyModel(const KeyTrainingSet& set, const HandLayout& layout, const Eigen::Matrix3Xd& head_reference,
                       const KeyModelOptions& options) {
  const std::string reason = options.Check();
  if (!reason.empty()) throw InvalidInput("key model: " + reason);
  std::vector<std::string> shape_names, placement_names;
  for (int s = 0; s < kNumShapes; ++s) shape_names.push_back("shape " + std::to_string(s));
  for (int p = 0; p < kNumPlacements; ++p) placement_names.push_back("placement " + std::to_string(p));
  KeyModel m;
  Eigen::MatrixXd shape_x = set.shape_samples;
  if (shape_x.rows() == 0) shape_x.resize(0, kNumDistances);
  Eigen::MatrixXd place_x = set.placement_samples;
  if (place_x.rows() == 0) place_x.resize(0, 3);
  m.shape = GaussianClassifier::Fit(shape_x, set.shape_labels, kNumShapes, shape_names, DistanceNames(), options.shape);
  m.placement = GaussianClassifier::Fit(place_x, set.placement_labels, kNumPlacements, placement_names,
                                        {"tip_x", "tip_y", "tip_z"}, options.placement);
  m.index_shapes = options.index_shapes;
  m.layout = layout;
  m.head_reference = head_reference;
  return m;
}

KeyPosteriors ScoreFrames(const KeyModel& model, const HandFeatures& features) {
  KeyPosteriors out;
  out.shape = model.shape.Posteriors(features.distances);
  const int64_t n = features.frames();
  out.placement_features.resize(n, 3);
  for (int64_t t = 0; t < n; ++t) {
    Eigen::Index best = 0;
    out.shape.row(t).maxCoeff(&best);
    out.placement_features.row(t) =
        model.IndexFinger(static_cast<int>(best)) ? features.index_tip.row(t) : features.middle_tip.row(t);
  }
  out.placement = model.placement.Posteriors(out.placement_features);
  out.shape_closeness = model.shape.Closeness(features.distances);
  out.placement_closeness = model.placement.Closeness(out.placement_features);
  return out;
}

}  // namespace csw::keys
