#include "workbench/jobs/info_job.h"

#include <cstdio>
#include <sstream>

#include "io/corpus/corpus.h"

namespace csw::jobs {

using nlohmann::json;

json Info(const std::string& corpus_path) {
  Corpus corpus = Corpus::Open(corpus_path);
  json takes = json::array();
  double total_s = 0;
  int64_t total_frames = 0;
  for (const TakeSummary& t : corpus.Takes()) {
    takes.push_back({{"name", t.name},
                     {"rate_hz", t.rate_hz},
                     {"frames", t.frames},
                     {"duration_s", t.duration_s},
                     {"markers", t.markers},
                     {"gaps", t.gaps},
                     {"tiers", t.tier_names},
                     {"audio", t.has_audio},
                     {"analog_channels", t.analog_channels},
                     {"markerset", t.has_markerset}});
    total_s += t.duration_s;
    total_frames += t.frames;
  }
  return {{"corpus", corpus_path},  {"format_version", corpus.format_version()},
          {"takes", takes},         {"take_count", takes.size()},
          {"frames", total_frames}, {"duration_s", total_s}};
}

std::string InfoText(const json& info) {
  std::ostringstream os;
  os << info["corpus"].get<std::string>() << ": " << info["take_count"].get<int64_t>() << " take(s), "
     << info["frames"].get<int64_t>() << " frames, ";
  char buf[64];
  std::snprintf(buf, sizeof(buf), "%.1f s", info["duration_s"].get<double>());
  os << buf << "\n";
  os << "  take                        rate   frames  dur(s) markers  gaps audio tiers\n";
  for (const json& t : info["takes"]) {
    std::string tiers;
    for (const auto& n : t["tiers"]) tiers += (tiers.empty() ? "" : ",") + n.get<std::string>();
    std::snprintf(buf, sizeof(buf), "%7.1f %8lld %7.2f %7lld %5lld %5s ", t["rate_hz"].get<double>(),
                  static_cast<long long>(t["frames"].get<int64_t>()), t["duration_s"].get<double>(),
                  static_cast<long long>(t["markers"].get<int64_t>()), static_cast<long long>(t["gaps"].get<int64_t>()),
                  t["audio"].get<bool>() ? "yes" : "no");
    std::string name = t["name"].get<std::string>();
    if (name.size() < 26) name.resize(26, ' ');
    os << "  " << name << buf << (tiers.empty() ? "-" : tiers) << "\n";
  }
  return os.str();
}

}  // namespace csw::jobs
