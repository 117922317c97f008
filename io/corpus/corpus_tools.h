#pragma once
// Whole-corpus tools: packing a version-2 corpus (index + folder) into one
// self-contained file to send, and upgrading a version-1 or packed file to
// the version-2 layout (docs/corpus-format.md).
#include <string>

namespace csw {

class Progress;

// Writes one self-contained HDF5 file at out_path holding every take of the
// corpus at path with all external links expanded (format_version 2, root
// attribute layout = "packed"). csw opens it read-only like any corpus; a
// CorpusTransaction on it splits it into index + folder again. The pack is
// written to a hidden sibling and renamed into place (crash-safe). Throws
// IoError when out_path exists (it is never replaced) or names the corpus
// itself, Cancelled on progress.Cancel() (nothing is left behind).
void PackCorpus(const std::string& path, const std::string& out_path, Progress& progress);

// Rewrites a version-1 (single file) or packed corpus as an index file plus
// its folder of per-take files, in one crash-safe transaction: the take files
// are made durable before the index atomically replaces the old file. Returns
// false, changing nothing, when the corpus already is in the version-2 layout.
bool UpgradeCorpus(const std::string& path, Progress& progress);

}  // namespace csw
