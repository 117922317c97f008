#pragma once
// `csw clean`: the cleaning a capture needs before any model is fitted
// (docs/cleaning.md). Per selected take, in this order:
//   1. label swaps between neighbouring markers: detected; exchanged back with --fix-swaps;
//   2. spikes (isolated outlier samples): detected; removed (made gaps) with --fix-spikes;
//   3. the gap report (per marker: gaps, longest, fraction missing) and, for every gap,
//      which of the fill methods can fill it;
//   4. fills (--fill METHODS, tried in the order given, each gap taking the first that
//      can fill it, gaps longer than --max-gap left): spline, rigid, pattern, dct, model;
//   5. an optional low-pass filter (zero-phase Butterworth or Kalman smoother) that
//      never crosses a gap.
// When anything changed (and not --dry-run) the result is written as a new take
// version (`<take>.filled`, `-2`, ... : the take-version rule of `csw invert --fill`)
// in one transaction; the original take is never touched. Its provenance gets one
// summary line, and its point tier "csw-fills" one point per filled gap (at the gap's
// start: marker, frames, method and parameters) so every fill can be traced, also in
// Praat or ELAN after an export.
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "core/progress.h"
#include "models/inversion.h"

namespace csw::jobs {

struct CleanOptions {
  std::string corpus;
  std::vector<std::string> takes;  // take selection (take_selection.h); empty = every take but fill versions
  std::string markerset;           // marker-set JSON; "" = the one the corpus remembers for each take
  std::vector<std::string> fill;   // methods in order: spline, rigid, pattern, dct, model; empty = report only
  double max_gap_s = 0.5;          // gaps longer than this are not filled (0 = no limit)
  // spline
  std::string spline = "smoothing";  // smoothing (GCV), cubic or quintic
  int side_frames = 5;               // valid frames needed each side (spline, dct)
  // pattern
  std::vector<std::string> donors;  // "MARKER=DONOR" pairs; others choose a donor automatically
  // model (the fill of csw invert --fill)
  std::string models;
  InversionOptions inversion;
  // filter
  std::string filter;     // "", "butterworth" or "kalman"
  double cutoff_hz = 15;  // butterworth: where the zero-phase response is -3 dB (docs/cleaning-filter.md)
  int order = 2;          // butterworth: single-pass order (even, 2-8; 2 = Winter's filter passed twice)
  std::string kalman_model = "acceleration";  // kalman: velocity or acceleration (lower error on every take)
  // detection
  bool fix_spikes = false;
  bool fix_swaps = false;
  bool dry_run = false;  // report only, write nothing
  std::string figures;   // folder for each take's gap map and its longest filled gap (PNG)
  // Folder with <take>.clean.c3d (csw simulate --clean): every filled sample is
  // scored against it, by method and gap length (1-5, 6-20, 21-60, > 60 frames).
  std::string truth;
  std::string Check() const;  // "" when valid, else the reason (a usage error)
};

// {"corpus", "takes": [{"take", "frames", "rate_hz", "markers", "gaps": {...},
//  "spikes": {...}, "swaps": {...}, "fills": {...}, "filter": {...}, "cleaned_take"}],
//  "figures": [...]}; docs/cleaning.md describes every field.
nlohmann::json Clean(const CleanOptions& options, Progress& progress);
// The default text output: one block per take.
std::string CleanText(const nlohmann::json& result);

}  // namespace csw::jobs
