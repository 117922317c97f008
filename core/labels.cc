#include "core/labels.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <limits>

#include "core/error.h"

namespace csw {
namespace {

std::string Seconds(double t) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.3f s", t);
  return buf;
}

std::string Trim(const std::string& s) {
  const size_t a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  const size_t b = s.find_last_not_of(" \t\r\n");
  return s.substr(a, b - a + 1);
}

constexpr const char* kCodeHelp = "(a key code is two digits PS: placement 0-5 then shape 0-8, 00 = rest)";

std::string Prefix(const std::string& where) { return where.empty() ? "" : where + ": "; }

}  // namespace

std::string KeyCode::Text() const { return std::to_string(placement) + std::to_string(shape); }

std::string KeyCodeProblem(const std::string& text) {
  const std::string t = Trim(text);
  if (t.empty()) return "empty label";
  if (t.size() != 2 || !std::isdigit(static_cast<unsigned char>(t[0])) ||
      !std::isdigit(static_cast<unsigned char>(t[1])))
    return "not two digits";
  if (t[0] - '0' > kMaxPlacement) return "placement " + std::string(1, t[0]) + " is not 0-5";
  if (t[1] - '0' > kMaxShape) return "shape " + std::string(1, t[1]) + " is not 0-8";
  return "";
}

bool TryParseKeyCode(const std::string& text, KeyCode* code) {
  if (!KeyCodeProblem(text).empty()) return false;
  const std::string t = Trim(text);
  code->placement = t[0] - '0';
  code->shape = t[1] - '0';
  return true;
}

KeyCode ParseKeyCode(const std::string& text, const std::string& where, const std::string& tier, size_t label_index,
                     double time_s) {
  KeyCode c;
  if (TryParseKeyCode(text, &c)) return c;
  throw InvalidInput(Prefix(where) + "tier '" + tier + "': label " + std::to_string(label_index + 1) + " at " +
                     Seconds(time_s) + ": bad key code '" + text + "': " + KeyCodeProblem(text) + " " + kCodeHelp);
}

std::vector<KeyMark> ReadKeyTier(const LabelTier& tier, const std::string& where) {
  const bool intervals = tier.kind == LabelTier::Kind::kInterval;
  std::vector<KeyMark> marks;
  marks.reserve(tier.labels.size());
  for (size_t i = 0; i < tier.labels.size(); ++i) {
    const Label& l = tier.labels[i];
    // An interval tier (ELAN has no point tiers): each labelled interval is a
    // target at its midpoint; empty intervals are the gaps between them.
    if (intervals && Trim(l.text).empty()) continue;
    const double t = intervals ? 0.5 * (l.start_s + l.end_s) : l.start_s;
    if (!std::isfinite(t))
      throw InvalidInput(Prefix(where) + "tier '" + tier.name + "': label " + std::to_string(i + 1) +
                         ": time is not finite");
    marks.push_back({t, ParseKeyCode(l.text, where, tier.name, i, t)});
  }
  std::stable_sort(marks.begin(), marks.end(), [](const KeyMark& a, const KeyMark& b) { return a.time_s < b.time_s; });
  return marks;
}

std::vector<ExpectedKey> ReadExpectedKeyTier(const LabelTier& tier, const std::string& where) {
  if (tier.kind != LabelTier::Kind::kInterval)
    throw InvalidInput(Prefix(where) + "tier '" + tier.name + "' is a point tier; expected keys are an interval tier");
  std::vector<ExpectedKey> keys;
  for (size_t i = 0; i < tier.labels.size(); ++i) {
    const Label& l = tier.labels[i];
    if (Trim(l.text).empty()) continue;  // a pause between keys
    keys.push_back({l.start_s, l.end_s, ParseKeyCode(l.text, where, tier.name, i, l.start_s)});
  }
  return keys;
}

KeyTargets ReadKeyTargets(const std::vector<LabelTier>& tiers, const std::string& where, const KeyTierNames& names) {
  auto find = [&](const std::string& name) -> const LabelTier* {
    for (const LabelTier& t : tiers)
      if (t.name == name) return &t;
    return nullptr;
  };
  const LabelTier* keys = find(names.keys);
  if (!keys) {
    std::string present;
    for (const LabelTier& t : tiers) present += (present.empty() ? "'" : ", '") + t.name + "'";
    throw InvalidInput(Prefix(where) + "no key label tier '" + names.keys +
                       "' (tiers: " + (present.empty() ? "none" : present) + ")");
  }
  KeyTargets out;
  for (const KeyMark& m : ReadKeyTier(*keys, where)) out.shape.push_back({m.time_s, m.code.shape, m.code});
  const LabelTier* place = names.placement.empty() ? nullptr : find(names.placement);
  out.placement_from_own_tier = place != nullptr;
  if (place) {
    for (const KeyMark& m : ReadKeyTier(*place, where)) out.placement.push_back({m.time_s, m.code.placement, m.code});
  } else {
    for (const ComponentTarget& s : out.shape) out.placement.push_back({s.time_s, s.code.placement, s.code});
  }
  return out;
}

KeyTargets ReadKeyTargets(const Take& take, const std::string& where, const KeyTierNames& names) {
  return ReadKeyTargets(take.tiers, where, names);
}

// ---------------------------------------------------------------------------

LabelModel::LabelModel(LabelTier tier, bool check_key_codes, std::string where)
    : tier_(std::move(tier)), check_codes_(check_key_codes), where_(std::move(where)) {
  if (tier_.kind != LabelTier::Kind::kPoint)
    throw InvalidInput(Prefix(where_) + "tier '" + tier_.name + "' is an interval tier; the label model edits points");
  if (check_codes_) ReadKeyTier(tier_, where_);
  std::stable_sort(tier_.labels.begin(), tier_.labels.end(),
                   [](const Label& a, const Label& b) { return a.start_s < b.start_s; });
}

long LabelModel::Find(double time_s, double tolerance_s) const {
  long best = -1;
  double best_d = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < tier_.labels.size(); ++i) {
    const double d = std::abs(tier_.labels[i].start_s - time_s);
    if (d <= tolerance_s && d < best_d) {
      best = static_cast<long>(i);
      best_d = d;
    }
  }
  return best;
}

void LabelModel::CheckText(const std::string& text) const {
  if (!check_codes_) return;
  if (const std::string why = KeyCodeProblem(text); !why.empty())
    throw InvalidInput(Prefix(where_) + "tier '" + tier_.name + "': bad key code '" + text + "': " + why + " " +
                       kCodeHelp);
}

void LabelModel::CheckTime(double time_s) const {
  if (!std::isfinite(time_s) || time_s < tier_.start_s || time_s > tier_.end_s)
    throw InvalidInput(Prefix(where_) + "tier '" + tier_.name + "': time " + Seconds(time_s) + " is outside [" +
                       Seconds(tier_.start_s) + ", " + Seconds(tier_.end_s) + "]");
}

size_t LabelModel::Insert(double time_s, const std::string& text) {
  CheckTime(time_s);
  CheckText(text);
  const auto it = std::upper_bound(tier_.labels.begin(), tier_.labels.end(), time_s,
                                   [](double t, const Label& l) { return t < l.start_s; });
  const size_t index = static_cast<size_t>(it - tier_.labels.begin());
  tier_.labels.insert(it, Label{time_s, time_s, text});
  ++revision_;
  return index;
}

void LabelModel::InsertAt(size_t index, const Label& label) {
  if (index > tier_.labels.size())
    throw InvalidInput(Prefix(where_) + "tier '" + tier_.name + "': no position " + std::to_string(index));
  tier_.labels.insert(tier_.labels.begin() + static_cast<std::ptrdiff_t>(index), label);
  ++revision_;
}

Label LabelModel::RemoveAt(size_t index) {
  if (index >= tier_.labels.size())
    throw InvalidInput(Prefix(where_) + "tier '" + tier_.name + "': no label " + std::to_string(index + 1) + " (" +
                       std::to_string(tier_.labels.size()) + " labels)");
  Label l = tier_.labels[index];
  tier_.labels.erase(tier_.labels.begin() + static_cast<std::ptrdiff_t>(index));
  ++revision_;
  return l;
}

void LabelModel::SetText(size_t index, const std::string& text) {
  if (index >= tier_.labels.size())
    throw InvalidInput(Prefix(where_) + "tier '" + tier_.name + "': no label " + std::to_string(index + 1) + " (" +
                       std::to_string(tier_.labels.size()) + " labels)");
  CheckText(text);
  tier_.labels[index].text = text;
  ++revision_;
}

namespace {

class AddLabel : public LabelCommand {
 public:
  AddLabel(double t, std::string text) : time_s_(t), text_(std::move(text)) {}
  void Do(LabelModel& m) override { index_ = m.Insert(time_s_, text_); }
  void Undo(LabelModel& m) override { m.RemoveAt(index_); }
  std::string Text() const override { return "add key " + text_ + " at " + Seconds(time_s_); }

 private:
  double time_s_;
  std::string text_;
  size_t index_ = 0;
};

class MoveLabel : public LabelCommand {
 public:
  MoveLabel(size_t index, double to_s) : from_index_(index), to_s_(to_s) {}
  void Do(LabelModel& m) override {
    m.CheckTime(to_s_);
    if (from_index_ >= m.size()) m.RemoveAt(from_index_);  // throws the clear error
    old_ = m.RemoveAt(from_index_);
    to_index_ = m.Insert(to_s_, old_.text);
  }
  void Undo(LabelModel& m) override {
    m.RemoveAt(to_index_);
    m.InsertAt(from_index_, old_);
  }
  std::string Text() const override {
    return "move key " + old_.text + " from " + Seconds(old_.start_s) + " to " + Seconds(to_s_);
  }

 private:
  size_t from_index_;
  double to_s_;
  size_t to_index_ = 0;
  Label old_;
};

class Relabel : public LabelCommand {
 public:
  Relabel(size_t index, std::string text) : index_(index), text_(std::move(text)) {}
  void Do(LabelModel& m) override {
    if (index_ >= m.size()) m.RemoveAt(index_);  // throws the clear error
    old_ = m.at(index_);
    m.SetText(index_, text_);
  }
  void Undo(LabelModel& m) override { m.SetText(index_, old_.text); }
  std::string Text() const override {
    return "relabel key " + old_.text + " as " + text_ + " at " + Seconds(old_.start_s);
  }

 private:
  size_t index_;
  std::string text_;
  Label old_;
};

class DeleteLabel : public LabelCommand {
 public:
  explicit DeleteLabel(size_t index) : index_(index) {}
  void Do(LabelModel& m) override { old_ = m.RemoveAt(index_); }
  void Undo(LabelModel& m) override { m.InsertAt(index_, old_); }
  std::string Text() const override { return "delete key " + old_.text + " at " + Seconds(old_.start_s); }

 private:
  size_t index_;
  Label old_;
};

}  // namespace

std::unique_ptr<LabelCommand> MakeAddLabel(double time_s, const std::string& text) {
  return std::make_unique<AddLabel>(time_s, text);
}
std::unique_ptr<LabelCommand> MakeMoveLabel(size_t index, double to_s) {
  return std::make_unique<MoveLabel>(index, to_s);
}
std::unique_ptr<LabelCommand> MakeRelabel(size_t index, const std::string& text) {
  return std::make_unique<Relabel>(index, text);
}
std::unique_ptr<LabelCommand> MakeDeleteLabel(size_t index) { return std::make_unique<DeleteLabel>(index); }

void LabelHistory::Push(std::unique_ptr<LabelCommand> command) {
  command->Do(*model_);  // throws before any change
  commands_.resize(done_);
  if (clean_ > done_) clean_ = std::numeric_limits<size_t>::max();  // the clean state is gone
  commands_.push_back(std::move(command));
  ++done_;
}

void LabelHistory::Undo() {
  if (!CanUndo()) return;
  commands_[--done_]->Undo(*model_);
}

void LabelHistory::Redo() {
  if (!CanRedo()) return;
  commands_[done_++]->Do(*model_);
}

std::string LabelHistory::UndoText() const { return CanUndo() ? commands_[done_ - 1]->Text() : ""; }
std::string LabelHistory::RedoText() const { return CanRedo() ? commands_[done_]->Text() : ""; }

}  // namespace csw
