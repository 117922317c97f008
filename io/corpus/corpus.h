#pragma once
// The HDF5 corpus store. Format version 2 (docs/corpus-format.md): the corpus
// file "corpus.h5" is a small index whose /takes/<name> groups carry each
// take's attributes and HDF5 external links into immutable per-take files in
// the folder "corpus.h5.d/" beside it, so that h5py and MATLAB users still read
// /takes/<name>/markers with one open call. Version 1 (one self-contained
// file) and packed files (PackCorpus) are read the same way.
//
// Reading goes through Corpus (a read-only view); every change goes through a
// CorpusTransaction, which writes only new files (the changed takes' files and
// a fresh index) and atomically renames the new index over the corpus on
// Commit(): a process killed at any moment leaves the previous corpus intact,
// and a commit costs what changed, not the size of the corpus.
//
// Thread safety: all HDF5 calls of this module are serialized by one lock, so
// different Corpus / CorpusTransaction objects may be used from different
// threads; one object must not be used from two threads at once.
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/take.h"

namespace csw {
class Progress;
}

namespace csw {

inline constexpr int kCorpusFormatVersion = 2;
// Markers are stored in chunks of kCorpusChunkFrames frames × all markers × 3,
// with the shuffle filter then deflate at kCorpusDeflateLevel.
inline constexpr int64_t kCorpusChunkFrames = 256;
inline constexpr int kCorpusDeflateLevel = 1;

struct TakeSummary {
  std::string name;
  double rate_hz = 0.0;
  int64_t frames = 0;
  int64_t markers = 0;
  int64_t gaps = 0;  // total gap count over markers (maximal runs of missing frames)
  double duration_s = 0.0;
  std::vector<std::string> tier_names;
  bool has_audio = false;
  int64_t analog_channels = 0;
  bool has_markerset = false;  // the take remembers the marker set it was imported with (Take::markerset_json)
};

// Per-frame analysis results of a take (docs/corpus-format.md, "scores/"):
// a named set (e.g. "keys", the gestural score of `csw keys score`) of
// matrices with one row per frame, sampled at rate_hz from start_s (take
// time). Set and matrix names are non-empty, without '/', not "." or "..".
struct ScoreMatrix {
  std::string name;                       // e.g. "shape"
  int64_t rows = 0;                       // frames
  int64_t cols = 0;                       // e.g. classes
  std::vector<double> values;             // rows × cols, row-major
  std::vector<std::string> column_names;  // cols names, or empty
};

struct TakeScores {
  std::string name;                   // e.g. "keys"
  double rate_hz = 0.0;               // rows per second (> 0)
  double start_s = 0.0;               // time of row 0
  std::string source;                 // what computed them, e.g. the key model file
  std::vector<ScoreMatrix> matrices;  // read back in name order
};

// "" or why the set cannot be stored (a name, a size, the rate).
std::string ScoresProblem(const TakeScores& scores);

// A read-only view of a corpus file. Cheap to copy (copies share the open file).
class Corpus {
 public:
  // Opens and validates the corpus: throws IoError when the file cannot be
  // read, ParseError naming the file (and the take) when it is not an HDF5
  // file, not a csw corpus, of a newer format version, or damaged.
  static Corpus Open(const std::string& path);

  std::vector<TakeSummary> Takes() const;  // in name order
  TakeSummary Summary(const std::string& take) const;
  bool HasTake(const std::string& name) const;
  // Everything about one take. Throws InvalidInput when there is no such take.
  Take LoadTake(const std::string& name) const;
  // Frames [first, first + count) of one take, for streaming reads; throws
  // InvalidInput when the range is not inside the take.
  MarkerArray LoadMarkers(const std::string& take, int64_t first, int64_t count) const;
  // The label tiers of one take (LoadTake(take).tiers without reading its
  // markers, audio or analog data). Throws InvalidInput when there is no such take.
  std::vector<LabelTier> LoadTiers(const std::string& take) const;
  // The marker-set definition (JSON text) the take was imported with, "" when
  // none. Throws InvalidInput when there is no such take.
  std::string TakeMarkerSet(const std::string& take) const;
  // Names of the take's score sets (name order); empty when none.
  std::vector<std::string> ScoreNames(const std::string& take) const;
  // One score set of a take, nullopt when the take has none of that name.
  // Throws InvalidInput when there is no such take, ParseError naming the
  // corpus and the object when the stored set is damaged.
  std::optional<TakeScores> LoadScores(const std::string& take, const std::string& name) const;
  // 1 (single file), 2 (index + folder, or packed).
  int format_version() const;
  std::string path() const;

 private:
  struct Impl;
  explicit Corpus(std::shared_ptr<const Impl> impl) : impl_(std::move(impl)) {}
  std::shared_ptr<const Impl> impl_;
};

enum class IfTakeExists { kFail, kReplace };

// Crash-safe writing. Every change writes new, uniquely named files in the
// folder "<name>.d/" (never rewriting a committed one) and edits an in-memory
// table of takes; Commit() fsyncs the new files, writes a fresh index to the
// temporary sibling TempPath(), fsyncs it, renames it over the corpus and
// fsyncs the directory, then deletes the files no index references any more
// unless a reader (in another process, or a live Corpus of this one) may still
// need them. Without Commit() the destructor removes the new files. A
// transaction on a version-1 or packed corpus copies its takes into per-take
// files (the upgrade) and commits a version-2 index. Only one transaction per
// corpus may be open at a time (an advisory lock on a sibling
// ".<name>.csw-lock" file); a second one throws IoError.
class CorpusTransaction {
 public:
  // Creates the corpus (in the temporary file) when it does not exist; throws
  // ParseError when an existing file is not a valid corpus.
  explicit CorpusTransaction(const std::string& path);
  // Same, reporting the upgrade of a version-1 or packed corpus (which copies
  // every take) to `progress`.
  CorpusTransaction(const std::string& path, Progress& progress);
  ~CorpusTransaction();
  CorpusTransaction(const CorpusTransaction&) = delete;
  CorpusTransaction& operator=(const CorpusTransaction&) = delete;

  // Streams one take's markers (and optionally analog samples) into the
  // corpus; memory stays O(one chunk). Must be finished before Commit(); a
  // writer destroyed unfinished removes its partial take. Must not outlive its
  // transaction.
  class TakeWriter {
   public:
    TakeWriter(TakeWriter&&) noexcept;
    TakeWriter& operator=(TakeWriter&&) noexcept;
    ~TakeWriter();

    // frames × markers × 3 floats (mm, NaN = missing), frame-major.
    void AppendFrames(const float* xyz_mm, int64_t frames);
    // samples × channels floats; the channels are those of the header's analog.
    void AppendAnalog(const float* values, int64_t samples);
    // frames × joints × 4 floats (w, x, y, z global joint orientations), for a
    // take begun with a skeleton; by Finish() as many frames as the markers.
    void AppendOrientations(const float* wxyz, int64_t frames);
    // Writes the remaining buffered frames and the summary attributes.
    void Finish();
    int64_t frames_written() const;

   private:
    friend class CorpusTransaction;
    struct Impl;
    explicit TakeWriter(std::unique_ptr<Impl> impl);
    std::unique_ptr<Impl> impl_;
  };

  // Starts a take from everything but its markers: name, rate, first_frame,
  // marker_names, source_units, analog (its data, possibly empty, is written
  // at once; more may follow with AppendAnalog), skeleton and orientations
  // (likewise: header.orientations is written at once, more may follow with
  // AppendOrientations; the skeleton must have one joint per marker), events,
  // tiers, audio, audio_path and provenance. header.markers is ignored.
  // Throws InvalidInput when the name is not a valid take name, a take of that
  // name exists and if_exists is kFail, or the skeleton does not match the
  // markers.
  TakeWriter BeginTake(const Take& header, IfTakeExists if_exists = IfTakeExists::kFail);
  // The whole take at once (BeginTake + AppendFrames + Finish).
  void WriteTake(const Take& take, IfTakeExists if_exists = IfTakeExists::kFail);
  bool HasTake(const std::string& name) const;
  std::vector<std::string> TakeNames() const;
  // Throws InvalidInput when there is no such take.
  void RemoveTake(const std::string& name);
  // The label tiers of a take as this transaction holds them: as stored when it
  // began, or as WriteTiers/BeginTake last replaced them. Reads only that
  // take's tiers file (a read-modify-write of one take's tiers costs the same
  // whatever the corpus holds). Throws InvalidInput when there is no such take.
  std::vector<LabelTier> LoadTiers(const std::string& take) const;
  // Replaces all label tiers of a take.
  void WriteTiers(const std::string& take, const std::vector<LabelTier>& tiers);
  // Stores a score set of a take, replacing the set of that name (the take's
  // other sets are kept). Replacing the take (WriteTake with kReplace) drops
  // its scores. Throws InvalidInput for a bad set (ScoresProblem) or take.
  void WriteScores(const std::string& take, const TakeScores& scores);
  // Replaces the audio of a take (an empty audio removes the samples).
  void WriteAudio(const std::string& take, const Audio& audio, const std::string& source_path);
  // Makes every change durable and visible at path(). Throws when a
  // TakeWriter is still open; the transaction cannot be used afterwards.
  void Commit();

  const std::string& path() const;
  // The temporary index written by Commit() before it replaces the corpus.
  static std::string TempPath(const std::string& corpus_path);
  // The folder of per-take files of a version-2 corpus: "<corpus_path>.d".
  static std::string FolderPath(const std::string& corpus_path);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace csw
