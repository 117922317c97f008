#pragma once
// Small pieces shared by the jobs: the usage-error type and file-type detection.
#include <string>
#include <vector>

#include "core/error.h"

namespace csw::jobs {

// A request that cannot be run as given (a missing or contradictory option, an
// option file that does not exist): the CLI exits 1 for these, 2 for bad data.
// Derives from InvalidInput so callers that catch csw::Error still see it.
class UsageError : public InvalidInput {
 public:
  using InvalidInput::InvalidInput;
};

// Format of a file from its extension: "c3d", "trc", "bvh", "textgrid", "eaf", "wav",
// "hdf5" (.h5/.hdf5: a corpus or a model file, told apart by its root "format"
// attribute), or "" when unknown.
std::string FormatOf(const std::string& path);
// The path's extension with its dot, in lower case (".json"); "" without one.
std::string LowerExtension(const std::string& path);

// Sentences of a text file (csw simulate --sentences, csw say --text-file):
// one per line; a trailing CR, blank lines and lines starting with '#' are
// skipped. Throws IoError when the file cannot be read, InvalidInput naming
// file:line for a line that is not UTF-8 and naming the file when it holds no
// sentence.
std::vector<std::string> ReadSentences(const std::string& path);

}  // namespace csw::jobs
