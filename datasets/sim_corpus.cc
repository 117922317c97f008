// Outputs of the virtual cuer: label tiers, ground truth, files per take, whole
// corpora and the demo corpus.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "core/error.h"
#include "datasets/virtual_cuer.h"
#include "io/c3d/c3d.h"
#include "io/formats/textgrid.h"
#include "io/formats/wav.h"

namespace csw {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

const char* KeyTypeName(KeyType t) {
  switch (t) {
    case KeyType::kRest:
      return "rest";
    case KeyType::kCV:
      return "cv";
    case KeyType::kConsonantAlone:
      return "c";
    case KeyType::kVowelAlone:
      return "v";
  }
  return "";
}

// Rounds to a decimal step (1e-k) for compact, deterministic JSON: the result is
// the double nearest the rounded decimal, which prints in few digits.
double Round(double v, double step) {
  const int digits = std::max(0, static_cast<int>(std::lround(-std::log10(step))));
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  double r = std::strtod(buf, nullptr);
  return r == 0.0 ? 0.0 : r;  // no "-0.0"
}

void ExtendTier(LabelTier* tier, double end) {
  tier->start_s = 0.0;
  if (!tier->labels.empty() && tier->labels.back().end_s < end) {
    if (tier->labels.back().text.empty()) {
      tier->labels.back().end_s = end;
    } else {
      tier->labels.push_back({tier->labels.back().end_s, end, ""});
    }
  }
  tier->end_s = end;
}

json Matrix(const Eigen::MatrixXd& m, double step) {
  json rows = json::array();
  for (Eigen::Index i = 0; i < m.rows(); ++i) {
    json row = json::array();
    for (Eigen::Index j = 0; j < m.cols(); ++j) row.push_back(Round(m(i, j), step));
    rows.push_back(std::move(row));
  }
  return rows;
}

void WriteText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  if (!out) throw IoError(path, "cannot open for writing");
  out << text;
  if (!out.flush()) throw IoError(path, "write failed");
}

}  // namespace

std::vector<LabelTier> SimulationTiers(const SimulationResult& r) {
  const double end = r.take.duration_s();
  std::vector<LabelTier> tiers;
  if (!r.utterance.phones.empty()) {
    tiers = UtteranceTiers(r.utterance);
    for (LabelTier& t : tiers) ExtendTier(&t, end);
  }
  if (r.keys.empty()) return tiers;
  LabelTier keys{"keys", LabelTier::Kind::kPoint, 0.0, end, {}};
  LabelTier places{"placement_targets", LabelTier::Kind::kPoint, 0.0, end, {}};
  LabelTier shape_g{"shape_gestures", LabelTier::Kind::kInterval, 0.0, end, {}};
  LabelTier place_g{"placement_gestures", LabelTier::Kind::kInterval, 0.0, end, {}};
  double last_key = -1.0, last_place = -1.0, shape_end = 0.0, place_end = 0.0;
  const double min_step = 1e-4;
  for (size_t i = 0; i < r.keys.size(); ++i) {
    const GestureTruth& g = r.keys[i];
    const std::string code = g.key.Code();
    double tk = std::max(g.timing.shape_target_s, last_key + min_step);
    keys.labels.push_back({tk, tk, code});
    last_key = tk;
    double tp = std::max(g.timing.placement_target_s, last_place + min_step);
    places.labels.push_back({tp, tp, code});
    last_place = tp;
    if (i == 0) continue;  // leaving rest is the next key's gesture
    double s0 = std::max(g.timing.shape_start_s, shape_end);
    if (g.timing.shape_target_s > s0) {
      shape_g.labels.push_back({s0, g.timing.shape_target_s, std::to_string(g.key.shape)});
      shape_end = g.timing.shape_target_s;
    }
    double p0 = std::max(g.timing.placement_start_s, place_end);
    if (g.timing.placement_target_s > p0) {
      place_g.labels.push_back({p0, g.timing.placement_target_s, std::to_string(g.key.placement)});
      place_end = g.timing.placement_target_s;
    }
  }
  tiers.push_back(keys);
  tiers.push_back(places);
  tiers.push_back(shape_g);
  tiers.push_back(place_g);
  return tiers;
}

std::string TruthToJson(const SimulationResult& r) {
  json j;
  j["format"] = "csw-virtual-truth";
  j["version"] = 1;
  j["name"] = r.take.name;
  j["rate_hz"] = r.take.rate_hz;
  j["frames"] = r.frames();
  j["marker_names"] = r.take.marker_names;
  j["units"] = {{"length", "mm"}, {"angle", "rad"}, {"time", "s"}};
  json ref = json::array();
  for (int i = 0; i < 4; ++i) {
    json row = json::array();
    for (int k = 0; k < 4; ++k) row.push_back(Round(r.head_reference.matrix()(i, k), 1e-9));
    ref.push_back(row);
  }
  j["head_reference"] = ref;
  json keys = json::array();
  for (const GestureTruth& g : r.keys) {
    keys.push_back({{"code", g.key.Code()},
                    {"type", KeyTypeName(g.key.type)},
                    {"placement", g.key.placement},
                    {"shape", g.key.shape},
                    {"a1_s", g.key.a1_s},
                    {"end_s", g.key.end_s},
                    {"consonant_phone", g.key.consonant_phone},
                    {"vowel_phone", g.key.vowel_phone},
                    {"placement_start_s", g.timing.placement_start_s},
                    {"placement_target_s", g.timing.placement_target_s},
                    {"shape_start_s", g.timing.shape_start_s},
                    {"shape_target_s", g.timing.shape_target_s}});
    if (g.posture.size() > 0) {
      json q = json::array();
      for (Eigen::Index j = 0; j < g.posture.size(); ++j) q.push_back(Round(g.posture[j], 1e-5));
      keys.back()["posture"] = q;
      keys.back()["placement_point"] = {Round(g.placement_point.x(), 1e-3), Round(g.placement_point.y(), 1e-3),
                                        Round(g.placement_point.z(), 1e-3)};
    }
  }
  j["keys"] = keys;
  j["phasing"] = PhasingModelToJson(r.phasing);
  json phones = json::array();
  for (const Phone& p : r.utterance.phones)
    phones.push_back({{"ipa", p.ipa}, {"start_s", p.start_s}, {"end_s", p.end_s}});
  j["phones"] = phones;
  j["joint_names"] = r.joint_angles.cols() > 0 ? r.joint_names : std::vector<std::string>{};
  j["joint_angles"] = Matrix(r.joint_angles, 1e-4);
  std::vector<std::string> art;
  for (int k = 0; k < kNumArticulatory; ++k) art.emplace_back(ArticulatoryName(k));
  // (precision: 1e-4 rad, 1e-3 mm, 1e-5 rad of head rotation: far below the capture noise)
  j["articulatory_names"] = art;
  j["articulation"] = Matrix(r.articulation, 1e-3);
  j["head_motion"] = Matrix(r.head_motion, 1e-5);
  j["forearm_pose"] = Matrix(r.forearm_pose, 1e-4);
  // Occlusion mask as runs per marker: [first_frame, end_frame, state].
  json mask = json::object();
  const int64_t nm = r.clean.markers();
  for (int64_t m = 0; m < nm; ++m) {
    json runs = json::array();
    int64_t f = 0;
    while (f < r.frames()) {
      uint8_t s = r.state[static_cast<size_t>(f * nm + m)];
      int64_t g = f;
      while (g < r.frames() && r.state[static_cast<size_t>(g * nm + m)] == s) ++g;
      if (s != kVisible) runs.push_back({f, g, s == kOccluded ? "occluded" : "dropped"});
      f = g;
    }
    if (!runs.empty()) mask[r.take.marker_names[static_cast<size_t>(m)]] = runs;
  }
  j["hidden"] = mask;
  json swaps = json::array();
  for (const LabelSwap& s : r.swaps)
    swaps.push_back({{"a", r.take.marker_names[static_cast<size_t>(s.marker_a)]},
                     {"b", r.take.marker_names[static_cast<size_t>(s.marker_b)]},
                     {"first_frame", s.first_frame},
                     {"end_frame", s.end_frame}});
  j["label_swaps"] = swaps;
  return j.dump();
}

void WriteTakeFiles(const SimulationResult& result, const SimulateOptions& options, const std::string& dir) {
  const fs::path base = fs::path(dir) / result.take.name;
  C3dWriteOptions c3d;
  if (options.int16_c3d) {
    c3d.storage = C3dWriteOptions::Storage::kInt16;
    c3d.point_scale_mm = options.c3d_scale_mm;
  }
  WriteC3d(base.string() + ".c3d", result.take, c3d);
  if (!result.take.audio.samples.empty()) WriteWav(base.string() + ".wav", result.take.audio);
  WriteTextGrid(base.string() + ".TextGrid", result.take.tiers, 0.0, result.take.duration_s());
  if (options.write_truth) WriteText(base.string() + ".truth.json", TruthToJson(result) + "\n");
  if (options.write_clean) {
    Take clean = result.take;
    clean.markers = result.clean;
    clean.name = result.take.name + ".clean";
    WriteC3d(base.string() + ".clean.c3d", clean, c3d);
  }
}

std::vector<int> AllShapeTransitions() {
  // Hierholzer's algorithm on the complete directed graph of shapes 1-8,
  // visiting each vertex's successors in increasing order: deterministic.
  std::vector<std::vector<int>> next(9);
  for (int a = 1; a <= 8; ++a)
    for (int b = 8; b >= 1; --b)
      if (a != b) next[static_cast<size_t>(a)].push_back(b);  // back() = smallest
  std::vector<int> stack = {1}, circuit;
  while (!stack.empty()) {
    int v = stack.back();
    if (!next[static_cast<size_t>(v)].empty()) {
      int w = next[static_cast<size_t>(v)].back();
      next[static_cast<size_t>(v)].pop_back();
      stack.push_back(w);
    } else {
      circuit.push_back(v);
      stack.pop_back();
    }
  }
  std::reverse(circuit.begin(), circuit.end());
  return circuit;
}

std::vector<std::string> ShippedSentences() {
  std::vector<std::string> out;
  std::istringstream in(DefaultSentencesText());
  std::string line;
  while (std::getline(in, line)) {
    auto b = line.find_first_not_of(" \t\r");
    if (b == std::string::npos || line[b] == '#') continue;
    auto e = line.find_last_not_of(" \t\r");
    out.push_back(line.substr(b, e - b + 1));
  }
  return out;
}

std::vector<VisemeItem> VisemeItems() {
  std::vector<VisemeItem> items;
  items.push_back({"visemes_vowels", "a. é. è. i. eau. u. ou. eux. heure. on. an. un. hein."});
  // Consonants spelled so that espeak-ng reads /VCV/: p b m f v t d n s z ʃ ʒ l ʁ k g ɲ j w ɥ.
  struct Context {
    const char* name;
    const char* v;
  };
  const char* cons[][2] = {{"p", "p"}, {"b", "b"}, {"m", "m"},  {"f", "f"},  {"v", "v"},  {"t", "t"},
                           {"d", "d"}, {"n", "n"}, {"s", "ss"}, {"z", "z"},  {"ʃ", "ch"}, {"ʒ", "j"},
                           {"l", "l"}, {"ʁ", "r"}, {"k", "k"},  {"g", "gu"}, {"ɲ", "gn"}};
  for (Context c : {Context{"a", "a"}, Context{"i", "i"}, Context{"u", "ou"}}) {
    std::string text;
    for (const auto& k : cons) {
      std::string spelling = k[1];
      if (std::string(c.v) == "a" && spelling == "gu") spelling = "g";
      if (!text.empty()) text += ", ";
      text += std::string(c.v) + spelling + c.v;
    }
    items.push_back({std::string("visemes_vcv_") + c.name, text + "."});
  }
  return items;
}

std::vector<std::string> SimulateCorpus(const SimulateOptions& options, const std::string& out_dir,
                                        Progress& progress) {
  if (std::string why = options.Check(); !why.empty()) throw InvalidInput("simulate options: " + why);
  VirtualCuer cuer(options);
  std::error_code ec;
  fs::create_directories(out_dir, ec);
  if (ec) throw IoError(out_dir, "cannot create the output folder: " + ec.message());
  WriteText((fs::path(out_dir) / "markerset.json").string(), MarkerSetToJson(cuer.MakeMarkerSet(options.kind)));
  std::vector<std::string> names;
  const std::string stage = std::string("simulate ") + CorpusKindName(options.kind);
  progress.Update(stage, 0.0);
  switch (options.kind) {
    case CorpusKind::kShapes: {
      int takes = std::max(1, options.count);
      for (int i = 0; i < takes; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "shapes_%02d", i + 1);
        SimulationResult r = cuer.SimulateShapes(name, AllShapeTransitions());
        WriteTakeFiles(r, options, out_dir);
        names.emplace_back(name);
        progress.Update(stage, static_cast<double>(i + 1) / takes);
      }
      break;
    }
    case CorpusKind::kVisemes: {
      std::vector<VisemeItem> items = VisemeItems();
      for (size_t i = 0; i < items.size(); ++i) {
        SimulationResult r = cuer.SimulateSentence(items[i].name, items[i].text, false);
        WriteTakeFiles(r, options, out_dir);
        names.push_back(items[i].name);
        progress.Update(stage, static_cast<double>(i + 1) / static_cast<double>(items.size()));
      }
      break;
    }
    case CorpusKind::kSentences: {
      std::vector<std::string> sentences = options.sentences.empty() ? ShippedSentences() : options.sentences;
      size_t n = sentences.size();
      if (options.count > 0) n = std::min(n, static_cast<size_t>(options.count));
      for (size_t i = 0; i < n; ++i) {
        char name[32];
        std::snprintf(name, sizeof name, "sentence_%03zu", i + 1);
        SimulationResult r = cuer.SimulateSentence(name, sentences[i], true);
        WriteTakeFiles(r, options, out_dir);
        names.emplace_back(name);
        progress.Update(stage, static_cast<double>(i + 1) / static_cast<double>(n));
      }
      break;
    }
  }
  return names;
}

void GenerateDemoCorpus(const std::string& out_dir, uint64_t seed, int sentences, Progress& progress) {
  SimulateOptions o;
  o.seed = seed;
  GenerateDemoCorpus(out_dir, o, sentences, progress);
}

void GenerateDemoCorpus(const std::string& out_dir, const SimulateOptions& base, int sentences, Progress& progress) {
  SimulateOptions o = base;
  o.write_truth = false;  // ground truth is for tests, which simulate their own takes
  o.int16_c3d = true;     // keeps shapes + visemes + 20 sentences under 20 MB
  for (CorpusKind kind : {CorpusKind::kShapes, CorpusKind::kVisemes, CorpusKind::kSentences}) {
    o.kind = kind;
    o.count = kind == CorpusKind::kSentences ? sentences : 0;
    SimulateCorpus(o, (fs::path(out_dir) / CorpusKindName(kind)).string(), progress);
  }
}

}  // namespace csw
