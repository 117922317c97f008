#include "io/formats/eaf.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <optional>
#include <pugixml.hpp>
#include <set>
#include <string_view>
#include <unordered_map>

#include "core/error.h"
#include "core/file_util.h"
#include "io/formats/text_util.h"

namespace csw {

namespace {

using formats_internal::FormatDouble;

struct Annotation {
  std::string id;
  size_t tier = 0;
  bool alignable = true;
  std::string slot1, slot2;   // alignable
  std::string ref, previous;  // reference
  std::string value;
  int64_t offset = 0;
  // Resolution.
  enum class State { kTodo, kBusy, kDone, kFailed } state = State::kTodo;
  double start_ms = 0, end_ms = 0;
  std::string why;  // when failed
  size_t group_pos = 0, group_size = 1;
};

struct RawTier {
  std::string name;
  std::vector<size_t> annotations;
};

// Text of an element: its PCDATA and CDATA children, concatenated.
std::string ElementText(const pugi::xml_node& node) {
  std::string s;
  for (pugi::xml_node c = node.first_child(); c; c = c.next_sibling()) {
    if (c.type() == pugi::node_pcdata || c.type() == pugi::node_cdata) s += c.value();
  }
  return s;
}

// Nearest aligned slot along one direction of a tier's chain of annotations:
// (time in ms, number of annotation steps), or steps = -1 when there is none.
using Reach = std::pair<double, int64_t>;

class EafReader {
 public:
  EafReader(const std::string& path, std::vector<std::string>* warnings) : path_(path), warnings_(warnings) {}

  std::vector<LabelTier> Read() {
    bytes_ = formats_internal::ReadFileBytes(path_);
    if (bytes_.empty()) throw ParseError({path_, 0, std::nullopt}, "file is empty; not an EAF file");
    pugi::xml_document doc;
    pugi::xml_parse_result result =
        doc.load_buffer(bytes_.data(), bytes_.size(), pugi::parse_default | pugi::parse_ws_pcdata_single);
    if (!result) {
      throw ParseError(At(result.offset), std::string("malformed XML: ") + result.description());
    }
    pugi::xml_node root = doc.document_element();
    if (std::string_view(root.name()) != "ANNOTATION_DOCUMENT") {
      throw ParseError(At(root ? root.offset_debug() : 0), "root element is <" +
                                                               std::string(root.name()).substr(0, 40) +
                                                               ">, not <ANNOTATION_DOCUMENT>; not an EAF file");
    }
    if (pugi::xml_node header = root.child("HEADER")) {
      std::string units = header.attribute("TIME_UNITS").as_string("milliseconds");
      if (units != "milliseconds") {
        Warn("EAF: TIME_UNITS is '" + units + "'; values read as milliseconds");
      }
    }
    ReadSlots(root);
    ReadTiers(root);
    ResolveAlignable();
    for (size_t i = 0; i < annotations_.size(); ++i) Resolve(i, 0);
    return BuildTiers();
  }

 private:
  Location At(ptrdiff_t offset) const {
    return {path_, static_cast<int64_t>(offset), formats_internal::LineOfOffset(bytes_, static_cast<int64_t>(offset))};
  }
  void Warn(const std::string& w) {
    if (warnings_) warnings_->push_back(w);
  }

  void ReadSlots(const pugi::xml_node& root) {
    for (pugi::xml_node order : root.children("TIME_ORDER")) {
      for (pugi::xml_node slot : order.children("TIME_SLOT")) {
        std::string id = slot.attribute("TIME_SLOT_ID").as_string();
        std::optional<double> ms;
        if (pugi::xml_attribute value = slot.attribute("TIME_VALUE")) {
          ms = formats_internal::ParseFiniteDouble(formats_internal::Trim(value.as_string()));
          if (!ms || *ms < 0) {
            throw ParseError(At(slot.offset_debug()), "time slot '" + id.substr(0, 40) + "': TIME_VALUE '" +
                                                          std::string(value.as_string()).substr(0, 40) +
                                                          "' is not a finite non-negative number");
          }
          max_ms_ = std::max(max_ms_, *ms);
        }
        if (!slots_.emplace(id, ms).second) {
          Warn("EAF: duplicate time slot id '" + id + "'; the first is used");
        }
      }
    }
  }

  void ReadTiers(const pugi::xml_node& root) {
    std::set<std::string> tier_names;
    for (pugi::xml_node tier_node : root.children("TIER")) {
      RawTier tier;
      tier.name = tier_node.attribute("TIER_ID").as_string();
      if (!tier_names.insert(tier.name).second) {
        Warn("EAF: duplicate TIER_ID '" + tier.name + "'; both tiers are kept");
      }
      const size_t tier_index = tiers_.size();
      for (pugi::xml_node wrapper : tier_node.children("ANNOTATION")) {
        for (pugi::xml_node a = wrapper.first_child(); a; a = a.next_sibling()) {
          if (a.type() != pugi::node_element) continue;
          std::string_view kind = a.name();
          Annotation ann;
          ann.tier = tier_index;
          ann.offset = static_cast<int64_t>(a.offset_debug());
          ann.id = a.attribute("ANNOTATION_ID").as_string();
          ann.value = ElementText(a.child("ANNOTATION_VALUE"));
          if (kind == "ALIGNABLE_ANNOTATION") {
            ann.alignable = true;
            ann.slot1 = a.attribute("TIME_SLOT_REF1").as_string();
            ann.slot2 = a.attribute("TIME_SLOT_REF2").as_string();
            for (const std::string* s : {&ann.slot1, &ann.slot2}) {
              if (!slots_.count(*s)) {
                throw ParseError(At(a.offset_debug()), "annotation '" + ann.id.substr(0, 40) +
                                                           "' refers to unknown time slot '" + s->substr(0, 40) + "'");
              }
            }
          } else if (kind == "REF_ANNOTATION") {
            ann.alignable = false;
            ann.ref = a.attribute("ANNOTATION_REF").as_string();
            ann.previous = a.attribute("PREVIOUS_ANNOTATION").as_string();
          } else {
            continue;
          }
          const size_t index = annotations_.size();
          if (!by_id_.emplace(ann.id, index).second) {
            Warn("EAF: duplicate ANNOTATION_ID '" + ann.id + "'; references use the first");
          }
          tier.annotations.push_back(index);
          annotations_.push_back(std::move(ann));
        }
      }
      tiers_.push_back(std::move(tier));
    }
  }

  // Times of alignable annotations, interpolating unaligned slots along the
  // tier's chain (slot1 -> slot2 of each annotation).
  void ResolveAlignable() {
    for (const RawTier& tier : tiers_) {
      std::unordered_map<std::string, std::string> next, prev;
      for (size_t idx : tier.annotations) {
        const Annotation& a = annotations_[idx];
        if (!a.alignable) continue;
        next.emplace(a.slot1, a.slot2);
        prev.emplace(a.slot2, a.slot1);
      }
      const int64_t limit = static_cast<int64_t>(tier.annotations.size()) + 1;
      std::unordered_map<std::string, Reach> back_memo, fwd_memo;
      auto walk = [&](const std::string& start, const std::unordered_map<std::string, std::string>& dir,
                      std::unordered_map<std::string, Reach>& memo) -> Reach {
        std::vector<const std::string*> path;
        const std::string* cur = &start;
        Reach reach{0.0, -1};
        int64_t steps = 0;
        while (true) {
          const std::optional<double>& ms = slots_.at(*cur);
          if (ms) {
            reach = {*ms, 0};
            break;
          }
          if (auto m = memo.find(*cur); m != memo.end()) {
            reach = m->second;
            break;
          }
          path.push_back(cur);
          auto it = dir.find(*cur);
          if (it == dir.end() || ++steps > limit) break;
          cur = &it->second;
        }
        for (size_t i = path.size(); i-- > 0;) {
          if (reach.second >= 0) ++reach.second;
          memo[*path[i]] = reach;
        }
        return memo.count(start) ? memo[start] : reach;
      };
      auto slot_time = [&](const std::string& slot, std::string* why) -> std::optional<double> {
        const std::optional<double>& ms = slots_.at(slot);
        if (ms) return ms;
        Reach back = walk(slot, prev, back_memo);
        Reach fwd = walk(slot, next, fwd_memo);
        if (back.second < 0 || fwd.second < 0) {
          *why = "unaligned time slot '" + slot + "' has no aligned slot on both sides in its tier";
          return std::nullopt;
        }
        const double frac = static_cast<double>(back.second) / static_cast<double>(back.second + fwd.second);
        return back.first + (fwd.first - back.first) * frac;
      };
      for (size_t idx : tier.annotations) {
        Annotation& a = annotations_[idx];
        if (!a.alignable) continue;
        std::optional<double> t1 = slot_time(a.slot1, &a.why);
        std::optional<double> t2 = t1 ? slot_time(a.slot2, &a.why) : std::nullopt;
        if (!t1 || !t2) {
          a.state = Annotation::State::kFailed;
          continue;
        }
        if (*t1 > *t2) {
          if (slots_.at(a.slot1) && slots_.at(a.slot2)) {
            throw ParseError(At(a.offset), "annotation '" + a.id.substr(0, 40) + "' starts at " + FormatDouble(*t1) +
                                               " ms, after its end " + FormatDouble(*t2) + " ms");
          }
          a.state = Annotation::State::kFailed;
          a.why = "interpolated times are reversed";
          continue;
        }
        a.start_ms = *t1;
        a.end_ms = *t2;
        a.state = Annotation::State::kDone;
      }
    }
    // Sibling groups of reference annotations: (tier, parent) -> ordered members.
    for (const RawTier& tier : tiers_) {
      std::unordered_map<std::string, std::vector<size_t>> groups;
      std::vector<std::string> order;
      for (size_t idx : tier.annotations) {
        const Annotation& a = annotations_[idx];
        if (a.alignable) continue;
        auto [it, inserted] = groups.try_emplace(a.ref);
        if (inserted) order.push_back(a.ref);
        it->second.push_back(idx);
      }
      bool warned = false;
      for (const std::string& parent : order) {
        std::vector<size_t>& members = groups[parent];
        std::vector<size_t> chain = OrderByPrevious(members);
        if (chain.size() != members.size()) {
          if (!warned) {
            Warn("EAF: tier '" + tier.name +
                 "': PREVIOUS_ANNOTATION links do not order the "
                 "annotations under '" +
                 parent + "'; file order used");
            warned = true;
          }
          chain = members;
        }
        for (size_t k = 0; k < chain.size(); ++k) {
          annotations_[chain[k]].group_pos = k;
          annotations_[chain[k]].group_size = chain.size();
        }
      }
    }
  }

  std::vector<size_t> OrderByPrevious(const std::vector<size_t>& members) const {
    if (members.size() == 1) return members;
    std::unordered_map<std::string, size_t> after;  // previous id -> member
    std::set<std::string> ids;
    for (size_t idx : members) ids.insert(annotations_[idx].id);
    std::vector<size_t> heads;
    for (size_t idx : members) {
      const Annotation& a = annotations_[idx];
      if (a.previous.empty() || !ids.count(a.previous)) {
        heads.push_back(idx);
      } else if (!after.emplace(a.previous, idx).second) {
        return {};
      }
    }
    if (heads.size() != 1) return {};
    std::vector<size_t> chain{heads[0]};
    while (chain.size() <= members.size()) {
      auto it = after.find(annotations_[chain.back()].id);
      if (it == after.end()) break;
      chain.push_back(it->second);
    }
    return chain;
  }

  void Resolve(size_t index, int depth) {
    Annotation& a = annotations_[index];
    if (a.state == Annotation::State::kDone || a.state == Annotation::State::kFailed) return;
    if (a.state == Annotation::State::kBusy) {
      a.state = Annotation::State::kFailed;
      a.why = "reference cycle";
      return;
    }
    if (depth > 64) {
      a.state = Annotation::State::kFailed;
      a.why = "reference chain deeper than 64";
      return;
    }
    a.state = Annotation::State::kBusy;
    auto it = by_id_.find(a.ref);
    if (it == by_id_.end()) {
      a.state = Annotation::State::kFailed;
      a.why = "refers to unknown annotation '" + a.ref + "'";
      return;
    }
    Resolve(it->second, depth + 1);
    Annotation& parent = annotations_[it->second];
    Annotation& self = annotations_[index];
    if (self.state == Annotation::State::kFailed) return;  // set by a cycle below
    if (parent.state != Annotation::State::kDone) {
      self.state = Annotation::State::kFailed;
      self.why = "its parent '" + parent.id + "' could not be aligned";
      return;
    }
    const double span = parent.end_ms - parent.start_ms;
    const double n = static_cast<double>(self.group_size);
    self.start_ms = parent.start_ms + span * static_cast<double>(self.group_pos) / n;
    self.end_ms = self.group_pos + 1 == self.group_size
                      ? parent.end_ms
                      : parent.start_ms + span * static_cast<double>(self.group_pos + 1) / n;
    self.state = Annotation::State::kDone;
  }

  std::vector<LabelTier> BuildTiers() {
    for (const Annotation& a : annotations_) {
      if (a.state == Annotation::State::kDone) max_ms_ = std::max(max_ms_, a.end_ms);
    }
    std::vector<LabelTier> out;
    for (const RawTier& raw : tiers_) {
      LabelTier tier;
      tier.name = raw.name;
      tier.start_s = 0.0;
      tier.end_s = max_ms_ / 1000.0;
      int64_t failed = 0;
      const Annotation* first_failed = nullptr;
      for (size_t idx : raw.annotations) {
        const Annotation& a = annotations_[idx];
        if (a.state != Annotation::State::kDone) {
          if (failed++ == 0) first_failed = &a;
          continue;
        }
        tier.labels.push_back({a.start_ms / 1000.0, a.end_ms / 1000.0, a.value});
      }
      if (failed > 0) {
        Warn("EAF: tier '" + raw.name + "': " + std::to_string(failed) + " of " +
             std::to_string(raw.annotations.size()) + " annotation(s) could not be aligned and " +
             (tier.labels.empty() ? "the tier is skipped" : "were skipped") + " (first: '" + first_failed->id +
             "': " + first_failed->why + ")");
        if (tier.labels.empty()) continue;
      }
      std::stable_sort(tier.labels.begin(), tier.labels.end(),
                       [](const Label& x, const Label& y) { return x.start_s < y.start_s; });
      const bool all_points = !tier.labels.empty() && std::all_of(tier.labels.begin(), tier.labels.end(),
                                                                  [](const Label& l) { return l.start_s == l.end_s; });
      tier.kind = all_points ? LabelTier::Kind::kPoint : LabelTier::Kind::kInterval;
      out.push_back(std::move(tier));
    }
    return out;
  }

  const std::string& path_;
  std::vector<std::string>* warnings_;
  std::string bytes_;
  std::unordered_map<std::string, std::optional<double>> slots_;
  std::vector<Annotation> annotations_;
  std::unordered_map<std::string, size_t> by_id_;
  std::vector<RawTier> tiers_;
  double max_ms_ = 0.0;
};

std::string MimeTypeFor(const std::string& url) {
  std::string ext = std::filesystem::path(url).extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".wav") return "audio/x-wav";
  if (ext == ".mp3") return "audio/mpeg";
  if (ext == ".mp4") return "video/mp4";
  if (ext == ".mov") return "video/quicktime";
  if (ext == ".mpg" || ext == ".mpeg") return "video/mpeg";
  return "unknown";
}

}  // namespace

std::vector<LabelTier> ReadEaf(const std::string& path, std::vector<std::string>* warnings) {
  EafReader reader(path, warnings);
  return reader.Read();
}

void WriteEaf(const std::string& path, const std::vector<LabelTier>& tiers, const std::string& media_url) {
  struct Slot {
    int64_t ms;
    size_t order;
    std::string id;
  };
  struct Ann {
    size_t slot1, slot2;
    const std::string* text;
  };
  std::vector<Slot> slots;
  std::vector<std::vector<Ann>> tier_anns(tiers.size());
  for (size_t t = 0; t < tiers.size(); ++t) {
    bool has_previous = false;  // the previous written label ended where this one may start
    int64_t previous_end_ms = 0;
    size_t previous_end_slot = 0;
    for (const Label& l : tiers[t].labels) {
      if (!std::isfinite(l.start_s) || !std::isfinite(l.end_s) || l.start_s < 0 || l.end_s < 0) {
        throw InvalidInput("WriteEaf: tier \"" + tiers[t].name + "\" has a negative or non-finite time");
      }
      if (l.start_s > l.end_s) {
        throw InvalidInput("WriteEaf: tier \"" + tiers[t].name + "\" has a label with start > end");
      }
      if (l.end_s > 9e12) throw InvalidInput("WriteEaf: time too large");
      if (l.text.empty()) {
        has_previous = false;
        continue;
      }
      const int64_t start_ms = std::llround(l.start_s * 1000.0);
      const int64_t end_ms = std::llround(l.end_s * 1000.0);
      size_t s1;
      if (has_previous && previous_end_ms == start_ms && start_ms != end_ms) {
        s1 = previous_end_slot;
      } else {
        s1 = slots.size();
        slots.push_back({start_ms, slots.size(), ""});
      }
      size_t s2 = slots.size();
      slots.push_back({end_ms, slots.size(), ""});
      tier_anns[t].push_back({s1, s2, &l.text});
      has_previous = true;
      previous_end_ms = end_ms;
      previous_end_slot = s2;
    }
  }
  std::vector<size_t> sorted(slots.size());
  for (size_t i = 0; i < sorted.size(); ++i) sorted[i] = i;
  std::stable_sort(sorted.begin(), sorted.end(), [&](size_t a, size_t b) { return slots[a].ms < slots[b].ms; });
  for (size_t k = 0; k < sorted.size(); ++k) slots[sorted[k]].id = "ts" + std::to_string(k + 1);

  pugi::xml_document doc;
  pugi::xml_node decl = doc.append_child(pugi::node_declaration);
  decl.append_attribute("version") = "1.0";
  decl.append_attribute("encoding") = "UTF-8";
  pugi::xml_node root = doc.append_child("ANNOTATION_DOCUMENT");
  root.append_attribute("AUTHOR") = "";
  root.append_attribute("DATE") = UtcNow(UtcZone::kOffset).c_str();
  root.append_attribute("FORMAT") = "3.0";
  root.append_attribute("VERSION") = "3.0";
  root.append_attribute("xmlns:xsi") = "http://www.w3.org/2001/XMLSchema-instance";
  root.append_attribute("xsi:noNamespaceSchemaLocation") = "http://www.mpi.nl/tools/elan/EAFv3.0.xsd";
  pugi::xml_node header = root.append_child("HEADER");
  header.append_attribute("MEDIA_FILE") = "";
  header.append_attribute("TIME_UNITS") = "milliseconds";
  if (!media_url.empty()) {
    std::string url = media_url;
    if (url.find("://") == std::string::npos) {
      url = "file://" + std::filesystem::absolute(url).lexically_normal().string();
    }
    pugi::xml_node media = header.append_child("MEDIA_DESCRIPTOR");
    media.append_attribute("MEDIA_URL") = url.c_str();
    media.append_attribute("MIME_TYPE") = MimeTypeFor(url).c_str();
  }
  size_t annotation_count = 0;
  for (const auto& anns : tier_anns) annotation_count += anns.size();
  pugi::xml_node property = header.append_child("PROPERTY");
  property.append_attribute("NAME") = "lastUsedAnnotationId";
  property.text() = std::to_string(annotation_count).c_str();

  pugi::xml_node order = root.append_child("TIME_ORDER");
  for (size_t k : sorted) {
    pugi::xml_node slot = order.append_child("TIME_SLOT");
    slot.append_attribute("TIME_SLOT_ID") = slots[k].id.c_str();
    slot.append_attribute("TIME_VALUE") = std::to_string(slots[k].ms).c_str();
  }
  std::set<std::string> used_names;
  size_t next_id = 1;
  for (size_t t = 0; t < tiers.size(); ++t) {
    const std::string base = tiers[t].name.empty() ? "tier " + std::to_string(t + 1) : tiers[t].name;
    std::string name = base;
    for (int k = 2; !used_names.insert(name).second; ++k) {
      name = base + " (" + std::to_string(k) + ")";
    }
    pugi::xml_node tier = root.append_child("TIER");
    tier.append_attribute("LINGUISTIC_TYPE_REF") = "default-lt";
    tier.append_attribute("TIER_ID") = name.c_str();
    for (const Ann& a : tier_anns[t]) {
      pugi::xml_node al = tier.append_child("ANNOTATION").append_child("ALIGNABLE_ANNOTATION");
      al.append_attribute("ANNOTATION_ID") = ("a" + std::to_string(next_id++)).c_str();
      al.append_attribute("TIME_SLOT_REF1") = slots[a.slot1].id.c_str();
      al.append_attribute("TIME_SLOT_REF2") = slots[a.slot2].id.c_str();
      al.append_child("ANNOTATION_VALUE").text() = a.text->c_str();
    }
  }
  pugi::xml_node type = root.append_child("LINGUISTIC_TYPE");
  type.append_attribute("GRAPHIC_REFERENCES") = "false";
  type.append_attribute("LINGUISTIC_TYPE_ID") = "default-lt";
  type.append_attribute("TIME_ALIGNABLE") = "true";
  if (!doc.save_file(path.c_str(), "    ", pugi::format_default, pugi::encoding_utf8)) {
    throw IoError(path, "cannot write the EAF file");
  }
}

}  // namespace csw
