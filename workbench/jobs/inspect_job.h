#pragma once
// csw inspect: header facts of any supported file.
#include <nlohmann/json.hpp>
#include <string>

#include "core/progress.h"

namespace csw::jobs {

// Header facts of any supported file (C3D, TRC, TextGrid, EAF, WAV, corpus or
// model file) as JSON, with "file", "format" and "bytes" first.
// C3D: processor, storage, points, first_frame, frames, point_rate_hz, point_scale,
//   units, analog_channels, analog_subframes_per_frame, analog_rate_hz,
//   valid_point_samples, sum_xyz_valid (the validity rule of io/c3d:
//   C3dPointSampleValid, the same as `csw import`), labels, analog_labels,
//   events, warnings.
// .h5/.hdf5: told apart by the root attribute "format": "csw-corpus" gives
//   format "corpus" and the facts of Info(); "csw-models" gives format "models"
//   and "models": one object per model present (head_motion, forearm_motion,
//   face, hand) with markers, parameters, training_takes, training_frames,
//   selected_frames, training_rms_mm, created_utc, csw_version. Any other HDF5
//   file is an InvalidInput naming its format attribute (or its absence).
// Throws csw::Error for unreadable files.
nlohmann::json Inspect(const std::string& path, Progress& progress);

// Human-readable rendering of Inspect's JSON: one "key: value" line per field
// (arrays of more than 12 items as "[N items]"); a model file's models as one
// indented block per model.
std::string InspectText(const nlohmann::json& facts);

}  // namespace csw::jobs
