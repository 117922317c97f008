#pragma once
// Dictionary files (docs/dictionary-format.md): one HDF5 file holding a unit
// dictionary (synth/dictionary.h) with a format version, the fingerprint of
// the models its parameters belong to, its provenance and its coverage,
// readable with h5py or MATLAB without csw.
//
// Saving is crash-safe (a temporary sibling, fsynced and renamed over the
// target). Every HDF5 call holds the process-wide HDF5 lock of
// io/corpus/hdf5_util.h.
#include <string>

#include "synth/dictionary.h"

namespace csw {

inline constexpr int kDictionaryFormatVersion = 1;
inline constexpr const char* kDictionaryFormatName = "csw-dictionary";

// Writes (replacing) `path`. Throws InvalidInput before touching any file when
// a unit is inconsistent (series of different lengths, a hand-parameter count
// other than the dictionary's names), IoError when the file cannot be written
// or `path` exists and is not a dictionary file (a corpus or model file given
// by mistake is never replaced).
void SaveDictionaryFile(const std::string& path, const dict::Dictionary& dictionary);

// Throws IoError when the file cannot be read, ParseError naming the file and
// the object when it is not a csw dictionary file, is of a newer version, or
// is damaged (missing or mis-shaped datasets, offsets out of range).
dict::Dictionary LoadDictionaryFile(const std::string& path);

}  // namespace csw
