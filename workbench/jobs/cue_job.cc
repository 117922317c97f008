#include "workbench/jobs/cue_job.h"

#include <algorithm>
#include <filesystem>
#include <sstream>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "io/formats/textgrid.h"
#include "synth/phone_symbols.h"
#include "workbench/jobs/job_util.h"
#include "workbench/jobs/take_data.h"
#include "workbench/jobs/take_selection.h"
#include "workbench/jobs/tier_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

std::string CueOptions::Check() const {
  if (input.empty()) return "no input given: a corpus (.h5) or a TextGrid";
  const std::string format = FormatOf(input);
  if (format != "hdf5" && format != "textgrid")
    return "csw cue reads a corpus (.h5) or a TextGrid (.TextGrid), not '" + input + "'";
  if (format == "textgrid") {
    if (output.empty()) return "csw cue FILE.TextGrid needs -o OUT.TextGrid";
    if (FormatOf(output) != "textgrid") return "-o must name a .TextGrid file, not '" + output + "'";
    if (!takes.empty()) return "--takes selects takes of a corpus; a TextGrid is one take";
  } else if (!output.empty()) {
    return "-o is for a TextGrid input; on a corpus csw cue writes the '" + tier + "' tier into each take";
  }
  PhoneSymbols s;
  if (!ParsePhoneSymbols(symbols, &s))
    return "--symbols must be auto, ipa, mfa, xsampa or sppas, not '" + symbols + "'";
  if (phones.empty()) return "--phones must name the phone tier";
  if (tier.empty()) return "--tier must name the tier to write";
  if (tier == phones) return "--tier must differ from --phones (the phone tier is kept)";
  return "";
}

namespace {

// Cues one take's tiers: the result JSON, and `tiers` with the expected keys
// tier replaced or added. `end_s` extends the phone tier's domain (a take's
// duration) when longer.
json CueTiers(const std::string& name, std::vector<LabelTier>* tiers, double end_s, const CueOptions& options,
              const std::string& where) {
  const LabelTier* it = FindTier(*tiers, options.phones);
  if (it == nullptr)
    throw InvalidInput(where + ": no phone tier '" + options.phones + "' (tiers: " + TierNames(*tiers) +
                       "); name it with --phones");
  LabelTier phones = *it;
  if (end_s > phones.end_s) phones.end_s = end_s;
  PhoneSymbols symbols = PhoneSymbols::kAuto;
  ParsePhoneSymbols(options.symbols, &symbols);  // checked by Check()
  const CuedTier cued = CuePhoneTier(phones, symbols, where + ": tier '" + options.phones + "'", options.tier);

  int64_t n_phones = 0, n_pauses = 0;
  for (const Phone& p : cued.mapped.phones) (p.ipa.empty() ? n_pauses : n_phones) += 1;
  json counts = {{"CV", 0}, {"V", 0}, {"C", 0}, {"rest", 0}};
  std::string sequence;
  int64_t keys = 0;
  for (const Key& k : cued.keys) {
    switch (k.type) {
      case KeyType::kCV:
        counts["CV"] = counts["CV"].get<int64_t>() + 1;
        break;
      case KeyType::kVowelAlone:
        counts["V"] = counts["V"].get<int64_t>() + 1;
        break;
      case KeyType::kConsonantAlone:
        counts["C"] = counts["C"].get<int64_t>() + 1;
        break;
      case KeyType::kRest:
        counts["rest"] = counts["rest"].get<int64_t>() + 1;
        break;
    }
    if (k.type != KeyType::kRest) ++keys;
    sequence += (sequence.empty() ? "" : " ") + k.Code();
  }

  LabelTier out = FillIntervalGaps(cued.tier);
  LabelTier* old = FindTier(*tiers, options.tier);
  if (old != nullptr) {
    *old = std::move(out);
  } else {
    tiers->push_back(std::move(out));
  }
  return {{"take", name},
          {"phones_tier", options.phones},
          {"symbols", PhoneSymbolsName(cued.mapped.symbols)},
          {"phones", n_phones},
          {"pauses", n_pauses},
          {"keys", keys},
          {"counts", counts},
          {"sequence", sequence},
          {"warnings", cued.mapped.warnings}};
}

}  // namespace

json Cue(const CueOptions& options, Progress& progress) {
  if (const std::string why = options.Check(); !why.empty()) throw UsageError(why);
  const bool corpus_input = FormatOf(options.input) == "hdf5";
  json result = {{"input", options.input},
                 {"kind", corpus_input ? "corpus" : "textgrid"},
                 {"output", corpus_input ? options.input : options.output},
                 {"tier", options.tier},
                 {"symbols", options.symbols},
                 {"dry_run", options.dry_run},
                 {"takes", json::array()}};

  if (corpus_input) {
    const Corpus corpus = Corpus::Open(options.input);
    const std::vector<TakeRange> ranges = SelectCorpusTakes(corpus, options.takes);
    std::vector<std::pair<std::string, std::vector<LabelTier>>> written;
    for (size_t i = 0; i < ranges.size(); ++i) {
      const TakeRange& r = ranges[i];
      progress.Update("cue " + r.take, static_cast<double>(i) / static_cast<double>(ranges.size()));
      const TakeSummary summary = corpus.Summary(r.take);
      if (r.first != 0 || r.count != summary.frames)
        throw UsageError("csw cue works on whole takes: '" + r.spec + "' selects frames of take '" + r.take + "'");
      Take take = corpus.LoadTake(r.take);
      const std::string where = corpus.path() + ": take '" + r.take + "'";
      result["takes"].push_back(CueTiers(r.take, &take.tiers, take.duration_s(), options, where));
      written.emplace_back(r.take, std::move(take.tiers));
    }
    if (!options.dry_run) {
      progress.Update("writing tiers", 0.0);
      CorpusTransaction tx(options.input, progress);
      for (const auto& [name, tiers] : written) tx.WriteTiers(name, tiers);
      tx.Commit();
    }
  } else {
    double xmin = 0, xmax = 0;
    std::vector<LabelTier> tiers = ReadTextGrid(options.input, &xmin, &xmax);
    progress.Update("cue " + options.input, 0.0);
    result["takes"].push_back(CueTiers(fs::path(options.input).stem().string(), &tiers, xmax, options, options.input));
    if (!options.dry_run) WriteTextGrid(options.output, tiers, xmin, xmax);
  }
  int64_t keys = 0, warnings = 0;
  for (const json& t : result["takes"]) {
    keys += t["keys"].get<int64_t>();
    warnings += static_cast<int64_t>(t["warnings"].size());
  }
  result["keys"] = keys;
  result["warnings"] = warnings;
  return result;
}

std::string CueText(const json& r) {
  std::ostringstream o;
  for (const json& t : r["takes"]) {
    const json& c = t["counts"];
    o << "take " << t["take"].get<std::string>() << ": " << t["keys"].get<int64_t>() << " keys (CV "
      << c["CV"].get<int64_t>() << ", V " << c["V"].get<int64_t>() << ", C " << c["C"].get<int64_t>() << ") from "
      << t["phones"].get<int64_t>() << " phones of tier '" << t["phones_tier"].get<std::string>() << "' ("
      << t["symbols"].get<std::string>() << " symbols): " << t["sequence"].get<std::string>() << "\n";
    for (const json& w : t["warnings"]) o << "  warning: " << w.get<std::string>() << "\n";
  }
  const size_t n = r["takes"].size();
  if (r["dry_run"].get<bool>()) {
    o << "dry run: nothing written\n";
  } else if (r["kind"] == "corpus") {
    o << "wrote tier '" << r["tier"].get<std::string>() << "' into " << n << (n == 1 ? " take" : " takes") << " of "
      << r["output"].get<std::string>() << "\n";
  } else {
    o << "wrote " << r["output"].get<std::string>() << " with tier '" << r["tier"].get<std::string>() << "'\n";
  }
  return o.str();
}

}  // namespace csw::jobs
