#pragma once
// Marker-set definition: which captured markers play which role (docs/markerset-format.md).
// One definition serves several recordings through label aliases.
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace csw {

struct ThroatMarker {
  std::string marker;
  std::optional<double> head_weight;  // in [0, 1); absent = fitted by the face model
};

// A rigid hand segment (palm, or one phalanx) whose frame is built from its markers.
struct HandSegment {
  std::string name;                  // "palm", "index1", ...
  std::string parent;                // "" = forearm
  std::vector<std::string> markers;  // ≥ 2 (with the parent's markers, ≥ 3 define a frame)
};

struct MarkerSet {
  std::string name;
  std::string description;
  // canonical name -> alternative labels found in recordings
  std::map<std::string, std::vector<std::string>> aliases;
  std::vector<std::string> head_cluster;     // ≥ 3 rigid markers on the head
  std::vector<std::string> forearm_cluster;  // ≥ 3 rigid markers on the forearm
  std::vector<std::string> face;             // face markers (lips, jaw, cheeks, ...)
  std::vector<ThroatMarker> throat;
  std::vector<HandSegment> hand_segments;
  std::vector<std::string> fingertips;
  std::vector<std::string> palm;
  std::vector<std::pair<std::string, std::string>> sticks;  // drawn as lines

  // Every canonical marker name that some role uses, each once, in role order.
  std::vector<std::string> AllMarkers() const;
};

// Parses a marker-set JSON document. Throws ParseError (file, line) for malformed
// JSON and InvalidInput for a definition that breaks a rule (names the rule).
MarkerSet ParseMarkerSet(const std::string& json_text, const std::string& file = "");
MarkerSet LoadMarkerSet(const std::string& path);
std::string MarkerSetToJson(const MarkerSet& set);

// The marker set applied to one take's labels: canonical name -> column index.
struct MarkerBinding {
  std::map<std::string, int> index;  // canonical name -> take column
  std::vector<std::string> missing;  // canonical names with no column
  // Column of a canonical name; throws InvalidInput when unbound.
  int At(const std::string& canonical) const;
  std::vector<int> Columns(const std::vector<std::string>& canonical) const;
};

// Matches labels (exact, then aliases, then case-insensitive with any "Subject:" prefix
// removed). When require_all, throws InvalidInput listing every unbound marker.
MarkerBinding BindMarkerSet(const MarkerSet& set, const std::vector<std::string>& labels, bool require_all,
                            const std::string& take_name = "");

}  // namespace csw
