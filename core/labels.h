#pragma once
// Target-frame labels of Cued Speech keys (../shared/docs/cued-speech.md, "Key
// codes"): a point tier (default "keys") whose marks are two-digit codes "PS",
// placement P 0-5 then shape S 0-8; "00" is rest; placement 0 with a shape is that
// shape in free space (the shapes corpus). Shape and placement targets need not
// fall on the same frame: a second point tier (default "placement_targets") may
// hold the placement targets.
//
// Also a plain-C++ label model (no Qt) with undoable edit commands (add, move,
// relabel, delete) and a linear undo/redo history. The GUI wraps each command in
// a QUndoCommand (redo() -> Do, undo() -> Undo, text() -> Text) on a QUndoStack;
// LabelHistory is the same thing for the CLI and the tests.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/take.h"

namespace csw {

inline constexpr int kMaxPlacement = 5;
inline constexpr int kMaxShape = 8;

struct KeyCode {
  int placement = 0;  // 0-5
  int shape = 0;      // 0-8
  bool IsRest() const { return placement == 0 && shape == 0; }
  bool IsFreeSpaceShape() const { return placement == 0 && shape != 0; }
  std::string Text() const;  // "PS"
  bool operator==(const KeyCode& o) const { return placement == o.placement && shape == o.shape; }
  bool operator!=(const KeyCode& o) const { return !(*this == o); }
};

// "PS" with P in 0-5 and S in 0-8 (surrounding white space allowed); false otherwise.
bool TryParseKeyCode(const std::string& text, KeyCode* code);
// Why `text` is not a key code ("" when it is one), for messages.
std::string KeyCodeProblem(const std::string& text);

// One clear error for a bad label: "<where>: tier 'keys': label 3 at 1.250 s:
// bad key code 'x7': <problem> (a key code is two digits PS: placement 0-5 then
// shape 0-8, 00 = rest)". `label_index` is 0-based (written 1-based).
KeyCode ParseKeyCode(const std::string& text, const std::string& where, const std::string& tier, size_t label_index,
                     double time_s);

struct KeyMark {
  double time_s = 0.0;
  KeyCode code;
};

// The marks of a point tier of key codes, in time order. An interval tier is
// read too (ELAN has no point tiers; io/formats/eaf.h returns a point tier only
// when every annotation has zero duration): each non-empty interval is one mark
// at its midpoint, empty intervals are skipped. Throws InvalidInput (one error,
// for the first bad label, as ParseKeyCode) when a label is not a key code or a
// time is not finite.
std::vector<KeyMark> ReadKeyTier(const LabelTier& tier, const std::string& where);

// One key of an `expected_keys` interval tier (csw cue, synth/phone_symbols.h):
// the key's span from its A1 to its end.
struct ExpectedKey {
  double start_s = 0.0;
  double end_s = 0.0;
  KeyCode code;
};
// The keys of an expected-keys interval tier in order, rests included; empty
// intervals (pauses) are skipped. Throws InvalidInput for a point tier and as
// ParseKeyCode for a bad label.
std::vector<ExpectedKey> ReadExpectedKeyTier(const LabelTier& tier, const std::string& where);

// A target of one component: the frame time and the class (shape 0-8 or
// placement 0-5), with the full code it came from.
struct ComponentTarget {
  double time_s = 0.0;
  int value = 0;
  KeyCode code;
};

struct KeyTargets {
  std::vector<ComponentTarget> shape;      // at the `keys` tier's marks
  std::vector<ComponentTarget> placement;  // at the placement tier's marks when present, else at `keys`
  bool placement_from_own_tier = false;    // the placement tier was present
};

struct KeyTierNames {
  std::string keys = "keys";
  std::string placement = "placement_targets";  // "" = use the keys tier for both
};

// The per-component target lists of a take. Throws InvalidInput naming `where`,
// the tier and the tiers present when the keys tier is missing, and as
// ReadKeyTier for bad labels of either tier.
KeyTargets ReadKeyTargets(const Take& take, const std::string& where, const KeyTierNames& names = {});
KeyTargets ReadKeyTargets(const std::vector<LabelTier>& tiers, const std::string& where,
                          const KeyTierNames& names = {});

// ---------------------------------------------------------------------------
// Label model and undoable edits.

// A point tier kept in time order (equal times keep their insertion order).
// With key codes checked (the default), every text put in it must be a key code.
class LabelModel {
 public:
  // Throws as ReadKeyTier when `check_key_codes` and a label is not a key code,
  // InvalidInput when the tier is not a point tier. Labels are sorted by time.
  explicit LabelModel(LabelTier tier, bool check_key_codes = true, std::string where = "");

  const LabelTier& tier() const { return tier_; }
  size_t size() const { return tier_.labels.size(); }
  const Label& at(size_t index) const { return tier_.labels.at(index); }
  bool checks_key_codes() const { return check_codes_; }
  // Index of the mark nearest to time_s within tolerance_s, or -1.
  long Find(double time_s, double tolerance_s) const;
  // Incremented by every change (a view can tell it must redraw).
  long revision() const { return revision_; }

  // Throw InvalidInput (nothing changed) for a bad code, a time that is not
  // finite or outside [tier start, tier end], or a bad index.
  void CheckText(const std::string& text) const;
  void CheckTime(double time_s) const;
  // Low-level edits used by the commands.
  size_t Insert(double time_s, const std::string& text);  // returns the index it went to
  void InsertAt(size_t index, const Label& label);        // exact position (undo)
  Label RemoveAt(size_t index);
  void SetText(size_t index, const std::string& text);

 private:
  LabelTier tier_;
  bool check_codes_;
  std::string where_;
  long revision_ = 0;
};

// One undoable edit. Do() may throw InvalidInput before changing anything;
// Undo() restores exactly the labels before Do().
class LabelCommand {
 public:
  virtual ~LabelCommand() = default;
  virtual void Do(LabelModel& model) = 0;
  virtual void Undo(LabelModel& model) = 0;
  virtual std::string Text() const = 0;  // "add key 24 at 1.250 s"
};

std::unique_ptr<LabelCommand> MakeAddLabel(double time_s, const std::string& text);
// The mark at `index` (in the model when the command is made) moves to `to_s`.
std::unique_ptr<LabelCommand> MakeMoveLabel(size_t index, double to_s);
std::unique_ptr<LabelCommand> MakeRelabel(size_t index, const std::string& text);
std::unique_ptr<LabelCommand> MakeDeleteLabel(size_t index);

// A linear history: Push does the command and drops the redo branch.
class LabelHistory {
 public:
  explicit LabelHistory(LabelModel* model) : model_(model) {}
  // Does the command; on InvalidInput the history and the model are unchanged
  // and the error propagates.
  void Push(std::unique_ptr<LabelCommand> command);
  bool CanUndo() const { return done_ > 0; }
  bool CanRedo() const { return done_ < commands_.size(); }
  void Undo();                   // no-op when nothing to undo
  void Redo();                   // no-op when nothing to redo
  std::string UndoText() const;  // "" when none
  std::string RedoText() const;
  size_t count() const { return commands_.size(); }
  size_t index() const { return done_; }  // commands done
  // The labels are unchanged since the last MarkClean() (e.g. after a save).
  bool IsClean() const { return done_ == clean_; }
  void MarkClean() { clean_ = done_; }

 private:
  LabelModel* model_;
  std::vector<std::unique_ptr<LabelCommand>> commands_;
  size_t done_ = 0;
  size_t clean_ = 0;
};

}  // namespace csw
