#include "core/markerset.h"

#include <algorithm>
#include <cctype>
#include <nlohmann/json.hpp>
#include <set>

#include "core/error.h"
#include "core/file_util.h"
#include "core/json_util.h"

namespace csw {

using nlohmann::json;

namespace {

std::vector<std::string> StringList(const json& j, const std::string& key, const std::string& file) {
  std::vector<std::string> out;
  if (!j.contains(key)) return out;
  const json& v = j.at(key);
  if (!v.is_array()) throw InvalidInput(file + ": \"" + key + "\" must be an array of marker names");
  for (const json& s : v) {
    if (!s.is_string()) throw InvalidInput(file + ": \"" + key + "\" must contain only strings");
    out.push_back(s.get<std::string>());
  }
  return out;
}

std::string Normalise(const std::string& label) {
  std::string s = label;
  auto colon = s.rfind(':');
  if (colon != std::string::npos) s = s.substr(colon + 1);
  std::string out;
  for (char c : s) {
    if (!std::isspace(static_cast<unsigned char>(c)))
      out += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  }
  return out;
}

void Validate(const MarkerSet& set, const std::string& file) {
  auto fail = [&](const std::string& what) { throw InvalidInput(file + ": marker set: " + what); };
  if (!set.head_cluster.empty() && set.head_cluster.size() < 3)
    fail("head_cluster needs at least 3 markers (has " + std::to_string(set.head_cluster.size()) + ")");
  if (!set.forearm_cluster.empty() && set.forearm_cluster.size() < 3)
    fail("forearm_cluster needs at least 3 markers (has " + std::to_string(set.forearm_cluster.size()) + ")");
  auto check_unique = [&](const std::vector<std::string>& v, const std::string& role) {
    std::set<std::string> seen;
    for (const auto& m : v) {
      if (m.empty()) fail(role + " has an empty marker name");
      if (!seen.insert(m).second) fail(role + " lists \"" + m + "\" twice");
    }
  };
  check_unique(set.head_cluster, "head_cluster");
  check_unique(set.forearm_cluster, "forearm_cluster");
  check_unique(set.face, "face");
  check_unique(set.fingertips, "fingertips");
  check_unique(set.palm, "palm");
  for (const auto& t : set.throat) {
    if (t.head_weight && (*t.head_weight < 0.0 || *t.head_weight >= 1.0))
      fail("throat marker \"" + t.marker + "\" head_weight must be in [0, 1)");
  }
  std::set<std::string> segments;
  for (const auto& s : set.hand_segments) {
    if (s.name.empty()) fail("a hand segment has no name");
    if (!s.parent.empty() && !segments.count(s.parent))
      fail("hand segment \"" + s.name + "\" names parent \"" + s.parent + "\" which is not defined before it");
    if (!segments.insert(s.name).second) fail("hand segment \"" + s.name + "\" is defined twice");
    if (s.markers.size() < 2) fail("hand segment \"" + s.name + "\" needs at least 2 markers");
    if (s.parent.empty() && s.markers.size() < 3)
      fail("hand segment \"" + s.name + "\" has no parent and needs at least 3 markers");
  }
  // Each marker plays one role: the rigid clusters, face, throat and every hand segment are disjoint
  // (the face model keeps head, face and throat markers in one layout; the hand model gives each marker
  // one segment). fingertips and palm name markers for the hand distances: they may repeat markers of
  // the hand segments, but no other role's, and not each other's.
  std::map<std::string, std::string> owner;  // marker -> role
  auto claim = [&](const std::string& m, const std::string& role) {
    auto [it, ok] = owner.emplace(m, role);
    if (!ok && it->second != role)
      fail("marker \"" + m + "\" is in both " + it->second + " and " + role + " (a marker plays one role)");
  };
  for (const auto& m : set.head_cluster) claim(m, "head_cluster");
  for (const auto& m : set.face) claim(m, "face");
  for (const auto& t : set.throat) claim(t.marker, "throat");
  for (const auto& m : set.forearm_cluster) claim(m, "forearm_cluster");
  for (const auto& s : set.hand_segments) {
    std::set<std::string> in_segment;
    for (const auto& m : s.markers) {
      if (m.empty()) fail("hand segment \"" + s.name + "\" has an empty marker name");
      if (!in_segment.insert(m).second) fail("hand segment \"" + s.name + "\" lists \"" + m + "\" twice");
      claim(m, "hand segment \"" + s.name + "\"");
    }
  }
  std::map<std::string, std::string> distance_owner;  // fingertips and palm
  for (const auto* list : {&set.fingertips, &set.palm}) {
    const std::string role = list == &set.fingertips ? "fingertips" : "palm";
    for (const auto& m : *list) {
      auto it = owner.find(m);
      if (it != owner.end() && it->second.rfind("hand segment", 0) != 0)
        fail("marker \"" + m + "\" is in both " + it->second + " and " + role +
             " (fingertips and palm may only share markers with hand segments)");
      auto [d, ok] = distance_owner.emplace(m, role);
      if (!ok && d->second != role) fail("marker \"" + m + "\" is in both " + d->second + " and " + role);
    }
  }
  std::set<std::string> throat_seen;
  for (const auto& t : set.throat) {
    if (t.marker.empty()) fail("throat has an empty marker name");
    if (!throat_seen.insert(t.marker).second) fail("throat lists \"" + t.marker + "\" twice");
  }
  // Every alias target must be unique across canonical names.
  std::map<std::string, std::string> alias_owner;
  for (const auto& [canon, alts] : set.aliases) {
    for (const auto& a : alts) {
      auto [it, ok] = alias_owner.emplace(a, canon);
      if (!ok && it->second != canon)
        fail("alias \"" + a + "\" is given to both \"" + it->second + "\" and \"" + canon + "\"");
    }
  }
}

}  // namespace

std::vector<std::string> MarkerSet::AllMarkers() const {
  std::vector<std::string> out;
  std::set<std::string> seen;
  auto add = [&](const std::string& m) {
    if (seen.insert(m).second) out.push_back(m);
  };
  for (const auto& m : head_cluster) add(m);
  for (const auto& m : face) add(m);
  for (const auto& t : throat) add(t.marker);
  for (const auto& m : forearm_cluster) add(m);
  for (const auto& s : hand_segments)
    for (const auto& m : s.markers) add(m);
  for (const auto& m : palm) add(m);
  for (const auto& m : fingertips) add(m);
  for (const auto& [a, b] : sticks) {
    add(a);
    add(b);
  }
  return out;
}

MarkerSet ParseMarkerSet(const std::string& json_text, const std::string& file) {
  json j = ParseJsonText(json_text, file);
  const std::string where = file.empty() ? std::string("<marker set>") : file;
  if (!j.is_object()) throw InvalidInput(where + ": marker set must be a JSON object");
  static const std::set<std::string> kKeys = {
      "name", "description", "format",        "version",    "aliases", "head_cluster", "forearm_cluster",
      "face", "throat",      "hand_segments", "fingertips", "palm",    "sticks"};
  for (auto it = j.begin(); it != j.end(); ++it) {
    if (!kKeys.count(it.key())) throw InvalidInput(where + ": marker set: unknown key \"" + it.key() + "\"");
  }
  MarkerSet set;
  try {
    set.name = j.value("name", "");
    set.description = j.value("description", "");
    if (j.contains("aliases")) {
      for (auto it = j["aliases"].begin(); it != j["aliases"].end(); ++it) {
        set.aliases[it.key()] = it.value().get<std::vector<std::string>>();
      }
    }
    set.head_cluster = StringList(j, "head_cluster", where);
    set.forearm_cluster = StringList(j, "forearm_cluster", where);
    set.face = StringList(j, "face", where);
    set.fingertips = StringList(j, "fingertips", where);
    set.palm = StringList(j, "palm", where);
    if (j.contains("throat")) {
      for (const json& t : j["throat"]) {
        ThroatMarker tm;
        if (t.is_string()) {
          tm.marker = t.get<std::string>();
        } else {
          tm.marker = t.at("marker").get<std::string>();
          if (t.contains("head_weight") && !t["head_weight"].is_null()) tm.head_weight = t["head_weight"].get<double>();
        }
        set.throat.push_back(tm);
      }
    }
    if (j.contains("hand_segments")) {
      for (const json& s : j["hand_segments"]) {
        HandSegment seg;
        seg.name = s.at("name").get<std::string>();
        seg.parent = s.value("parent", "");
        seg.markers = s.at("markers").get<std::vector<std::string>>();
        set.hand_segments.push_back(seg);
      }
    }
    if (j.contains("sticks")) {
      for (const json& s : j["sticks"]) {
        auto v = s.get<std::vector<std::string>>();
        if (v.size() != 2) throw InvalidInput(where + ": marker set: each stick joins exactly 2 markers");
        set.sticks.emplace_back(v[0], v[1]);
      }
    }
  } catch (const json::exception& e) {
    throw InvalidInput(where + ": marker set: " + e.what());
  }
  Validate(set, where);
  return set;
}

MarkerSet LoadMarkerSet(const std::string& path) { return ParseMarkerSet(ReadTextFile(path), path); }

std::string MarkerSetToJson(const MarkerSet& set) {
  json j;
  j["format"] = "csw-markerset";
  j["version"] = 1;
  j["name"] = set.name;
  if (!set.description.empty()) j["description"] = set.description;
  if (!set.aliases.empty()) j["aliases"] = set.aliases;
  j["head_cluster"] = set.head_cluster;
  j["forearm_cluster"] = set.forearm_cluster;
  j["face"] = set.face;
  json throat = json::array();
  for (const auto& t : set.throat) {
    json tj = {{"marker", t.marker}};
    if (t.head_weight) tj["head_weight"] = *t.head_weight;
    throat.push_back(tj);
  }
  j["throat"] = throat;
  json segs = json::array();
  for (const auto& s : set.hand_segments) {
    json sj = {{"name", s.name}, {"markers", s.markers}};
    if (!s.parent.empty()) sj["parent"] = s.parent;
    segs.push_back(sj);
  }
  j["hand_segments"] = segs;
  j["fingertips"] = set.fingertips;
  j["palm"] = set.palm;
  json sticks = json::array();
  for (const auto& [a, b] : set.sticks) sticks.push_back({a, b});
  j["sticks"] = sticks;
  return j.dump(2) + "\n";
}

int MarkerBinding::At(const std::string& canonical) const {
  auto it = index.find(canonical);
  if (it == index.end()) throw InvalidInput("marker \"" + canonical + "\" is not in this take");
  return it->second;
}

std::vector<int> MarkerBinding::Columns(const std::vector<std::string>& canonical) const {
  std::vector<int> out;
  out.reserve(canonical.size());
  for (const auto& c : canonical) out.push_back(At(c));
  return out;
}

MarkerBinding BindMarkerSet(const MarkerSet& set, const std::vector<std::string>& labels, bool require_all,
                            const std::string& take_name) {
  MarkerBinding b;
  std::map<std::string, int> exact, loose;
  for (size_t i = 0; i < labels.size(); ++i) {
    exact.emplace(labels[i], static_cast<int>(i));
    loose.emplace(Normalise(labels[i]), static_cast<int>(i));
  }
  for (const auto& canon : set.AllMarkers()) {
    std::vector<std::string> candidates = {canon};
    auto a = set.aliases.find(canon);
    if (a != set.aliases.end()) candidates.insert(candidates.end(), a->second.begin(), a->second.end());
    int found = -1;
    for (const auto& c : candidates) {
      if (auto it = exact.find(c); it != exact.end()) {
        found = it->second;
        break;
      }
    }
    if (found < 0) {
      for (const auto& c : candidates) {
        if (auto it = loose.find(Normalise(c)); it != loose.end()) {
          found = it->second;
          break;
        }
      }
    }
    if (found >= 0)
      b.index[canon] = found;
    else
      b.missing.push_back(canon);
  }
  if (require_all && !b.missing.empty()) {
    std::string list;
    for (size_t i = 0; i < b.missing.size() && i < 12; ++i) list += (i ? ", " : "") + b.missing[i];
    if (b.missing.size() > 12) list += ", ... (" + std::to_string(b.missing.size()) + " in all)";
    throw InvalidInput((take_name.empty() ? std::string("take") : take_name) + ": marker set \"" + set.name +
                       "\" names markers the take does not have: " + list);
  }
  return b;
}

}  // namespace csw
