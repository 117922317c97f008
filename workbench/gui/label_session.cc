#include "workbench/gui/label_session.h"

#include <QUndoCommand>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>

#include "core/error.h"
#include "io/corpus/corpus.h"
#include "workbench/gui/log_panel.h"

namespace csw::gui {

int64_t NearestSpeedMinimum(const std::vector<float>& speed, int64_t frame, int64_t max_distance) {
  const auto n = static_cast<int64_t>(speed.size());
  auto ok = [&](int64_t i) { return i >= 0 && i < n && std::isfinite(speed[static_cast<size_t>(i)]); };
  auto v = [&](int64_t i) { return speed[static_cast<size_t>(i)]; };
  int64_t best = -1;
  int64_t best_distance = max_distance + 1;
  for (int64_t i = 0; i < n;) {
    if (!ok(i)) {
      ++i;
      continue;
    }
    // A run of equal finite values [i, j).
    int64_t j = i + 1;
    while (ok(j) && v(j) == v(i)) ++j;
    const bool left_higher = !ok(i - 1) || v(i - 1) > v(i);
    const bool right_higher = !ok(j) || v(j) > v(i);
    const bool has_neighbour = ok(i - 1) || ok(j);  // so every neighbour there is, is higher
    if (left_higher && right_higher && has_neighbour) {
      const int64_t at = i + (j - 1 - i) / 2;
      const int64_t distance = std::abs(at - frame);
      if (distance < best_distance) {
        best_distance = distance;
        best = at;
      }
    }
    i = j;
  }
  return best;
}

std::vector<uint8_t> UnsureFrames(const TakeScores& scores, int64_t frames, double rate_hz, double threshold) {
  std::vector<uint8_t> unsure(static_cast<size_t>(std::max<int64_t>(0, frames)), 0);
  if (rate_hz <= 0 || scores.rate_hz <= 0) return unsure;
  std::vector<const ScoreMatrix*> used;
  for (const ScoreMatrix& m : scores.matrices) {
    if (m.name == "shape" || m.name == "placement") used.push_back(&m);
  }
  if (used.empty()) {
    for (const ScoreMatrix& m : scores.matrices) used.push_back(&m);
  }
  for (int64_t f = 0; f < frames; ++f) {
    const double t = static_cast<double>(f) / rate_hz;
    const int64_t row = std::llround((t - scores.start_s) * scores.rate_hz);
    for (const ScoreMatrix* m : used) {
      if (row < 0 || row >= m->rows || m->cols <= 0) continue;
      double best = -std::numeric_limits<double>::infinity();
      for (int64_t c = 0; c < m->cols; ++c) {
        const double v = m->values[static_cast<size_t>(row * m->cols + c)];
        if (std::isfinite(v)) best = std::max(best, v);
      }
      if (std::isfinite(best) && best < threshold) unsure[static_cast<size_t>(f)] = 1;
    }
  }
  return unsure;
}

// ---------------------------------------------------------------------------
// TierSaver

TierSaver::TierSaver(QObject* parent) : QObject(parent) {
  thread_ = std::thread([this] { Run(); });
}

TierSaver::~TierSaver() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

void TierSaver::Post(Job job) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    jobs_.push_back(std::move(job));
  }
  wake_.notify_all();
}

bool TierSaver::busy() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return running_job_ || !jobs_.empty();
}

void TierSaver::Run() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stop_ || !jobs_.empty(); });
      if (jobs_.empty()) return;  // stopping, and every queued job is done
      job = std::move(jobs_.front());
      jobs_.pop_front();
      running_job_ = true;
    }
    const QString corpus = QString::fromStdString(job.corpus);
    const QString take = QString::fromStdString(job.take);
    const auto start = std::chrono::steady_clock::now();
    try {
      CorpusTransaction tx(job.corpus);                       // takes the writer lock
      std::vector<LabelTier> tiers = tx.LoadTiers(job.take);  // as stored now (another writer's tiers are kept)
      for (LabelTier& edited : job.tiers) {
        auto it = std::find_if(tiers.begin(), tiers.end(), [&](const LabelTier& t) { return t.name == edited.name; });
        if (it != tiers.end()) {
          *it = std::move(edited);
        } else {
          tiers.push_back(std::move(edited));
        }
      }
      tx.WriteTiers(job.take, tiers);
      tx.Commit();
      const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
      emit Saved(corpus, take, job.generation, ms);
    } catch (const std::exception& e) {
      // WriterLock's message (core/file_util.h) when another writer holds the corpus.
      const std::string what = e.what();
      const bool locked = what.find("is writing this corpus") != std::string::npos;
      emit Failed(corpus, take, job.generation, QString::fromStdString(what), locked);
      bool stopping = false;
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stopping = stop_;
      }
      // On exit nobody listens any more: say it where the user can still see it.
      if (stopping)
        std::fprintf(stderr, "csw-workbench: labels of take %s not saved: %s\n", job.take.c_str(), e.what());
    }
    std::lock_guard<std::mutex> lock(mutex_);
    running_job_ = false;
  }
}

// ---------------------------------------------------------------------------
// LabelSession

// A core label command on the QUndoStack. The first redo() is skipped: Push()
// has already done the command (so that a refused edit never reaches the stack).
class LabelSession::Command : public QUndoCommand {
 public:
  Command(LabelSession* session, std::unique_ptr<LabelCommand> command)
      : QUndoCommand(QString::fromStdString(command->Text())), session_(session), command_(std::move(command)) {}

  void redo() override {
    if (first_) {
      first_ = false;
      return;
    }
    Guarded([this] { command_->Do(*session_->model_); });
  }
  void undo() override {
    Guarded([this] { command_->Undo(*session_->model_); });
  }

 private:
  template <class F>
  void Guarded(F f) {
    try {
      f();
    } catch (const std::exception& e) {
      session_->log_->Error(QObject::tr("Label edit '%1' failed: %2").arg(text(), QString::fromStdString(e.what())));
    }
  }

  LabelSession* session_;
  std::unique_ptr<LabelCommand> command_;
  bool first_ = true;
};

std::vector<LabelTier> LabelSession::EditedTiers(const Snap& snap) {
  std::vector<LabelTier> tiers;
  for (const auto& [name, tier] : snap.edited) tiers.push_back(tier);
  return tiers;
}

LabelSession::LabelSession(LogPanel* log, QObject* parent)
    : QObject(parent), log_(log), stack_(new QUndoStack(this)), saver_(std::make_unique<TierSaver>()) {
  autosave_timer_.setSingleShot(true);
  autosave_timer_.setInterval(kDefaultAutosaveDelayMs);
  retry_timer_.setSingleShot(true);
  retry_timer_.setInterval(kDefaultRetryDelayMs);
  connect(stack_, &QUndoStack::indexChanged, this, [this](int) { OnChanged(); });
  connect(&autosave_timer_, &QTimer::timeout, this, [this] {
    Snapshot();
    StartNextSave();
  });
  connect(&retry_timer_, &QTimer::timeout, this, &LabelSession::StartNextSave);
  connect(saver_.get(), &TierSaver::Saved, this, &LabelSession::OnSaved);
  connect(saver_.get(), &TierSaver::Failed, this, &LabelSession::OnFailed);
}

LabelSession::~LabelSession() {
  retry_timer_.stop();
  if (autosave_timer_.isActive()) {
    autosave_timer_.stop();
    Snapshot();
  }
  disconnect(saver_.get(), nullptr, this, nullptr);
  for (auto& [key, snap] : snaps_) {
    if (snap.generation > snap.saved_generation)
      saver_->Post({key.first, key.second, EditedTiers(snap), snap.generation});
  }
  saver_.reset();  // runs the queued jobs, then joins
}

void LabelSession::SetTake(const std::string& corpus, std::shared_ptr<const Take> take, const std::string& tier_name) {
  // Unsaved edits of the previous take are saved now, not lost with its model.
  if (autosave_timer_.isActive()) {
    autosave_timer_.stop();
    Snapshot();
    StartNextSave();
  }
  std::unique_ptr<LabelModel> model;
  std::vector<LabelTier> base;
  if (take) {
    // The tiers this session wrote last win over the (older) loaded ones.
    base = KnownTiers(corpus, take->name).value_or(take->tiers);
    const std::string where = corpus + ": take '" + take->name + "'";
    LabelTier tier{tier_name, LabelTier::Kind::kPoint, 0.0, take->duration_s(), {}};
    for (const LabelTier& t : base) {
      if (t.name != tier_name) continue;
      if (t.kind != LabelTier::Kind::kPoint) {
        throw InvalidInput(where + ": tier '" + tier_name + "' is an interval tier; key targets go on a point tier");
      }
      tier = t;
      // A tier shorter than the take (e.g. from a TextGrid) still admits every frame.
      tier.start_s = std::min(tier.start_s, 0.0);
      tier.end_s = std::max(tier.end_s, take->duration_s());
    }
    model = std::make_unique<LabelModel>(std::move(tier), true, where);
  }
  clearing_ = true;  // the stack's signals still reach the Undo / Redo actions
  stack_->clear();
  clearing_ = false;
  model_ = std::move(model);
  base_tiers_ = std::move(base);
  take_ = take;
  corpus_ = take ? corpus : std::string();
  take_name_ = take ? take->name : std::string();
  tier_name_ = tier_name;
  rate_hz_ = take ? take->rate_hz : 0.0;
  frames_ = take ? take->frames() : 0;
  ReadGuides();
  emit LabelsChanged();
}

void LabelSession::SetSuggestionTier(const std::string& name) {
  suggestion_tier_ = name;
  ReadGuides();
  emit LabelsChanged();
}

void LabelSession::SetExpectedTier(const std::string& name) {
  expected_tier_ = name;
  ReadGuides();
  emit LabelsChanged();
}

void LabelSession::ReadGuides() {
  suggestions_.clear();
  expected_.clear();
  if (!model_ || !take_) return;
  const std::string where = corpus_ + ": take '" + take_name_ + "'";
  for (const LabelTier& t : base_tiers_) {
    if (t.name == tier_name_) continue;  // the tier labelled guides nothing
    try {
      if (t.name == suggestion_tier_) {
        for (const KeyMark& m : ReadKeyTier(t, where)) {
          const int64_t f = TimeFrame(m.time_s);
          if (f >= 0 && f < frames_) suggestions_.push_back({f, QString::fromStdString(m.code.Text())});
        }
      } else if (t.name == expected_tier_) {
        for (const ExpectedKey& k : ReadExpectedKeyTier(t, where)) {
          const int64_t middle = std::clamp<int64_t>(TimeFrame(0.5 * (k.start_s + k.end_s)), 0, frames_ - 1);
          expected_.push_back({k.start_s, k.end_s, middle, QString::fromStdString(k.code.Text())});
        }
      }
    } catch (const std::exception& e) {
      log_->Warning(tr("Tier %1 not shown as a guide in the label lane: %2")
                        .arg(QString::fromStdString(t.name), QString::fromStdString(e.what())));
      if (t.name == suggestion_tier_) suggestions_.clear();
      if (t.name == expected_tier_) expected_.clear();
    }
  }
  std::stable_sort(suggestions_.begin(), suggestions_.end(),
                   [](const Suggestion& a, const Suggestion& b) { return a.frame < b.frame; });
  std::stable_sort(expected_.begin(), expected_.end(),
                   [](const ExpectedKeySpan& a, const ExpectedKeySpan& b) { return a.start_s < b.start_s; });
}

bool LabelSession::SuggestionAccepted(size_t index) const {
  if (!model_ || rate_hz_ <= 0 || index >= suggestions_.size()) return false;
  const double tolerance = (static_cast<double>(kSuggestionToleranceFrames) + 0.49) / rate_hz_;
  return model_->Find(FrameTime(suggestions_[index].frame), tolerance) >= 0;
}

bool LabelSession::ExpectedKeyLabelled(size_t index) const {
  if (!model_ || index >= expected_.size()) return false;
  const ExpectedKeySpan& span = expected_[index];
  for (size_t i = 0; i < model_->size(); ++i) {
    const double t = model_->at(i).start_s;
    if (t >= span.start_s && t < span.end_s) return true;
  }
  return false;
}

int64_t LabelSession::NextOpenSuggestion(int64_t frame, int direction) const {
  const auto n = suggestions_.size();
  for (size_t k = 0; k < n; ++k) {
    const size_t i = direction > 0 ? k : n - 1 - k;
    const int64_t f = suggestions_[i].frame;
    if ((direction > 0 ? f > frame : f < frame) && !SuggestionAccepted(i)) return f;
  }
  return -1;
}

long LabelSession::OpenSuggestionNear(int64_t frame) const {
  long best = -1;
  int64_t best_distance = kSuggestionToleranceFrames + 1;
  for (size_t i = 0; i < suggestions_.size(); ++i) {
    const int64_t d = std::abs(suggestions_[i].frame - frame);
    if (d < best_distance && !SuggestionAccepted(i)) {
      best_distance = d;
      best = static_cast<long>(i);
    }
  }
  return best;
}

int64_t LabelSession::AcceptSuggestion(int64_t frame) {
  if (!model_) return -1;
  const long index = OpenSuggestionNear(frame);
  if (index < 0) {
    log_->Info(tr("No open suggested target (tier %1) within %2 frames of frame %3")
                   .arg(QString::fromStdString(suggestion_tier_))
                   .arg(kSuggestionToleranceFrames)
                   .arg(frame + (take_ ? take_->first_frame : 0)));
    return -1;
  }
  const Suggestion s = suggestions_[static_cast<size_t>(index)];
  return AddLabel(s.frame, s.code) ? s.frame : -1;
}

void LabelSession::SetUnsureFrames(const std::string& take, std::vector<uint8_t> unsure) {
  unsure_take_ = take;
  unsure_ = std::move(unsure);
  emit LabelsChanged();
}

const std::vector<uint8_t>& LabelSession::unsure_frames() const {
  static const std::vector<uint8_t> kNone;
  return model_ && unsure_take_ == take_name_ ? unsure_ : kNone;
}

int64_t LabelSession::NextUnsureFrame(int64_t frame, int direction) const {
  const std::vector<uint8_t>& u = unsure_frames();
  const auto n = static_cast<int64_t>(u.size());
  auto run_start = [&](int64_t f) {
    return u[static_cast<size_t>(f)] != 0 && (f == 0 || u[static_cast<size_t>(f - 1)] == 0);
  };
  if (direction > 0) {
    for (int64_t f = std::max<int64_t>(0, frame + 1); f < n; ++f)
      if (run_start(f)) return f;
  } else {
    for (int64_t f = std::min(frame - 1, n - 1); f >= 0; --f)
      if (run_start(f)) return f;
  }
  return -1;
}

int64_t LabelSession::NextOpenExpectedKey(int64_t frame, int direction) const {
  const auto n = expected_.size();
  for (size_t k = 0; k < n; ++k) {
    const size_t i = direction > 0 ? k : n - 1 - k;
    const int64_t f = expected_[i].middle_frame;
    if ((direction > 0 ? f > frame : f < frame) && !ExpectedKeyLabelled(i)) return f;
  }
  return -1;
}

std::optional<std::vector<LabelTier>> LabelSession::KnownTiers(const std::string& corpus,
                                                               const std::string& take) const {
  auto it = snaps_.find({corpus, take});
  if (it == snaps_.end()) return std::nullopt;
  return it->second.tiers;
}

void LabelSession::ForgetSaved() {
  for (auto it = snaps_.begin(); it != snaps_.end();) {
    if (it->second.generation <= it->second.saved_generation && !it->second.in_flight) {
      it = snaps_.erase(it);
    } else {
      ++it;
    }
  }
}

double LabelSession::FrameTime(int64_t frame) const {
  return rate_hz_ > 0 ? static_cast<double>(frame) / rate_hz_ : 0.0;
}

int64_t LabelSession::TimeFrame(double time_s) const { return std::llround(time_s * rate_hz_); }

long LabelSession::LabelAtFrame(int64_t frame) const {
  if (!model_ || rate_hz_ <= 0) return -1;
  return model_->Find(FrameTime(frame), 0.49 / rate_hz_);
}

bool LabelSession::Push(std::unique_ptr<LabelCommand> command) {
  if (!model_) return false;
  try {
    command->Do(*model_);
  } catch (const std::exception& e) {
    log_->Error(tr("Label edit refused: %1").arg(QString::fromStdString(e.what())));
    return false;
  }
  stack_->push(new Command(this, std::move(command)));  // its first redo() does nothing
  return true;
}

bool LabelSession::AddLabel(int64_t frame, const QString& code) {
  if (!model_) return false;
  if (frame < 0 || frame >= frames_) {
    log_->Error(tr("Label edit refused: frame %1 is outside take %2 (0-%3)")
                    .arg(frame)
                    .arg(QString::fromStdString(take_name_))
                    .arg(frames_ - 1));
    return false;
  }
  return Push(MakeAddLabel(FrameTime(frame), code.toStdString()));
}

bool LabelSession::MoveLabel(long index, int64_t to_frame) {
  if (!model_ || index < 0) return false;
  if (to_frame < 0 || to_frame >= frames_) {
    log_->Error(tr("Label edit refused: frame %1 is outside take %2 (0-%3)")
                    .arg(to_frame)
                    .arg(QString::fromStdString(take_name_))
                    .arg(frames_ - 1));
    return false;
  }
  return Push(MakeMoveLabel(static_cast<size_t>(index), FrameTime(to_frame)));
}

bool LabelSession::Relabel(long index, const QString& code) {
  if (!model_ || index < 0) return false;
  return Push(MakeRelabel(static_cast<size_t>(index), code.toStdString()));
}

bool LabelSession::DeleteLabel(long index) {
  if (!model_ || index < 0) return false;
  return Push(MakeDeleteLabel(static_cast<size_t>(index)));
}

void LabelSession::OnChanged() {
  if (clearing_) return;
  // Not restarted by later changes: an edit reaches a snapshot within the delay
  // even while the user keeps labelling.
  if (model_ && !autosave_timer_.isActive()) autosave_timer_.start();
  emit LabelsChanged();
}

void LabelSession::Snapshot() {
  if (!model_ || !take_) return;
  std::vector<LabelTier> tiers = base_tiers_;
  bool replaced = false;
  for (LabelTier& t : tiers) {
    if (t.name == tier_name_) {
      t = model_->tier();
      replaced = true;
    }
  }
  if (!replaced) tiers.push_back(model_->tier());
  Snap& snap = snaps_[{corpus_, take_name_}];
  snap.tiers = std::move(tiers);
  snap.edited[tier_name_] = model_->tier();
  snap.generation = ++next_generation_;
}

void LabelSession::StartNextSave() {
  for (const auto& [key, snap] : snaps_) {
    if (snap.in_flight) return;  // one save at a time; the next starts when it ends
  }
  for (auto& [key, snap] : snaps_) {
    if (snap.generation > snap.saved_generation) {
      snap.in_flight = true;
      saver_->Post({key.first, key.second, EditedTiers(snap), snap.generation});
      return;
    }
  }
}

bool LabelSession::HasUnsavedEdits() const {
  if (autosave_timer_.isActive()) return true;
  for (const auto& [key, snap] : snaps_) {
    if (snap.generation > snap.saved_generation || snap.in_flight) return true;
  }
  return false;
}

void LabelSession::SaveNow() {
  if (autosave_timer_.isActive()) {
    autosave_timer_.stop();
    Snapshot();
  }
  StartNextSave();
}

void LabelSession::OnSaved(const QString& corpus, const QString& take, long generation, double elapsed_ms) {
  auto it = snaps_.find({corpus.toStdString(), take.toStdString()});
  if (it != snaps_.end()) {
    Snap& snap = it->second;
    snap.in_flight = false;
    snap.saved_generation = std::max(snap.saved_generation, generation);
    if (snap.deferred_logged) {
      log_->Info(tr("Autosave: the labels of take %1 are saved now that the corpus is free.").arg(take));
      snap.deferred_logged = false;
    }
  }
  emit Saved(take, elapsed_ms);
  StartNextSave();
}

void LabelSession::OnFailed(const QString& corpus, const QString& take, long /*generation*/, const QString& message,
                            bool locked) {
  auto it = snaps_.find({corpus.toStdString(), take.toStdString()});
  if (it != snaps_.end()) {
    Snap& snap = it->second;
    snap.in_flight = false;
    if (!snap.deferred_logged) {
      const QString retry = tr("the edits are kept and retried every %1 s").arg(retry_timer_.interval() / 1000.0);
      if (locked) {
        log_->Warning(
            tr("Autosave of take %1 waits: another writer holds the corpus (%2); %3.").arg(take, message, retry));
      } else {
        log_->Error(tr("Autosave of take %1 failed: %2; %3.").arg(take, message, retry));
      }
      snap.deferred_logged = true;
    }
  }
  emit SaveDeferred(take, message);
  retry_timer_.start();
}

}  // namespace csw::gui
