#pragma once
// Model files (docs/model-format.md): one HDF5 file holding any of a head
// motion model, a forearm motion model, a face model and a hand model, each in
// its own group with marker names, configuration and provenance, readable with
// h5py or MATLAB without csw.
//
// Saving is crash-safe: the file is written to a temporary sibling, fsynced and
// renamed over the target, so a model file is never left half-written.
// Every HDF5 call holds the process-wide HDF5 lock of io/corpus/hdf5_util.h
// (the Debian HDF5 library is not thread-safe), so these functions may be
// called from several threads, also while a corpus is being read.
#include <optional>
#include <string>

#include "analysis/keys/key_model.h"
#include "models/face_model.h"
#include "models/hand_model.h"
#include "models/rigid_model.h"

namespace csw {

inline constexpr int kModelFormatVersion = 1;

struct ModelFile {
  std::optional<RigidModel> head;      // /head_motion
  std::optional<RigidModel> forearm;   // /forearm_motion
  std::optional<FaceModel> face;       // /face
  std::optional<HandModel> hand;       // /hand
  std::optional<keys::KeyModel> keys;  // /keys (the Gaussian key recogniser)
};

// Throws IoError when the file cannot be read, ParseError naming the file and
// the group/dataset when it is not a csw model file, is of a newer version, or
// is damaged (missing or mis-shaped datasets, non-finite values).
ModelFile LoadModelFile(const std::string& path);
// Writes every model present (replacing the file; models absent from `models`
// are not in the new file). Throws InvalidInput, before touching any file,
// when a model is inconsistent (sizes, non-finite values, bad indices: it
// would not load back), naming the object as in the file
// ("/face/shape/loadings"); IoError when the file cannot be written, or when
// `path` exists and is not a csw model file (a corpus given by mistake is never
// replaced). On any failure an existing file at `path` is left unchanged.
void SaveModelFile(const std::string& path, const ModelFile& models);
// Loads `path` if it exists (else starts empty), replaces the models present
// in `update`, keeps the others, and saves. Errors as LoadModelFile and
// SaveModelFile (a damaged existing file is reported, not replaced).
void UpdateModelFile(const std::string& path, const ModelFile& update);

// The temporary sibling SaveModelFile writes before renaming it over `path`:
// ".<name>.csw-tmp.<pid>" in the same directory (exposed for tests).
std::string ModelFileTempPath(const std::string& path);

}  // namespace csw
