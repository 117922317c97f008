#pragma once
// `csw invert`: invert face / hand models on takes (per frame: cluster pose
// and shape parameters from the visible markers), score the reconstruction,
// and optionally write each take with its gaps filled as a new take.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"
#include "core/take.h"
#include "models/inversion.h"

namespace csw::jobs {

struct InvertOptions {
  std::string corpus;
  std::string models;
  std::vector<std::string> takes;  // take selection (take_selection.h); empty = every take but fill versions
  std::string only;                // "face", "hand" or "" (every model in the file)
  bool fill = false;               // write each take with gaps filled as a new take "<take>.filled"
  double hide_fraction = 0;        // hide this fraction of visible shape samples and score them
  uint64_t seed = 1;               // for hide_fraction
  std::string truth;               // folder with <take>.clean.c3d: score occluded samples and poses
  std::string figures;             // folder for PNG + SVG figures
  int threads = 0;                 // takes inverted in parallel (0 = hardware threads)
  // Add the model's misfit at the edges of each gap, interpolated across it, to
  // the reconstruction of missing samples (CorrectGapsWithEdgeResiduals).
  bool edge_correction = true;
  // Per-frame errors: one CSV row per (take, frame, model) into this file ("" =
  // none; columns in docs/models.md, "Per-frame errors").
  std::string frames_csv;
  int worst_frames = 20;  // frames listed per model in the JSON's "worst_frames" (by max visible error)
  // Leave out selected takes that lack a marker of some model (each listed in
  // the summary's "skipped_takes" with the reason) instead of failing; an error
  // still when no take is left. For the workbench's error inspector.
  bool skip_unbound = false;
  InversionOptions inversion;
  std::string Check() const;
};

// Per model: per take, per marker and overall (training / held-out) mean, sd,
// 99th and 99.9th percentiles and max absolute errors (mm) of visible samples;
// hidden and occluded samples when asked; pose errors against the truth; the
// worst frames (by max visible error). Writes options.frames_csv when given.
// model_reports.h: InvertText renders it.
nlohmann::json Invert(const InvertOptions& options, Progress& progress);

// One frame of one take under one model, as in `csw invert --frames-csv`.
// Errors are those of the visible shape markers (the samples of the per-take
// "visible" statistics); NaN when none is visible or the frame is not solved.
struct FrameReport {
  std::string take;          // the take's name
  int64_t frame = 0;         // 0-based frame of the take (--takes NAME@frame:end selects it)
  double time_s = 0;         // frame / the take's rate
  std::string model;         // "face" or "hand"
  int cluster_visible = 0;   // visible cluster (head / forearm) markers
  int shape_visible = 0;     // visible shape (face + throat / hand) markers
  double mean_error_mm = 0;  // mean |reconstructed − observed| over the visible shape markers
  double max_error_mm = 0;   // largest of them
  std::string max_marker;    // the marker with the largest error, "" when none
  FrameStatus status = FrameStatus::kTooFewMarkers;
  int iterations = 0;       // solver iterations of the kept solve
  bool cold_start = false;  // the kept solve started cold
  bool cold_retry = false;  // a warm start was retried from a cold start
  // Samples hidden on purpose (--hide) in this frame and their reconstruction
  // errors (the per-take "hidden" statistics); 0 and NaN without --hide.
  int hidden = 0;
  double hidden_mean_mm = 0;
  double hidden_max_mm = 0;
};

// The CSV header and one row (no newline) of FrameReport, RFC 4180 quoting.
std::string FrameCsvHeader();
std::string FrameCsvRow(const FrameReport& row);
nlohmann::json FrameJson(const FrameReport& row);

// Invert, also handing back every per-frame report (the rows of
// --frames-csv, in its order: take by take in selection order, frame by
// frame, model by model) when `frames` is not null. For the workbench's
// reconstruction-error inspector.
nlohmann::json Invert(const InvertOptions& options, Progress& progress, std::vector<FrameReport>* frames);

// The models' reconstruction of one whole take, in the take's column layout:
// every marker that a model of the file (options.only: "face", "hand", "" =
// all) reconstructs, NaN elsewhere and where a frame's solve gives nothing.
// Gaps get the same edge correction as `csw invert --fill`. For `csw clean
// --fill model`. `where` names the take in errors (unbound model markers).
MarkerArray ModelReconstruction(const Take& take, const InvertOptions& options, const std::string& where,
                                Progress& progress);

}  // namespace csw::jobs
