// libFuzzer target for the key codes and key-target tiers of core/labels.h.
// The input is split at '\n' into labels; a line starting with '@' and at
// least 9 bytes long carries its time as the 8 raw bytes after the '@'
// (any double: NaN, infinities, negatives), else label i is at 0.1·i s.
// The first byte picks a point (even) or interval (odd) tier.
// Invariants: TryParseKeyCode agrees with KeyCodeProblem, and a code reads
// back from its Text(); ReadKeyTier / ReadKeyTargets / ReadExpectedKeyTier /
// LabelModel either succeed or throw csw::Error, and what ReadKeyTier returns
// is in time order with codes in range; a LabelModel edit that throws leaves
// the model unchanged, and undo gives back the labels exactly.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/labels.h"

namespace {

// Aborts (a finding) naming the broken invariant's line.
#define CHECK(ok)                                                                     \
  do {                                                                                \
    if (!(ok)) {                                                                      \
      std::fprintf(stderr, "%s:%d: invariant broken: %s\n", __FILE__, __LINE__, #ok); \
      std::abort();                                                                   \
    }                                                                                 \
  } while (0)

bool SameLabels(const csw::LabelTier& a, const csw::LabelTier& b) {
  if (a.labels.size() != b.labels.size()) return false;
  for (size_t i = 0; i < a.labels.size(); ++i) {
    const csw::Label& x = a.labels[i];
    const csw::Label& y = b.labels[i];
    // Bitwise, so that NaN times compare equal to themselves.
    if (std::memcmp(&x.start_s, &y.start_s, sizeof(double)) != 0 ||
        std::memcmp(&x.end_s, &y.end_s, sizeof(double)) != 0 || x.text != y.text)
      return false;
  }
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size == 0) return 0;
  const std::string in(reinterpret_cast<const char*>(data) + 1, size - 1);
  csw::LabelTier tier;
  tier.name = "keys";
  tier.kind = (data[0] & 1) != 0 ? csw::LabelTier::Kind::kInterval : csw::LabelTier::Kind::kPoint;
  size_t start = 0;
  for (size_t i = 0; start <= in.size(); ++i) {
    size_t end = in.find('\n', start);
    if (end == std::string::npos) end = in.size();
    std::string line = in.substr(start, end - start);
    double t = 0.1 * static_cast<double>(i);
    if (line.size() >= 9 && line[0] == '@') {
      std::memcpy(&t, line.data() + 1, sizeof t);
      line = line.substr(9);
    }
    // Each component's codes: the text as it is.
    csw::KeyCode code;
    const bool ok = csw::TryParseKeyCode(line, &code);
    CHECK(ok == csw::KeyCodeProblem(line).empty());
    if (ok) {
      CHECK(code.placement >= 0 && code.placement <= csw::kMaxPlacement);
      CHECK(code.shape >= 0 && code.shape <= csw::kMaxShape);
      csw::KeyCode back;
      CHECK(csw::TryParseKeyCode(code.Text(), &back) && back == code);
    }
    const double end_t = tier.kind == csw::LabelTier::Kind::kInterval ? t + 0.05 : t;
    tier.labels.push_back({t, end_t, line});
    tier.end_s = std::isfinite(end_t) && end_t > tier.end_s ? end_t : tier.end_s;
    start = end + 1;
  }
  try {
    const std::vector<csw::KeyMark> marks = csw::ReadKeyTier(tier, "fuzz");
    for (size_t i = 0; i < marks.size(); ++i) {
      CHECK(std::isfinite(marks[i].time_s));
      CHECK(marks[i].code.placement <= csw::kMaxPlacement && marks[i].code.shape <= csw::kMaxShape);
      if (i > 0) CHECK(marks[i - 1].time_s <= marks[i].time_s);
    }
  } catch (const csw::Error&) {
  }
  try {
    csw::LabelTier places = tier;
    places.name = "placement_targets";
    const csw::KeyTargets t = csw::ReadKeyTargets({tier, places}, "fuzz");
    CHECK(t.placement_from_own_tier && t.shape.size() == t.placement.size());
  } catch (const csw::Error&) {
  }
  try {
    csw::ReadExpectedKeyTier(tier, "fuzz");
  } catch (const csw::Error&) {
  }
  // The label model on the point version of the tier, codes unchecked (any
  // text) and checked; every edit with the input's own texts and times.
  csw::LabelTier points = tier;
  points.kind = csw::LabelTier::Kind::kPoint;
  for (bool check : {false, true}) {
    try {
      csw::LabelModel model(points, check, "fuzz");
      csw::LabelHistory history(&model);
      const csw::LabelTier before = model.tier();
      for (size_t i = 0; i < tier.labels.size() && i < 16; ++i) {
        const csw::Label& l = tier.labels[i];
        const csw::LabelTier pre = model.tier();
        try {
          switch (i % 4) {
            case 0:
              history.Push(csw::MakeAddLabel(l.start_s, l.text));
              break;
            case 1:
              history.Push(csw::MakeMoveLabel(i % (model.size() + 1), l.start_s));
              break;
            case 2:
              history.Push(csw::MakeRelabel(i % (model.size() + 1), l.text));
              break;
            default:
              history.Push(csw::MakeDeleteLabel(i % (model.size() + 1)));
          }
        } catch (const csw::InvalidInput&) {
          CHECK(SameLabels(pre, model.tier()));
        }
      }
      while (history.CanUndo()) history.Undo();
      CHECK(SameLabels(before, model.tier()));
    } catch (const csw::Error&) {
    }
  }
  return 0;
}
