#include "workbench/jobs/simulate_job.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "core/file_util.h"
#include "datasets/virtual_cuer.h"
#include "datasets/virtual_signer.h"
#include "io/corpus/corpus.h"
#include "synth/phasing.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;

namespace {

fs::path OutputPath(const std::string& output) {
  fs::path out = fs::path(output).lexically_normal();
  if (out.filename().empty()) out = out.parent_path();
  return out;
}

// Moves the tree `from` into `to`: renames entries that `to` lacks (or files it
// has: replaced), recursing into folders present in both.
void MoveInto(const fs::path& from, const fs::path& to) {
  for (const auto& e : fs::directory_iterator(from)) {
    const fs::path dst = to / e.path().filename();
    std::error_code ec;
    if (e.is_directory() && fs::is_directory(dst, ec)) {
      MoveInto(e.path(), dst);
      continue;
    }
    fs::rename(e.path(), dst, ec);
    if (ec) throw IoError(dst.string(), "cannot move the simulated file into place: " + ec.message());
  }
}

}  // namespace

SimulateOptions ToSimulateOptions(const SimulateJobOptions& options) {
  SimulateOptions o;
  if (options.corpus != "demo") ParseCorpusKind(options.corpus, &o.kind);
  o.seed = options.seed;
  o.count = options.count;
  o.noise_mm = options.noise_mm;
  o.occlusions = options.occlusions;
  o.dropouts_per_s = options.dropouts_per_s;
  o.label_swaps = options.label_swaps;
  o.rate_hz = options.rate_hz;
  o.write_clean = options.clean;
  o.sentences = options.texts;
  o.layout = options.layout;
  o.hand_scale = options.hand_scale;
  o.speech_rate_wpm = options.speech_rate_wpm;
  return o;
}

SignerOptions ToSignerOptions(const SimulateJobOptions& options) {
  SignerOptions o;
  o.seed = options.seed;
  o.rate_hz = options.rate_hz;
  o.noise_mm = options.noise_mm;
  ParseDurationLaw(options.law, &o.law);
  o.hand_offset_max_s = options.hand_offset_s;
  o.duration_noise_sd_s = options.duration_noise_s;
  o.naming = options.naming;
  return o;
}

std::string SimulateJobOptions::Check() const {
  if (output.empty()) return "simulate: no output folder (-o)";
  if (corpus == "signs") {
    DurationLaw law;
    if (!ParseDurationLaw(this->law, &law)) return "simulate: --law must be surface or simple, not '" + this->law + "'";
    if (count < 0) return "simulate: --count must be >= 0";
    if (!(manual_jitter_s >= 0.0 && manual_jitter_s <= 1.0)) return "simulate: --manual-jitter must be in [0, 1] s";
    if (!texts.empty() || !sentences_file.empty() || !phasing_file.empty())
      return "simulate: --text, --sentences and --phasing apply to the virtual cuer, not signs";
    if (hand_scale != 1.0) return "simulate: --hand-scale applies to the virtual cuer, not signs";
    if (speech_rate_wpm != 80) return "simulate: --speech-rate applies to the virtual cuer, not signs";
    std::error_code ec;
    const fs::path out = OutputPath(output);
    if (fs::exists(out, ec) && !fs::is_directory(out, ec)) return "simulate: -o " + output + " is a file, not a folder";
    if (std::string why = ToSignerOptions(*this).Check(); !why.empty()) return "simulate: " + why;
    return "";
  }
  CorpusKind kind;
  if (corpus != "demo" && !ParseCorpusKind(corpus, &kind))
    return "simulate: unknown corpus \"" + corpus + "\" (shapes, visemes, sentences, signs or demo)";
  if (count < 0) return "simulate: --count must be >= 0";
  if (!texts.empty() && !sentences_file.empty()) return "simulate: give --text or --sentences, not both";
  if (corpus == "shapes" || corpus == "visemes") {
    if (!texts.empty()) return "simulate: --text applies to the sentences and demo corpora, not " + corpus;
    if (!sentences_file.empty())
      return "simulate: --sentences applies to the sentences and demo corpora, not " + corpus;
    if (speech_rate_wpm != 80)
      return "simulate: --speech-rate applies to the sentences and demo corpora (cued speech), not " + corpus;
  }
  std::error_code ec;
  if (!sentences_file.empty() && !fs::is_regular_file(sentences_file, ec))
    return "simulate: --sentences " + sentences_file + ": no such file";
  if (!phasing_file.empty() && !fs::is_regular_file(phasing_file, ec))
    return "simulate: --phasing " + phasing_file + ": no such file";
  if (!phasing_file.empty() && (corpus == "shapes" || corpus == "visemes"))
    return "simulate: --phasing applies to the sentences and demo corpora, not " + corpus;
  const fs::path out = OutputPath(output);
  if (fs::exists(out, ec) && !fs::is_directory(out, ec)) return "simulate: -o " + output + " is a file, not a folder";
  // Ranges of the capture options (--rate, --noise, --dropouts), in the option's words.
  if (!(rate_hz >= 10.0 && rate_hz <= 2000.0)) return "simulate: --rate must be in [10, 2000] Hz";
  if (!(noise_mm >= 0.0 && noise_mm <= 50.0)) return "simulate: --noise must be in [0, 50] mm";
  if (!(dropouts_per_s >= 0.0 && dropouts_per_s <= 10.0)) return "simulate: --dropouts must be in [0, 10] per s";
  if (!(hand_scale >= 0.5 && hand_scale <= 2.0)) return "simulate: --hand-scale must be in [0.5, 2]";
  if (speech_rate_wpm < 80 || speech_rate_wpm > 450)
    return "simulate: --speech-rate must be in [80, 450] words per minute";
  if (std::string why = ToSimulateOptions(*this).Check(); !why.empty()) return "simulate: " + why;
  return "";
}

namespace {

// The virtual signer's corpus and truth files into `dir`.
std::vector<std::string> SimulateSigns(const SimulateJobOptions& options, const fs::path& dir, Progress& progress) {
  const SignerOptions so = ToSignerOptions(options);
  const VirtualSigner signer(so);
  fs::create_directories(dir);
  const int count = options.count > 0 ? options.count : 20;
  std::vector<std::string> names;
  CorpusTransaction tx((dir / "signs.h5").string());
  for (int i = 0; i < count; ++i) {
    progress.Update("virtual signer", static_cast<double>(i) / count);
    progress.CheckCancel();
    const SignerTake t = signer.SimulateTake(i);
    Take take = t.take;
    if (options.manual_jitter_s > 0)
      take.tiers.push_back(
          JitterBoundaries(take.tiers[0], "manual", options.manual_jitter_s, so.rate_hz, so.seed * 1000 + i));
    tx.WriteTake(take);
    std::ofstream out(dir / (take.name + ".truth.json"));
    out << SignerTruthToJson(t, so);
    if (!out) throw IoError((dir / (take.name + ".truth.json")).string(), "cannot write the ground truth");
    names.push_back(take.name);
  }
  tx.Commit();
  return names;
}

}  // namespace

std::vector<std::string> Simulate(const SimulateJobOptions& options, Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw UsageError(why);
  if (options.corpus == "signs") {
    const fs::path out = OutputPath(options.output);
    const fs::path partial = HiddenSibling(out.string(), ".csw-partial");
    std::error_code ec;
    fs::remove_all(partial, ec);
    std::vector<std::string> names;
    try {
      names = SimulateSigns(options, partial, progress);
      if (!fs::exists(out, ec)) {
        if (!out.parent_path().empty()) fs::create_directories(out.parent_path(), ec);
        fs::rename(partial, out, ec);
        if (ec) throw IoError(out.string(), "cannot move the simulated corpus into place: " + ec.message());
      } else {
        MoveInto(partial, out);
        fs::remove_all(partial, ec);
      }
    } catch (...) {
      fs::remove_all(partial, ec);
      throw;
    }
    return names;
  }
  SimulateOptions o = ToSimulateOptions(options);
  if (!options.sentences_file.empty()) o.sentences = ReadSentences(options.sentences_file);
  if (!options.phasing_file.empty()) o.phasing = LoadPhasingModel(options.phasing_file);

  const fs::path out = OutputPath(options.output);
  const fs::path partial = HiddenSibling(out.string(), ".csw-partial");
  std::error_code ec;
  fs::remove_all(partial, ec);  // left by a killed run
  std::vector<std::string> names;
  try {
    if (options.corpus == "demo") {
      GenerateDemoCorpus(partial.string(), o, options.count > 0 ? options.count : 20, progress);
      for (const char* sub : {"shapes", "visemes", "sentences"}) {
        for (const auto& e : fs::directory_iterator(partial / sub))
          if (e.path().extension() == ".c3d" && e.path().stem().extension().empty())
            names.push_back(std::string(sub) + "/" + e.path().stem().string());
      }
      std::sort(names.begin(), names.end());
    } else {
      names = SimulateCorpus(o, partial.string(), progress);
    }
    progress.CheckCancel();
    if (!fs::exists(out, ec)) {
      if (!out.parent_path().empty()) fs::create_directories(out.parent_path(), ec);
      fs::rename(partial, out, ec);
      if (ec) throw IoError(out.string(), "cannot move the simulated corpus into place: " + ec.message());
    } else {
      MoveInto(partial, out);
      fs::remove_all(partial, ec);
    }
  } catch (...) {
    fs::remove_all(partial, ec);
    throw;
  }
  return names;
}

}  // namespace csw::jobs
