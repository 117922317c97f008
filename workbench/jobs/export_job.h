#pragma once
// csw export: one take of a corpus as C3D, TRC, CSV or (a skeleton capture) BVH.
#include <string>

#include "core/progress.h"

namespace csw::jobs {

struct ExportOptions {
  std::string corpus;
  std::string take;
  std::string format;  // "c3d", "trc", "csv", "bvh"
  std::string output;
  // BVH only: the length unit written ("mm", "cm", "dm", "m", "in"); "" = the
  // unit the take was imported in (Take::source_units), else mm.
  std::string units;
  std::string Check() const;  // "" when valid, else the reason
};

// Writes into a hidden temporary folder next to the output and renames: a failed
// or cancelled export never leaves half a file. Throws UsageError for bad options,
// InvalidInput for a BVH export of a take without a skeleton.
void Export(const ExportOptions& options, Progress& progress);

}  // namespace csw::jobs
