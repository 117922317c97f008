#pragma once
// Labelling one key tier of one take: the core label model (core/labels.h)
// edited through undoable commands on a QUndoStack, and autosave. The first
// change (an edit, an undo, a redo) not yet in a snapshot starts a single-shot
// timer, which later changes do not restart (so that labelling without a pause
// is still saved every few seconds); when it fires, a snapshot of the take's tiers is handed to a TierSaver, which
// commits it to the corpus on its own thread (CorpusTransaction + WriteTiers: only that take's tier file and a fresh
// index are written; the tiers edited replace their namesakes among those stored, so tiers another writer stored
// meanwhile are kept). The GUI thread never waits on HDF5. When the corpus's writer lock is held by another writer the
// save fails, a warning goes to the log once, and the newest snapshot is retried until it is written: an edit is never
// dropped.
//
// Guides for labelling, read from the take's other tiers when the take is set:
// the suggested targets (a point tier of key codes, default `keys_suggested`,
// written by `csw keys suggest`) and the expected keys (an interval tier,
// default `expected_keys`, written by `csw cue`). A suggestion is open while
// the labelled tier has no label within kSuggestionToleranceFrames of it; an
// expected key is open while the labelled tier has no label inside its interval.
#include <QObject>
#include <QString>
#include <QTimer>
#include <QUndoStack>
#include <condition_variable>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/labels.h"
#include "core/take.h"

namespace csw {
struct TakeScores;
}

namespace csw::gui {

class LogPanel;

// Where the key recogniser is unsure, per frame of a take (rate_hz, `frames`
// frames): 1 where the largest posterior of the score set's "shape" or
// "placement" matrix (every matrix when it has neither) at the frame's row is
// below `threshold`; 0 elsewhere, and where the scores have no row or no finite
// value for the frame.
std::vector<uint8_t> UnsureFrames(const TakeScores& scores, int64_t frames, double rate_hz, double threshold);

// The frame of the local minimum of `speed` (one value per frame, NaN =
// missing) nearest to `frame` within max_distance frames, the earlier one on a
// tie; -1 when there is none. A local minimum is a finite value no larger than
// its finite neighbours and smaller than at least one of them (the ends of the
// take and of a gap count with their one neighbour); in a flat run the run's middle frame
// stands for it.
int64_t NearestSpeedMinimum(const std::vector<float>& speed, int64_t frame, int64_t max_distance);

// Writes a take's label tiers into a corpus on one worker thread, one job at
// a time, in order. Results come back as queued calls on the GUI thread.
class TierSaver : public QObject {
  Q_OBJECT

 public:
  // Replaces (or adds) `tiers` among the take's tiers as they are in the corpus
  // when the writer lock is taken: tiers written meanwhile by someone else
  // (e.g. a CLI command) are kept.
  struct Job {
    std::string corpus;
    std::string take;
    std::vector<LabelTier> tiers;
    long generation = 0;  // the caller's tag for this snapshot
  };

  explicit TierSaver(QObject* parent = nullptr);
  // Finishes the jobs already queued, then stops the thread.
  ~TierSaver() override;

  void Post(Job job);
  bool busy() const;

 signals:
  void Saved(const QString& corpus, const QString& take, long generation, double elapsed_ms);
  void Failed(const QString& corpus, const QString& take, long generation, const QString& message, bool locked);

 private:
  void Run();

  mutable std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<Job> jobs_;
  bool running_job_ = false;
  bool stop_ = false;
  std::thread thread_;
};

class LabelSession : public QObject {
  Q_OBJECT

 public:
  static constexpr int kDefaultAutosaveDelayMs = 2000;
  static constexpr int kDefaultRetryDelayMs = 1000;

  explicit LabelSession(LogPanel* log, QObject* parent = nullptr);
  // Writes any unsaved snapshot (waiting for the worker), unless the writer
  // lock is still held by someone else.
  ~LabelSession() override;

  // Starts labelling `tier_name` of `take` (stored in `corpus`), after taking a
  // snapshot of the pending edits of the tier labelled so far. The take's tiers
  // are those this session last wrote for it (KnownTiers) when there are any,
  // else take->tiers. An existing point tier of that name is edited; a missing one is created empty over
  // [0, take duration]. The undo history starts empty. Throws InvalidInput
  // when the tier exists but is an interval tier or holds a bad key code.
  // `take` may be null (nothing to label).
  void SetTake(const std::string& corpus, std::shared_ptr<const Take> take, const std::string& tier_name);
  // The tiers of `take` to show instead of the stored ones when this session
  // has written (or is writing) them since the corpus was opened; nullopt when
  // it has not.
  std::optional<std::vector<LabelTier>> KnownTiers(const std::string& corpus, const std::string& take) const;
  // Forgets snapshots already saved (a corpus was (re)opened); unsaved ones stay queued.
  void ForgetSaved();

  bool has_take() const { return model_ != nullptr; }
  const LabelModel* model() const { return model_.get(); }
  QUndoStack* undo_stack() const { return stack_; }
  const std::string& tier_name() const { return tier_name_; }
  const std::string& take_name() const { return take_name_; }
  double rate_hz() const { return rate_hz_; }
  int64_t frames() const { return frames_; }

  // Frame <-> label time (frame / rate).
  double FrameTime(int64_t frame) const;
  int64_t TimeFrame(double time_s) const;
  // Index of the label on `frame`, or -1.
  long LabelAtFrame(int64_t frame) const;

  // Edits; each pushes one undoable command. False (and an error in the log,
  // nothing changed) when the edit is refused (bad code, frame outside the
  // take, no such label).
  bool AddLabel(int64_t frame, const QString& code);
  bool MoveLabel(long index, int64_t to_frame);
  bool Relabel(long index, const QString& code);
  bool DeleteLabel(long index);

  // Guides (see the top of this file). A tier that is missing gives no guides;
  // one that cannot be read (bad key codes, wrong kind) gives none and a
  // warning in the log.
  static constexpr int64_t kSuggestionToleranceFrames = 2;
  struct Suggestion {
    int64_t frame = 0;
    QString code;
  };
  struct ExpectedKeySpan {
    double start_s = 0.0;
    double end_s = 0.0;
    int64_t middle_frame = 0;  // where a jump puts the cursor
    QString code;
  };
  void SetSuggestionTier(const std::string& name);
  void SetExpectedTier(const std::string& name);
  const std::string& suggestion_tier() const { return suggestion_tier_; }
  const std::string& expected_tier() const { return expected_tier_; }
  const std::vector<Suggestion>& suggestions() const { return suggestions_; }
  const std::vector<ExpectedKeySpan>& expected_keys() const { return expected_; }
  // A label of the labelled tier lies within the tolerance of suggestion `index`.
  bool SuggestionAccepted(size_t index) const;
  // A label of the labelled tier lies in [start, end) of expected key `index`.
  bool ExpectedKeyLabelled(size_t index) const;
  // The frame of the first open suggestion after `frame` (direction > 0) or the
  // last one before it (direction < 0); -1 when there is none.
  int64_t NextOpenSuggestion(int64_t frame, int direction) const;
  // Index of the open suggestion nearest to `frame` within the tolerance, or -1.
  long OpenSuggestionNear(int64_t frame) const;
  // Accepts the open suggestion nearest to `frame` within the tolerance: one
  // undoable AddLabel of its code at its frame. Returns that frame, or -1 (and
  // a line in the log) when there is none.
  int64_t AcceptSuggestion(int64_t frame);
  // The middle frame of the first open expected key whose middle frame is after
  // `frame` (direction > 0) or the last one before it (direction < 0); -1 when none.
  int64_t NextOpenExpectedKey(int64_t frame, int direction) const;

  // Frames where the recogniser is unsure (UnsureFrames of the take's stored
  // score set kUnsureScores, read by the take loader), for take `take`; an
  // empty vector when the take has none. Kept when the tier changes.
  static constexpr const char* kUnsureScores = "keys";
  static constexpr double kUnsurePosterior = 0.6;
  void SetUnsureFrames(const std::string& take, std::vector<uint8_t> unsure);
  // The unsure frames of the take labelled (empty when none are known).
  const std::vector<uint8_t>& unsure_frames() const;
  // The first frame of the first run of unsure frames starting after `frame`
  // (direction > 0) or the last one starting before it (direction < 0); -1 when none.
  int64_t NextUnsureFrame(int64_t frame, int direction) const;

  // Autosave.
  void SetAutosaveDelay(int ms) { autosave_timer_.setInterval(ms); }
  void SetRetryDelay(int ms) { retry_timer_.setInterval(ms); }
  int autosave_delay_ms() const { return autosave_timer_.interval(); }
  // Snapshots not yet committed (waiting for the timer, the worker or the lock).
  bool HasUnsavedEdits() const;
  // Starts the save now instead of at the timer.
  void SaveNow();
  TierSaver* saver() const { return saver_.get(); }

 signals:
  // The labels changed (edit, undo, redo, new take).
  void LabelsChanged();
  // A snapshot of `take` reached the corpus; elapsed_ms is the worker's commit time.
  void Saved(const QString& take, double elapsed_ms);
  // A save failed and will be retried.
  void SaveDeferred(const QString& take, const QString& message);

 private:
  class Command;
  bool Push(std::unique_ptr<LabelCommand> command);
  void OnChanged();
  void ReadGuides();
  void Snapshot();
  void StartNextSave();
  void OnSaved(const QString& corpus, const QString& take, long generation, double elapsed_ms);
  void OnFailed(const QString& corpus, const QString& take, long generation, const QString& message, bool locked);

  LogPanel* log_;
  QUndoStack* stack_;
  std::unique_ptr<LabelModel> model_;
  std::shared_ptr<const Take> take_;
  std::vector<LabelTier> base_tiers_;  // the take's tiers the model's tier goes into
  std::string corpus_;
  std::string take_name_;
  std::string tier_name_;
  double rate_hz_ = 0.0;
  int64_t frames_ = 0;
  bool clearing_ = false;
  std::string suggestion_tier_ = "keys_suggested";
  std::string expected_tier_ = "expected_keys";
  std::vector<Suggestion> suggestions_;    // in frame order
  std::vector<ExpectedKeySpan> expected_;  // in time order
  std::string unsure_take_;
  std::vector<uint8_t> unsure_;

  // Per (corpus, take): the newest tiers this session produced, and whether
  // they still have to be written.
  struct Snap {
    std::vector<LabelTier> tiers;             // all the take's tiers, as shown
    std::map<std::string, LabelTier> edited;  // the tiers edited, by name: what a save writes
    long generation = 0;
    long saved_generation = 0;
    bool in_flight = false;
    bool deferred_logged = false;
  };
  static std::vector<LabelTier> EditedTiers(const Snap& snap);
  std::map<std::pair<std::string, std::string>, Snap> snaps_;
  long next_generation_ = 0;
  QTimer autosave_timer_;
  QTimer retry_timer_;
  std::unique_ptr<TierSaver> saver_;
};

}  // namespace csw::gui
