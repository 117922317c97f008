#include "core/markerset.h"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "core/error.h"
#include "tests/testing/testing.h"

namespace csw {
namespace {

const char* kSet = R"({
  "name": "demo",
  "aliases": {"H1": ["HeadFront"]},
  "head_cluster": ["H1", "H2", "H3"],
  "face": ["LipU", "LipL"],
  "throat": [{"marker": "T1", "head_weight": 0.5}, "T2"],
  "forearm_cluster": ["F1", "F2", "F3"],
  "hand_segments": [
    {"name": "palm", "markers": ["P1", "P2", "P3"]},
    {"name": "index1", "parent": "palm", "markers": ["I1a", "I1b"]}
  ],
  "fingertips": ["I1b"],
  "sticks": [["H1", "H2"]]
})";

TEST(MarkerSet, ParsesRolesAndRoundTrips) {
  MarkerSet s = ParseMarkerSet(kSet, "demo.json");
  EXPECT_EQ(s.name, "demo");
  ASSERT_EQ(s.throat.size(), 2u);
  EXPECT_DOUBLE_EQ(*s.throat[0].head_weight, 0.5);
  EXPECT_FALSE(s.throat[1].head_weight.has_value());
  EXPECT_EQ(s.hand_segments[1].parent, "palm");
  EXPECT_EQ(s.AllMarkers().size(), 15u);
  MarkerSet back = ParseMarkerSet(MarkerSetToJson(s));
  EXPECT_EQ(back.AllMarkers(), s.AllMarkers());
  EXPECT_EQ(back.aliases, s.aliases);
  EXPECT_EQ(back.sticks, s.sticks);
}

TEST(MarkerSet, BindsThroughAliasesAndSubjectPrefix) {
  MarkerSet s = ParseMarkerSet(kSet);
  std::vector<std::string> labels = {"Subj:HeadFront", "h2", "H3", "LipU"};
  MarkerBinding b = BindMarkerSet(s, labels, false);
  EXPECT_EQ(b.At("H1"), 0);
  EXPECT_EQ(b.At("H2"), 1);
  EXPECT_EQ(b.At("H3"), 2);
  EXPECT_EQ(b.At("LipU"), 3);
  EXPECT_EQ(b.missing.size(), 11u);
  EXPECT_THROW(b.At("LipL"), InvalidInput);
  try {
    BindMarkerSet(s, labels, true, "take7");
    FAIL() << "expected InvalidInput";
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("take7"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("LipL"), std::string::npos);
  }
}

TEST(MarkerSet, RejectsBrokenDefinitionsWithReasons) {
  EXPECT_THROW(ParseMarkerSet(R"({"head_cluster": ["a", "b"]})"), InvalidInput);
  EXPECT_THROW(ParseMarkerSet(R"({"head_cluster": ["a", "a", "b"]})"), InvalidInput);
  EXPECT_THROW(ParseMarkerSet(R"({"throat": [{"marker": "t", "head_weight": 1.5}]})"), InvalidInput);
  EXPECT_THROW(ParseMarkerSet(R"({"hand_segments": [{"name": "x", "parent": "nope", "markers": ["a", "b"]}]})"),
               InvalidInput);
  EXPECT_THROW(ParseMarkerSet(R"({"colour": "red"})"), InvalidInput);
  try {
    ParseMarkerSet("{\n\"name\": \"x\",\n\"face\": [\"a\",]\n}", "bad.json");
    FAIL() << "expected ParseError";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.where().file, "bad.json");
    EXPECT_EQ(e.where().line.value_or(0), 3);
  }
}

std::string ParseErrorText(const std::string& json_text, const std::string& file) {
  try {
    ParseMarkerSet(json_text, file);
  } catch (const InvalidInput& e) {
    return e.what();
  }
  return "(accepted)";
}

// A marker in two roles is refused at parse time, before any fit, with the file, the marker and both roles.
TEST(MarkerSet, RefusesAMarkerInTwoRoles) {
  EXPECT_EQ(ParseErrorText(R"({"head_cluster": ["FHL", "H2", "H3"], "face": ["LipU", "FHL"]})", "lab.json"),
            "lab.json: marker set: marker \"FHL\" is in both head_cluster and face (a marker plays one role)");
  EXPECT_EQ(ParseErrorText(R"({"face": ["LipU"], "throat": ["LipU"]})", "lab.json"),
            "lab.json: marker set: marker \"LipU\" is in both face and throat (a marker plays one role)");
  EXPECT_EQ(
      ParseErrorText(R"({"head_cluster": ["H1", "H2", "H3"], "forearm_cluster": ["F1", "F2", "H3"]})", "lab.json"),
      "lab.json: marker set: marker \"H3\" is in both head_cluster and forearm_cluster (a marker plays one "
      "role)");
  EXPECT_EQ(ParseErrorText(R"({"forearm_cluster": ["F1", "F2", "F3"],
      "hand_segments": [{"name": "palm", "markers": ["F1", "P2", "P3"]}]})",
                           "lab.json"),
            "lab.json: marker set: marker \"F1\" is in both forearm_cluster and hand segment \"palm\" (a marker "
            "plays one role)");
}

TEST(MarkerSet, RefusesAMarkerInTwoHandSegments) {
  EXPECT_EQ(ParseErrorText(R"({"hand_segments": [
      {"name": "palm", "markers": ["P1", "P2", "P3"]},
      {"name": "index1", "parent": "palm", "markers": ["I1a", "I1b"]},
      {"name": "index2", "parent": "index1", "markers": ["I1b", "I2b"]}]})",
                           "hand.json"),
            "hand.json: marker set: marker \"I1b\" is in both hand segment \"index1\" and hand segment "
            "\"index2\" (a marker plays one role)");
  EXPECT_EQ(ParseErrorText(R"({"hand_segments": [{"name": "palm", "markers": ["P1", "P2", "P1"]}]})", "hand.json"),
            "hand.json: marker set: hand segment \"palm\" lists \"P1\" twice");
}

// fingertips and palm may repeat hand-segment markers (kSet's fingertip I1b is index1's), not other roles'.
TEST(MarkerSet, FingertipsAndPalmShareOnlyHandSegmentMarkers) {
  EXPECT_EQ(ParseErrorText(R"({"hand_segments": [{"name": "palm", "markers": ["P1", "P2", "P3"]}],
      "palm": ["P1", "P2", "P3"], "fingertips": ["T1"]})",
                           "hand.json"),
            "(accepted)");
  EXPECT_EQ(ParseErrorText(R"({"face": ["LipU"], "fingertips": ["LipU"]})", "hand.json"),
            "hand.json: marker set: marker \"LipU\" is in both face and fingertips (fingertips and palm may only "
            "share markers with hand segments)");
  EXPECT_EQ(ParseErrorText(R"({"fingertips": ["T1"], "palm": ["T1"]})", "hand.json"),
            "hand.json: marker set: marker \"T1\" is in both fingertips and palm");
  EXPECT_EQ(ParseErrorText(R"({"throat": ["T1", "T1"]})", "t.json"), "t.json: marker set: throat lists \"T1\" twice");
}

// The marker sets shipped in datasets/markersets follow every rule, the one-role rule included.
TEST(MarkerSet, ShippedMarkerSetsLoad) {
  int files = 0;
  for (const auto& e : std::filesystem::directory_iterator(testing::SourceDir() / "datasets/markersets")) {
    if (e.path().extension() != ".json") continue;
    ++files;
    EXPECT_NO_THROW(LoadMarkerSet(e.path().string())) << e.path();
  }
  EXPECT_GE(files, 1);
}

// LoadMarkerSet reads the file (core ReadTextFile) and names it in errors.
TEST(MarkerSet, LoadFromFileEqualsParseAndNamesBadFiles) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("csw_markerset_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const std::string path = (dir / "set.json").string();
  std::ofstream(path, std::ios::binary) << kSet;
  const MarkerSet loaded = LoadMarkerSet(path);
  const MarkerSet parsed = ParseMarkerSet(kSet, "demo.json");
  EXPECT_EQ(loaded.name, "demo");
  EXPECT_EQ(loaded.AllMarkers(), parsed.AllMarkers());
  EXPECT_EQ(loaded.aliases, parsed.aliases);
  EXPECT_EQ(loaded.sticks, parsed.sticks);
  try {
    LoadMarkerSet((dir / "absent.json").string());
    FAIL() << "missing file accepted";
  } catch (const IoError& e) {
    EXPECT_NE(std::string(e.what()).find("absent.json"), std::string::npos) << e.what();
  }
  std::ofstream(path, std::ios::binary | std::ios::trunc) << "{\n  \"name\": \"x\",\n  oops\n}";
  try {
    LoadMarkerSet(path);
    FAIL() << "broken JSON accepted";
  } catch (const ParseError& e) {
    EXPECT_EQ(e.where().file, path);
    EXPECT_EQ(e.where().line, 3);
  }
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace csw
