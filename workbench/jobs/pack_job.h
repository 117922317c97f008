#pragma once
// csw pack: one self-contained corpus file to send to a colleague; csw upgrade:
// a version-1 or packed corpus rewritten as index + folder (docs/corpus-format.md).
#include <nlohmann/json.hpp>
#include <string>

#include "core/progress.h"

namespace csw::jobs {

struct PackOptions {
  std::string corpus;
  std::string output;         // must not exist
  std::string Check() const;  // "" when valid, else the reason
};

// {"corpus", "output", "takes", "bytes"}. Throws csw::Error (IoError when the
// output exists), Cancelled (nothing left behind).
nlohmann::json Pack(const PackOptions& options, Progress& progress);
std::string PackText(const nlohmann::json& result);

// {"corpus", "upgraded" (false: already version 2 with a folder), "takes",
// "format_version"}.
nlohmann::json Upgrade(const std::string& corpus, Progress& progress);
std::string UpgradeText(const nlohmann::json& result);

}  // namespace csw::jobs
