#include "workbench/jobs/jobs.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "core/error.h"
#include "core/markerset.h"
#include "core/sha256.h"
#include "core/take.h"
#include "datasets/virtual_cuer.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "io/formats/eaf.h"
#include "io/formats/textgrid.h"
#include "io/formats/trc.h"
#include "io/formats/wav.h"

namespace csw::jobs {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

std::string Lower(std::string s) {
  for (char& c : s) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return s;
}

// Format of a file from its extension (and, for ambiguous cases, its first bytes).
std::string FormatOf(const std::string& path) {
  std::string ext = Lower(fs::path(path).extension().string());
  if (ext == ".c3d") return "c3d";
  if (ext == ".trc") return "trc";
  if (ext == ".textgrid") return "textgrid";
  if (ext == ".eaf") return "eaf";
  if (ext == ".wav") return "wav";
  if (ext == ".h5" || ext == ".hdf5") return "corpus";
  return "";
}

std::string NowUtc() {
  std::time_t t = std::time(nullptr);
  char buf[32];
  std::strftime(buf, sizeof(buf), "%Y-%m-%dT%H:%M:%SZ", std::gmtime(&t));
  return buf;
}

json TierJson(const std::vector<LabelTier>& tiers) {
  json out = json::array();
  for (const auto& t : tiers) {
    out.push_back({{"name", t.name},
                   {"kind", t.kind == LabelTier::Kind::kInterval ? "interval" : "point"},
                   {"start_s", t.start_s},
                   {"end_s", t.end_s},
                   {"labels", t.labels.size()}});
  }
  return out;
}

json EventsJson(const std::vector<Event>& events) {
  json out = json::array();
  for (const auto& e : events) {
    out.push_back({{"label", e.label}, {"context", e.context}, {"time_s", e.time_s}, {"description", e.description}});
  }
  return out;
}

json TakeFacts(const Take& t) {
  return {{"markers", t.marker_names.size()}, {"frames", t.frames()},
          {"first_frame", t.first_frame},     {"rate_hz", t.rate_hz},
          {"units", t.source_units},          {"valid_point_samples", t.markers.CountVisible()},
          {"labels", t.marker_names},         {"warnings", t.provenance.warnings}};
}

}  // namespace

// ---- inspect ---------------------------------------------------------------

json Inspect(const std::string& path, Progress& progress) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw IoError(path, "no such file");
  if (fs::is_directory(path, ec)) throw IoError(path, "is a directory, not a file");
  std::string format = FormatOf(path);
  json j = {{"file", path}, {"format", format}, {"bytes", fs::file_size(path, ec)}};
  if (format == "c3d") {
    progress.CheckCancel();
    C3dReader reader(path);
    const C3dInfo& i = reader.info();
    int64_t valid = 0;
    double sum = 0.0;
    reader.ValidPointStats(&valid, &sum);
    j.update({{"processor", i.processor},
              {"storage", i.storage},
              {"points", i.points},
              {"first_frame", i.first_frame},
              {"frames", i.frames},
              {"point_rate_hz", i.point_rate_hz},
              {"point_scale", i.point_scale},
              {"units", i.units},
              {"analog_channels", i.analog_channels},
              {"analog_subframes_per_frame", i.analog_subframes_per_frame},
              {"analog_rate_hz", i.analog_rate_hz},
              {"valid_point_samples", valid},
              {"sum_xyz_valid", sum},
              {"labels", i.labels},
              {"analog_labels", i.analog_labels},
              {"events", EventsJson(i.events)},
              {"warnings", i.warnings}});
  } else if (format == "trc") {
    j.update(TakeFacts(ReadTrc(path)));
  } else if (format == "textgrid") {
    double xmin = 0, xmax = 0;
    auto tiers = ReadTextGrid(path, &xmin, &xmax);
    j.update({{"xmin", xmin}, {"xmax", xmax}, {"tiers", TierJson(tiers)}});
  } else if (format == "eaf") {
    std::vector<std::string> warnings;
    auto tiers = ReadEaf(path, &warnings);
    j.update({{"tiers", TierJson(tiers)}, {"warnings", warnings}});
  } else if (format == "wav") {
    Audio a = ReadWav(path);
    j.update(
        {{"rate_hz", a.rate_hz}, {"channels", a.channels}, {"frames", a.frames()}, {"duration_s", a.duration_s()}});
  } else if (format == "corpus") {
    j.update(Info(path));
  } else {
    throw InvalidInput(path + ": unknown file type (expected .c3d, .trc, .TextGrid, .eaf, .wav or .h5)");
  }
  return j;
}

std::string InspectText(const json& facts) {
  std::ostringstream os;
  for (auto it = facts.begin(); it != facts.end(); ++it) {
    const json& v = it.value();
    if (v.is_array() && v.size() > 12) {
      os << it.key() << ": [" << v.size() << " items]\n";
    } else if (v.is_array() || v.is_object()) {
      os << it.key() << ": " << v.dump() << "\n";
    } else if (v.is_string()) {
      os << it.key() << ": " << v.get<std::string>() << "\n";
    } else {
      os << it.key() << ": " << v.dump() << "\n";
    }
  }
  return os.str();
}

// ---- import ----------------------------------------------------------------

std::string ImportOptions::Check() const {
  if (files.empty()) return "import: no input files";
  if (corpus.empty()) return "import: no output corpus (-o)";
  if (chunk_frames < 1) return "import: chunk_frames must be positive";
  for (const auto& f : files) {
    if (FormatOf(f).empty() || FormatOf(f) == "corpus")
      return "import: " + f + ": unsupported file type (expected .c3d, .trc, .TextGrid, .eaf or .wav)";
  }
  return "";
}

namespace {

struct TakeFiles {
  std::string capture, capture_format, labels, labels_format, audio;
};

}  // namespace

ImportResult Import(const ImportOptions& options, Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  // Pair files by base name.
  std::map<std::string, TakeFiles> takes;
  std::vector<std::string> order;
  for (const auto& f : options.files) {
    std::string stem = fs::path(f).stem().string();
    std::string fmt = FormatOf(f);
    if (!takes.count(stem)) order.push_back(stem);
    TakeFiles& t = takes[stem];
    auto set = [&](std::string& slot, const std::string& what) {
      if (!slot.empty())
        throw InvalidInput(f + ": a second " + what + " for take \"" + stem + "\" (first: " + slot + ")");
      slot = f;
    };
    if (fmt == "c3d" || fmt == "trc") {
      set(t.capture, "capture");
      t.capture_format = fmt;
    } else if (fmt == "textgrid" || fmt == "eaf") {
      set(t.labels, "label file");
      t.labels_format = fmt;
    } else if (fmt == "wav") {
      set(t.audio, "audio file");
    }
  }
  ImportResult result;
  for (const auto& stem : order) {
    const TakeFiles& t = takes[stem];
    if (t.capture.empty()) {
      std::string f = !t.labels.empty() ? t.labels : t.audio;
      throw InvalidInput(f + ": no capture (.c3d or .trc) named \"" + stem + "\" to pair it with");
    }
  }
  std::optional<MarkerSet> markerset;
  if (!options.markerset.empty()) markerset = LoadMarkerSet(options.markerset);

  std::error_code ec;
  int64_t total_bytes = 0;
  for (const auto& stem : order) total_bytes += static_cast<int64_t>(fs::file_size(takes[stem].capture, ec));
  total_bytes = std::max<int64_t>(total_bytes, 1);

  CorpusTransaction tx(options.corpus);
  int64_t done_bytes = 0;
  for (const auto& stem : order) {
    const TakeFiles& files = takes[stem];
    progress.Update("import " + stem, static_cast<double>(done_bytes) / static_cast<double>(total_bytes));
    Take header;
    header.name = stem;
    header.provenance.csw_version = CSW_VERSION;
    header.provenance.imported_utc = NowUtc();
    header.provenance.sources.push_back({files.capture, Sha256OfFile(files.capture), files.capture_format});
    std::unique_ptr<C3dReader> c3d;
    Take whole;  // TRC: small files, read whole
    if (files.capture_format == "c3d") {
      c3d = std::make_unique<C3dReader>(files.capture);
      const C3dInfo& info = c3d->info();
      header.rate_hz = info.point_rate_hz;
      header.first_frame = info.first_frame;
      header.marker_names = info.labels;
      header.source_units = info.units;
      header.events = info.events;
      header.analog.rate_hz = info.analog_rate_hz;
      header.analog.names = info.analog_labels;
      header.analog.units = info.analog_units;
      for (const auto& w : info.warnings) header.provenance.warnings.push_back(w);
    } else {
      whole = ReadTrc(files.capture);
      header.rate_hz = whole.rate_hz;
      header.first_frame = whole.first_frame;
      header.marker_names = whole.marker_names;
      header.source_units = whole.source_units;
      header.events = whole.events;
      header.provenance.warnings = whole.provenance.warnings;
    }
    if (markerset) BindMarkerSet(*markerset, header.marker_names, true, files.capture);
    if (!files.labels.empty()) {
      header.provenance.sources.push_back({files.labels, Sha256OfFile(files.labels), files.labels_format});
      if (files.labels_format == "textgrid") {
        header.tiers = ReadTextGrid(files.labels);
      } else {
        std::vector<std::string> warnings;
        header.tiers = ReadEaf(files.labels, &warnings);
        for (const auto& w : warnings) header.provenance.warnings.push_back(files.labels + ": " + w);
      }
    }
    if (!files.audio.empty()) {
      header.provenance.sources.push_back({files.audio, Sha256OfFile(files.audio), "wav"});
      header.audio = ReadWav(files.audio);
      header.audio_path = files.audio;
    }
    for (const auto& w : header.provenance.warnings) result.warnings.push_back(stem + ": " + w);
    if (tx.HasTake(stem)) {
      if (!options.replace)
        throw InvalidInput(options.corpus + ": already has a take named \"" + stem + "\" (from " + files.capture +
                           "); use --replace to replace it");
      tx.RemoveTake(stem);
    }

    if (c3d) {
      const C3dInfo& info = c3d->info();
      const int64_t frames = info.frames;
      const int64_t n_markers = info.points;
      const int64_t chunk = options.chunk_frames;
      const int64_t analog_per_frame = info.analog_channels * info.analog_subframes_per_frame;
      CorpusTransaction::TakeWriter writer = tx.BeginTake(header);
      std::vector<float> points(static_cast<size_t>(chunk * n_markers * 3));
      std::vector<float> analog(static_cast<size_t>(chunk * analog_per_frame));
      const int64_t file_bytes = static_cast<int64_t>(fs::file_size(files.capture, ec));
      for (int64_t f = 0; f < frames; f += chunk) {
        int64_t n = std::min(chunk, frames - f);
        c3d->ReadFrames(f, n, points.data(), nullptr, analog_per_frame ? analog.data() : nullptr);
        writer.AppendFrames(points.data(), n);
        if (analog_per_frame) writer.AppendAnalog(analog.data(), n * info.analog_subframes_per_frame);
        progress.Update("import " + stem, (static_cast<double>(done_bytes) +
                                           static_cast<double>(file_bytes) * (f + n) / std::max<int64_t>(frames, 1)) /
                                              static_cast<double>(total_bytes));
      }
      writer.Finish();
      result.frames += frames;
    } else {
      whole.name = header.name;
      whole.tiers = header.tiers;
      whole.audio = header.audio;
      whole.audio_path = header.audio_path;
      whole.provenance = header.provenance;
      tx.WriteTake(whole);
      result.frames += whole.frames();
    }
    done_bytes += static_cast<int64_t>(fs::file_size(files.capture, ec));
    result.bytes_read += static_cast<int64_t>(fs::file_size(files.capture, ec));
    result.takes.push_back(stem);
  }
  progress.Update("commit", 1.0);
  tx.Commit();
  return result;
}

// ---- info ------------------------------------------------------------------

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
                     {"analog_channels", t.analog_channels}});
    total_s += t.duration_s;
    total_frames += t.frames;
  }
  return {{"corpus", corpus_path},
          {"takes", takes},
          {"take_count", takes.size()},
          {"frames", total_frames},
          {"duration_s", total_s}};
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

// ---- export ----------------------------------------------------------------

std::string ExportOptions::Check() const {
  if (corpus.empty() || take.empty() || output.empty()) return "export: corpus, --take and -o are required";
  if (format != "c3d" && format != "trc" && format != "csv") return "export: --format must be c3d, trc or csv";
  return "";
}

void Export(const ExportOptions& options, Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  Corpus corpus = Corpus::Open(options.corpus);
  if (!corpus.HasTake(options.take)) throw InvalidInput(options.corpus + ": no take named \"" + options.take + "\"");
  progress.Update("export", 0.0);
  Take take = corpus.LoadTake(options.take);
  // Write into a temporary sibling folder under the final file name (formats such as
  // TRC record their own file name), then rename: a failed export never leaves half a file.
  fs::path out_path(options.output);
  fs::path tmp_dir = out_path.parent_path() / (".csw-export-" + out_path.filename().string());
  std::error_code mk;
  fs::create_directories(tmp_dir, mk);
  if (mk) throw IoError(tmp_dir.string(), "cannot create temporary folder: " + mk.message());
  std::string tmp = (tmp_dir / out_path.filename()).string();
  try {
    if (options.format == "c3d") {
      WriteC3d(tmp, take);
    } else if (options.format == "trc") {
      WriteTrc(tmp, take);
    } else {
      std::ofstream out(tmp);
      if (!out) throw IoError(tmp, "cannot open for writing");
      out << "frame,time_s";
      for (const auto& n : take.marker_names) out << "," << n << "_x," << n << "_y," << n << "_z";
      out << "\n";
      char buf[32];
      for (int64_t f = 0; f < take.frames(); ++f) {
        std::snprintf(buf, sizeof(buf), "%.6f", static_cast<double>(f) / take.rate_hz);
        out << (take.first_frame + f) << "," << buf;
        for (int64_t m = 0; m < take.markers.markers(); ++m) {
          const float* p = take.markers.at(f, m);
          for (int k = 0; k < 3; ++k) {
            out << ",";
            if (!IsMissing(p[k])) {
              std::snprintf(buf, sizeof(buf), "%.9g", static_cast<double>(p[k]));
              out << buf;
            }
          }
        }
        out << "\n";
        if (f % 1024 == 0) progress.Update("export", static_cast<double>(f) / static_cast<double>(take.frames()));
      }
      out.close();
      if (!out) throw IoError(tmp, "write failed");
    }
    std::error_code ec;
    fs::rename(tmp, options.output, ec);
    if (ec) throw IoError(options.output, "cannot rename from " + tmp + ": " + ec.message());
    fs::remove(tmp_dir, ec);
  } catch (...) {
    std::error_code ec;
    fs::remove_all(tmp_dir, ec);
    throw;
  }
  progress.Update("export", 1.0);
}

// ---- simulate --------------------------------------------------------------

std::string SimulateJobOptions::Check() const {
  if (output.empty()) return "simulate: no output folder (-o)";
  CorpusKind kind;
  if (corpus != "demo" && !ParseCorpusKind(corpus, &kind))
    return "simulate: unknown corpus \"" + corpus + "\" (shapes, visemes, sentences or demo)";
  if (count < 0) return "simulate: --count must be >= 0";
  if (!texts.empty() && !sentences_file.empty()) return "simulate: give --text or --sentences, not both";
  return "";
}

std::vector<std::string> Simulate(const SimulateJobOptions& options, Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput(why);
  if (options.corpus == "demo") {
    GenerateDemoCorpus(options.output, options.seed, options.count > 0 ? options.count : 20, progress);
    std::vector<std::string> names;
    for (const char* sub : {"shapes", "visemes", "sentences"}) {
      std::error_code ec;
      for (const auto& e : fs::directory_iterator(fs::path(options.output) / sub, ec))
        if (e.path().extension() == ".c3d" && e.path().stem().extension().empty())
          names.push_back(std::string(sub) + "/" + e.path().stem().string());
    }
    std::sort(names.begin(), names.end());
    return names;
  }
  SimulateOptions o;
  ParseCorpusKind(options.corpus, &o.kind);
  o.seed = options.seed;
  o.count = options.count;
  o.noise_mm = options.noise_mm;
  o.occlusions = options.occlusions;
  o.label_swaps = options.label_swaps;
  o.rate_hz = options.rate_hz;
  o.write_clean = options.clean;
  o.sentences = options.texts;
  if (!options.sentences_file.empty()) {
    std::ifstream in(options.sentences_file);
    if (!in) throw IoError(options.sentences_file, "cannot open sentence list");
    std::string line;
    while (std::getline(in, line)) {
      if (!line.empty() && line.back() == '\r') line.pop_back();
      if (!line.empty() && line[0] != '#') o.sentences.push_back(line);
    }
    if (o.sentences.empty()) throw InvalidInput(options.sentences_file + ": no sentences (one per line)");
  }
  if (std::string why = o.Check(); !why.empty()) throw InvalidInput("simulate: " + why);
  return SimulateCorpus(o, options.output, progress);
}

}  // namespace csw::jobs
