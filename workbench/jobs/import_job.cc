#include "workbench/jobs/import_job.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>

#include "core/error.h"
#include "core/file_util.h"
#include "core/markerset.h"
#include "core/sha256.h"
#include "core/take.h"
#include "io/c3d/c3d.h"
#include "io/corpus/corpus.h"
#include "io/formats/bvh.h"
#include "io/formats/eaf.h"
#include "io/formats/textgrid.h"
#include "io/formats/trc.h"
#include "io/formats/wav.h"
#include "workbench/jobs/job_util.h"

namespace csw::jobs {

namespace fs = std::filesystem;

namespace {

// `f` is the --markerset file itself (a folder's files given with a wildcard
// include its markerset.json): left out of the takes.
bool IsTheMarkerSet(const std::string& f, const std::string& markerset) {
  if (markerset.empty()) return false;
  if (f == markerset) return true;
  std::error_code ec;
  return fs::equivalent(f, markerset, ec) && !ec;
}

}  // namespace

std::string ImportOptions::Check() const {
  if (files.empty()) return "import: no input files";
  if (corpus.empty()) return "import: no output corpus (-o)";
  if (chunk_frames < 1) return "import: chunk_frames must be positive";
  for (const auto& f : files) {
    if (IsTheMarkerSet(f, markerset)) continue;
    if (FormatOf(f).empty() || FormatOf(f) == "hdf5") {
      std::string why = "import: " + f + ": unsupported file type (expected .c3d, .trc, .bvh, .TextGrid, .eaf or .wav)";
      if (LowerExtension(f) == ".json") why += "; a marker set is given with --markerset " + f;
      return why;
    }
  }
  if (!units.empty()) {
    if (!IsBvhUnit(units)) return "import: --units must be mm, cm, dm, m or in, not '" + units + "'";
    bool any_bvh = false;
    for (const auto& f : files) any_bvh = any_bvh || FormatOf(f) == "bvh";
    if (!any_bvh) return "import: --units applies to .bvh files (C3D and TRC files carry their unit)";
  }
  std::error_code ec;
  if (!markerset.empty() && !std::filesystem::is_regular_file(markerset, ec))
    return "import: --markerset " + markerset + ": no such file";
  return "";
}

namespace {

struct TakeFiles {
  std::string capture, capture_format, labels, labels_format, audio;
};

}  // namespace

ImportResult Import(const ImportOptions& options, Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw UsageError(why);
  // Pair files by base name.
  std::map<std::string, TakeFiles> takes;
  std::vector<std::string> order;
  for (const auto& f : options.files) {
    if (IsTheMarkerSet(f, options.markerset)) continue;
    std::string stem = fs::path(f).stem().string();
    std::string fmt = FormatOf(f);
    if (!takes.count(stem)) order.push_back(stem);
    TakeFiles& t = takes[stem];
    auto set = [&](std::string& slot, const std::string& what) {
      if (!slot.empty())
        throw UsageError(f + ": a second " + what + " for take \"" + stem + "\" (first: " + slot + ")");
      slot = f;
    };
    if (fmt == "c3d" || fmt == "trc" || fmt == "bvh") {
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
      throw UsageError(f + ": no capture (.c3d, .trc or .bvh) named \"" + stem + "\" to pair it with");
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
    header.provenance.imported_utc = UtcNow();
    header.provenance.sources.push_back({files.capture, Sha256OfFile(files.capture), files.capture_format});
    std::unique_ptr<C3dReader> c3d;
    Take whole;  // TRC, BVH: text files, read whole
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
      if (files.capture_format == "bvh") {
        BvhReadOptions bvh;
        bvh.units = options.units;
        whole = ReadBvh(files.capture, bvh);
      } else {
        whole = ReadTrc(files.capture);
      }
      header.rate_hz = whole.rate_hz;
      header.first_frame = whole.first_frame;
      header.marker_names = whole.marker_names;
      header.source_units = whole.source_units;
      header.events = whole.events;
      header.provenance.warnings = whole.provenance.warnings;
    }
    if (markerset) {
      BindMarkerSet(*markerset, header.marker_names, true, files.capture);
      header.markerset_json = MarkerSetToJson(*markerset);  // the corpus remembers it with the take
    }
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

nlohmann::json ImportReportJson(const ImportOptions& options, const ImportResult& result) {
  return {
      {"corpus", options.corpus}, {"takes", result.takes}, {"frames", result.frames}, {"warnings", result.warnings}};
}

std::string ImportWarningsText(const ImportResult& result) {
  std::string out;
  for (const auto& w : result.warnings) out += "warning: " + w + "\n";
  return out;
}

std::string ImportSummaryText(const ImportOptions& options, const ImportResult& result) {
  return "imported " + std::to_string(result.takes.size()) + " take(s), " + std::to_string(result.frames) +
         " frames into " + options.corpus + "\n";
}

}  // namespace csw::jobs
