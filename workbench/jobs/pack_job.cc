#include "workbench/jobs/pack_job.h"

#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "io/corpus/corpus_tools.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

std::string PackOptions::Check() const {
  if (corpus.empty()) return "pack: no corpus given";
  if (output.empty()) return "pack: no output file given (-o)";
  std::error_code ec;
  if (fs::exists(output, ec)) return "pack: " + output + " exists; give a new file name";
  return "";
}

json Pack(const PackOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  PackCorpus(options.corpus, options.output, progress);
  const Corpus packed = Corpus::Open(options.output);
  std::error_code ec;
  const auto bytes = fs::file_size(options.output, ec);
  return {{"corpus", options.corpus},
          {"output", options.output},
          {"takes", packed.Takes().size()},
          {"bytes", ec ? 0 : static_cast<int64_t>(bytes)}};
}

std::string PackText(const json& r) {
  std::ostringstream os;
  os << "packed " << r["takes"].get<int64_t>() << " take(s) of " << r["corpus"].get<std::string>() << " into "
     << r["output"].get<std::string>() << " (" << r["bytes"].get<int64_t>() << " bytes, one self-contained file)\n";
  return os.str();
}

json Upgrade(const std::string& corpus, Progress& progress) {
  if (corpus.empty()) throw UsageError("upgrade: no corpus given");
  const bool upgraded = UpgradeCorpus(corpus, progress);
  const Corpus c = Corpus::Open(corpus);
  return {
      {"corpus", corpus}, {"upgraded", upgraded}, {"takes", c.Takes().size()}, {"format_version", c.format_version()}};
}

std::string UpgradeText(const json& r) {
  std::ostringstream os;
  const std::string corpus = r["corpus"].get<std::string>();
  if (r["upgraded"].get<bool>()) {
    os << corpus << ": upgraded to format version " << r["format_version"].get<int>() << " ("
       << r["takes"].get<int64_t>() << " take(s) now in " << corpus << ".d/)\n";
  } else {
    os << corpus << ": already format version " << r["format_version"].get<int>()
       << " with its folder; nothing to do\n";
  }
  return os.str();
}

}  // namespace csw::jobs
