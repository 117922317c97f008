#include "analysis/signing/duration_models.h"

#include <Eigen/Dense>
#include <algorithm>
#include <cctype>
#include <cmath>

#include "core/error.h"

namespace csw::signing {
namespace {

// The two terms of equation 3 (NaN when undefined).
void SimpleTerms(const Transition& t, double* linear, double* angular) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double v = t.from_speed + t.to_speed;
  const double w = t.from_angular_speed + t.to_angular_speed;
  *linear = std::isfinite(v) && v > 0 ? 2.0 * t.euclidean / v : nan;
  *angular = std::isfinite(w) && w > 0 ? 2.0 * t.geodesic / w : nan;
}

double Number(const nlohmann::json& j, const char* key) {
  if (!j.contains(key) || !j[key].is_number()) {
    throw InvalidInput(std::string("duration model: '") + key + "' is missing or not a number");
  }
  const double v = j[key].get<double>();
  if (!std::isfinite(v)) throw InvalidInput(std::string("duration model: '") + key + "' is not finite");
  return v;
}

}  // namespace

const char* DurationModelName(DurationModelKind kind) {
  switch (kind) {
    case DurationModelKind::kSimple:
      return "simple";
    case DurationModelKind::kSimpleBounded:
      return "simple_bounded";
    case DurationModelKind::kLinear:
      return "linear";
    case DurationModelKind::kSurface:
      return "surface";
  }
  return "?";
}

const std::vector<DurationModelKind>& AllDurationModels() {
  static const std::vector<DurationModelKind> all = {DurationModelKind::kSimple, DurationModelKind::kSimpleBounded,
                                                     DurationModelKind::kLinear, DurationModelKind::kSurface};
  return all;
}

DurationModelKind ParseDurationModel(const std::string& name) {
  std::string n;
  for (char c : name) n += c == '-' ? '_' : static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (n.size() > 9 && n.substr(n.size() - 9) == "_duration") n = n.substr(0, n.size() - 9);
  for (DurationModelKind k : AllDurationModels()) {
    if (n == DurationModelName(k)) return k;
  }
  throw InvalidInput("unknown duration model '" + name + "' (simple, simple_bounded, linear, surface)");
}

std::string DurationModelOptions::Check() const {
  if (!fit_alpha && !(alpha >= 0 && alpha <= 1)) return "alpha must be in [0, 1]";
  if (!(min_s >= 0) || !(max_s > min_s)) return "the bounds must satisfy 0 <= min < max";
  return "";
}

double DurationModel::Predict(const Transition& t) const {
  switch (kind) {
    case DurationModelKind::kSimple:
    case DurationModelKind::kSimpleBounded: {
      double a = 0, b = 0;
      SimpleTerms(t, &a, &b);
      double d = 0;
      if (std::isfinite(a) && std::isfinite(b)) {
        d = alpha * a + (1 - alpha) * b;
      } else if (std::isfinite(a)) {
        d = a;
      } else if (std::isfinite(b)) {
        d = b;
      }
      return kind == DurationModelKind::kSimpleBounded ? std::clamp(d, min_s, max_s) : d;
    }
    case DurationModelKind::kLinear:
      return intercept + slope * normaliser(t.geodesic, t.euclidean);
    case DurationModelKind::kSurface:
      return theta[0] + theta[1] * t.geodesic + theta[2] * t.euclidean;
  }
  return 0;
}

nlohmann::json DurationModel::ToJson() const {
  nlohmann::json j;
  j["model"] = DurationModelName(kind);
  j["training_transitions"] = training_transitions;
  j["training_mae_s"] = training_mae_s;
  switch (kind) {
    case DurationModelKind::kSimpleBounded:
      j["min_s"] = min_s;
      j["max_s"] = max_s;
      [[fallthrough]];
    case DurationModelKind::kSimple:
      j["alpha"] = alpha;
      break;
    case DurationModelKind::kLinear:
      j["intercept_s"] = intercept;
      j["slope_s"] = slope;
      j["normaliser"] = {{"geodesic_mean", normaliser.geodesic_mean},
                         {"geodesic_range", normaliser.geodesic_range},
                         {"euclidean_mean", normaliser.euclidean_mean},
                         {"euclidean_range", normaliser.euclidean_range}};
      break;
    case DurationModelKind::kSurface:
      j["theta"] = {theta[0], theta[1], theta[2]};
      break;
  }
  return j;
}

DurationModel DurationModel::FromJson(const nlohmann::json& j) {
  if (!j.is_object() || !j.contains("model") || !j["model"].is_string()) {
    throw InvalidInput("duration model: not an object with a 'model' name");
  }
  DurationModel m;
  m.kind = ParseDurationModel(j["model"].get<std::string>());
  if (j.contains("training_transitions") && j["training_transitions"].is_number_integer()) {
    m.training_transitions = j["training_transitions"].get<int>();
  }
  if (j.contains("training_mae_s") && j["training_mae_s"].is_number())
    m.training_mae_s = j["training_mae_s"].get<double>();
  switch (m.kind) {
    case DurationModelKind::kSimpleBounded:
      m.min_s = Number(j, "min_s");
      m.max_s = Number(j, "max_s");
      if (!(m.min_s >= 0 && m.max_s > m.min_s)) throw InvalidInput("duration model: needs 0 <= min_s < max_s");
      [[fallthrough]];
    case DurationModelKind::kSimple:
      m.alpha = Number(j, "alpha");
      if (!(m.alpha >= 0 && m.alpha <= 1)) throw InvalidInput("duration model: 'alpha' outside [0, 1]");
      break;
    case DurationModelKind::kLinear: {
      m.intercept = Number(j, "intercept_s");
      m.slope = Number(j, "slope_s");
      if (!j.contains("normaliser") || !j["normaliser"].is_object()) {
        throw InvalidInput("duration model: 'normaliser' is missing");
      }
      const nlohmann::json& n = j["normaliser"];
      m.normaliser.geodesic_mean = Number(n, "geodesic_mean");
      m.normaliser.geodesic_range = Number(n, "geodesic_range");
      m.normaliser.euclidean_mean = Number(n, "euclidean_mean");
      m.normaliser.euclidean_range = Number(n, "euclidean_range");
      if (!(m.normaliser.geodesic_range > 0 && m.normaliser.euclidean_range > 0)) {
        throw InvalidInput("duration model: normaliser ranges must be > 0");
      }
      break;
    }
    case DurationModelKind::kSurface: {
      if (!j.contains("theta") || !j["theta"].is_array() || j["theta"].size() != 3) {
        throw InvalidInput("duration model: 'theta' must be an array of 3 numbers");
      }
      for (int i = 0; i < 3; ++i) {
        if (!j["theta"][static_cast<size_t>(i)].is_number())
          throw InvalidInput("duration model: 'theta' must be numbers");
        m.theta[i] = j["theta"][static_cast<size_t>(i)].get<double>();
        if (!std::isfinite(m.theta[i])) throw InvalidInput("duration model: 'theta' is not finite");
      }
      break;
    }
  }
  return m;
}

DurationModel SeedSurfaceModel() {
  DurationModel m;
  m.kind = DurationModelKind::kSurface;
  m.theta[0] = 0.148777;
  m.theta[1] = 0.663958;
  m.theta[2] = 0.275229;
  m.training_transitions = 89;
  m.training_mae_s = 0.06075;
  return m;
}

DurationModel FitDurationModel(DurationModelKind kind, const std::vector<Transition>& transitions,
                               const DurationModelOptions& options) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput("duration model: " + why);
  const std::string name = DurationModelName(kind);
  DurationModel m;
  m.kind = kind;
  m.min_s = options.min_s;
  m.max_s = options.max_s;
  m.training_transitions = static_cast<int>(transitions.size());
  switch (kind) {
    case DurationModelKind::kSimple:
    case DurationModelKind::kSimpleBounded: {
      if (transitions.empty()) throw InvalidInput(name + ": no transitions to fit");
      m.alpha = options.alpha;
      if (options.fit_alpha) {
        // d − B = α (A − B): one unknown, least squares over the transitions
        // where both terms are defined.
        double num = 0, den = 0;
        for (const Transition& t : transitions) {
          double a = 0, b = 0;
          SimpleTerms(t, &a, &b);
          if (!std::isfinite(a) || !std::isfinite(b)) continue;
          num += (t.duration_s - b) * (a - b);
          den += (a - b) * (a - b);
        }
        m.alpha = den > 0 ? std::clamp(num / den, 0.0, 1.0) : options.alpha;
      }
      break;
    }
    case DurationModelKind::kLinear: {
      if (transitions.size() < 2) throw InvalidInput(name + ": needs at least 2 transitions");
      m.normaliser = FitNormaliser(transitions);
      double sx = 0, sy = 0, sxx = 0, sxy = 0;
      const auto n = static_cast<double>(transitions.size());
      for (const Transition& t : transitions) {
        const double x = m.normaliser(t.geodesic, t.euclidean);
        sx += x;
        sy += t.duration_s;
        sxx += x * x;
        sxy += x * t.duration_s;
      }
      const double var = sxx - sx * sx / n;
      m.slope = var > 1e-15 ? (sxy - sx * sy / n) / var : 0.0;
      m.intercept = (sy - m.slope * sx) / n;
      break;
    }
    case DurationModelKind::kSurface: {
      if (transitions.size() < 3) throw InvalidInput(name + ": needs at least 3 transitions");
      // The seed's equation 4, θ = (XᵀX)⁻¹ Xᵀ y, with X = [1 G E].
      Eigen::Matrix3d xtx = Eigen::Matrix3d::Zero();
      Eigen::Vector3d xty = Eigen::Vector3d::Zero();
      for (const Transition& t : transitions) {
        const Eigen::Vector3d x(1.0, t.geodesic, t.euclidean);
        xtx += x * x.transpose();
        xty += x * t.duration_s;
      }
      // XᵀX is symmetric: its eigenvalues (ascending) say whether it is invertible.
      const Eigen::Vector3d ev =
          Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(xtx, Eigen::EigenvaluesOnly).eigenvalues();
      if (!(ev(0) > 1e-12 * ev(2))) {
        throw InvalidInput(name + ": the distances of the " + std::to_string(transitions.size()) +
                           " transitions do not span a plane (all on a line), so the surface is not defined");
      }
      const Eigen::Vector3d theta = xtx.ldlt().solve(xty);
      for (int i = 0; i < 3; ++i) m.theta[i] = theta(i);
      break;
    }
  }
  m.training_mae_s = MeanAbsoluteError(m, transitions);
  return m;
}

double MeanAbsoluteError(const DurationModel& model, const std::vector<Transition>& transitions) {
  if (transitions.empty()) return 0.0;
  double sum = 0;
  for (const Transition& t : transitions) sum += std::abs(model.Predict(t) - t.duration_s);
  return sum / static_cast<double>(transitions.size());
}

double CrossValidatedError(DurationModelKind kind, const std::vector<Transition>& transitions, int folds,
                           const DurationModelOptions& options) {
  if (folds < 2) throw InvalidInput("cross-validation needs at least 2 folds");
  if (static_cast<int>(transitions.size()) < folds) {
    throw InvalidInput("cross-validation: " + std::to_string(transitions.size()) + " transitions for " +
                       std::to_string(folds) + " folds");
  }
  double sum = 0;
  for (int f = 0; f < folds; ++f) {
    std::vector<Transition> train, test;
    for (size_t i = 0; i < transitions.size(); ++i) {
      (static_cast<int>(i % static_cast<size_t>(folds)) == f ? test : train).push_back(transitions[i]);
    }
    const DurationModel m = FitDurationModel(kind, train, options);
    for (const Transition& t : test) sum += std::abs(m.Predict(t) - t.duration_s);
  }
  return sum / static_cast<double>(transitions.size());
}

}  // namespace csw::signing
