#pragma once
// Transition duration models of Naert, Larboulette & Gibet (§5.2):
//   SIMPLE          equation 3: α · 2E / (v̄₁ + v̄₂) + (1 − α) · 2G / (ω̄₁ + ω̄₂), with E, G the
//                   Euclidean and geodesic distances between the bounding postures and v̄, ω̄
//                   the mean linear and angular speeds of the two signs; α fitted by least
//                   squares (clamped to [0, 1]) or fixed;
//   SIMPLE_BOUNDED  SIMPLE clamped to [0.1 s, 0.5 s] (configurable);
//   LINEAR          a trend line d = a + b · n on the mean n of the two normalised distances
//                   ((x − mean) / range, normalisation of the training set kept with the model);
//   SURFACE         the plane d = θ₀ + θ₁ G + θ₂ E by the normal equations θ = (XᵀX)⁻¹ Xᵀ y.
// Each is fitted on transitions (transitions.h), predicts, round-trips through JSON
// and is evaluated by the mean absolute error in k-fold cross-validation.
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "analysis/signing/transitions.h"

namespace csw::signing {

enum class DurationModelKind { kSimple, kSimpleBounded, kLinear, kSurface };
const char* DurationModelName(DurationModelKind kind);  // "simple", "simple_bounded", "linear", "surface"
// Parses a name as DurationModelName writes it (case-insensitive; "-" for "_");
// throws InvalidInput listing the names otherwise.
DurationModelKind ParseDurationModel(const std::string& name);
const std::vector<DurationModelKind>& AllDurationModels();

struct DurationModelOptions {
  bool fit_alpha = true;  // SIMPLE: fit α by least squares; otherwise use `alpha`
  double alpha = 0.5;     // SIMPLE's α when not fitted
  double min_s = 0.1;     // SIMPLE_BOUNDED's limits
  double max_s = 0.5;
  std::string Check() const;
};

struct DurationModel {
  DurationModelKind kind = DurationModelKind::kSurface;
  double alpha = 0.5;                   // SIMPLE, SIMPLE_BOUNDED
  double min_s = 0.1, max_s = 0.5;      // SIMPLE_BOUNDED
  double intercept = 0.0, slope = 0.0;  // LINEAR: d = intercept + slope · normalised
  DistanceNormaliser normaliser;        // LINEAR
  double theta[3] = {0.0, 0.0, 0.0};    // SURFACE: θ₀ + θ₁ G + θ₂ E
  int training_transitions = 0;
  double training_mae_s = 0.0;  // mean absolute error on the training set

  // The predicted duration of a transition (s). SIMPLE with a speed of zero or
  // unknown on both sides falls back to the distance term that is defined, and
  // to 0 when none is.
  double Predict(const Transition& t) const;
  nlohmann::json ToJson() const;
  // Throws InvalidInput naming the member when `j` is not a model ToJson wrote.
  static DurationModel FromJson(const nlohmann::json& j);
};

// The seed's SURFACE model: θ = (0.148777, 0.663958, 0.275229), fitted on 89
// LSF transitions with geodesic distances in radians and Euclidean distances
// in the units of the Sign3D skeleton.
DurationModel SeedSurfaceModel();

// Fits one model. Throws InvalidInput when there are too few transitions
// (SURFACE needs 3 with distances that are not collinear, LINEAR 2, SIMPLE 1).
DurationModel FitDurationModel(DurationModelKind kind, const std::vector<Transition>& transitions,
                               const DurationModelOptions& options = {});

double MeanAbsoluteError(const DurationModel& model, const std::vector<Transition>& transitions);

// k-fold cross-validation: the transitions in order, fold i = those with
// index % folds == i (deterministic); each fold predicted by a model fitted on
// the others. Returns the mean absolute error over every transition (s).
// Throws InvalidInput when folds < 2 or there are fewer transitions than folds.
double CrossValidatedError(DurationModelKind kind, const std::vector<Transition>& transitions, int folds,
                           const DurationModelOptions& options = {});

}  // namespace csw::signing
