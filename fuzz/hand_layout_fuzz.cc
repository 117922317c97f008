// libFuzzer target for the hand_layout JSON section (analysis/keys/
// hand_features.h ParseHandLayout), read as csw keys train reads --layout
// (core/json_util.h ParseJsonText). Any input parses or throws csw::Error
// (ParseError for bad JSON, InvalidInput for a bad section); a layout that
// parses passes HandLayout::Check and reads back identically from
// HandLayoutToJson.
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "analysis/keys/hand_features.h"
#include "core/error.h"
#include "core/json_util.h"
#include "core/markerset.h"

namespace {

// Aborts (a finding) naming the broken invariant's line.
#define CHECK(ok)                                                                     \
  do {                                                                                \
    if (!(ok)) {                                                                      \
      std::fprintf(stderr, "%s:%d: invariant broken: %s\n", __FILE__, __LINE__, #ok); \
      std::abort();                                                                   \
    }                                                                                 \
  } while (0)

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const csw::MarkerSet set = [] {
    csw::MarkerSet s;
    s.name = "fuzz";
    s.head_cluster = {"H1", "H2", "H3"};
    return s;
  }();
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const nlohmann::json doc = csw::ParseJsonText(text, "layout.json");
    const nlohmann::json& section = doc.is_object() && doc.contains("hand_layout") ? doc["hand_layout"] : doc;
    const csw::keys::HandLayout layout = csw::keys::ParseHandLayout(section, set, "layout.json: hand_layout");
    CHECK(layout.Check().empty());
    const csw::keys::HandLayout back =
        csw::keys::ParseHandLayout(csw::keys::HandLayoutToJson(layout), set, "round trip");
    CHECK(back == layout);
  } catch (const csw::Error&) {
  }
  return 0;
}
