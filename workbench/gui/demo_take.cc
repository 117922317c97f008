#include "workbench/gui/demo_take.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "core/error.h"

namespace csw::gui {

namespace {

using Vec = std::array<double, 3>;
constexpr double kPi = std::numbers::pi;

const char* kFingers[5] = {"thumb", "index", "middle", "ring", "little"};
const char* kJoints[3] = {"mcp", "pip", "tip"};

struct Syllable {
  double start, end;
  std::string text;
  int position;     // LfPC hand position 0..4
  double openness;  // jaw opening of the vowel, 0..1
};

const char* kPositions[5] = {"side", "chin", "mouth", "cheek", "throat"};
// Hand targets in the head frame (mm; x forward, y left, z up).
const Vec kTargets[5] = {{40, -140, -40}, {105, -5, -95}, {112, -30, -48}, {88, -78, -18}, {55, 0, -150}};

std::vector<Syllable> MakeSyllables(double seconds) {
  static const char* consonants[] = {"b", "d", "m", "k", "s", "t", "l", "p", "n", "f"};
  static const char* vowels[] = {"a", "o", "i", "e", "u"};
  static const int vowel_position[] = {0, 1, 2, 3, 4};
  static const double vowel_open[] = {1.0, 0.75, 0.35, 0.6, 0.45};
  std::vector<Syllable> out;
  uint32_t state = 12345;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return (state >> 8) / static_cast<double>(1u << 24);
  };
  double t = 0.4;
  while (t < seconds - 0.5) {
    double dur = 0.2 + 0.12 * next();
    int c = static_cast<int>(next() * 10) % 10, v = static_cast<int>(next() * 5) % 5;
    out.push_back({t, t + dur, std::string(consonants[c]) + vowels[v], vowel_position[v], vowel_open[v]});
    t += dur;
    if (next() < 0.18) t += 0.15 + 0.25 * next();  // a pause between phrases
  }
  return out;
}

double Smooth(double x) {
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

Vec Rotate(double yaw, double pitch, const Vec& v) {
  // pitch about y, then yaw about z.
  double cp = std::cos(pitch), sp = std::sin(pitch), cy = std::cos(yaw), sy = std::sin(yaw);
  Vec a{cp * v[0] + sp * v[2], v[1], -sp * v[0] + cp * v[2]};
  return {cy * a[0] - sy * a[1], sy * a[0] + cy * a[1], a[2]};
}

int FaceCount(int markers) { return markers - 25; }

}  // namespace

MarkerSet DemoMarkerSet(int markers) {
  MarkerSet set;
  set.name = "synthetic-cuer";
  set.description = "Marker set of the synthetic demo take (csw-workbench tour and benchmark)";
  set.head_cluster = {"head_front", "head_left", "head_right", "head_top"};
  set.forearm_cluster = {"forearm_1", "forearm_2", "forearm_3"};
  set.palm = {"palm_1", "palm_2", "palm_3"};
  set.hand_segments.push_back({"palm", "", {"palm_1", "palm_2", "palm_3"}});
  for (const char* f : kFingers) {
    set.fingertips.push_back(std::string(f) + "_tip");
    set.sticks.push_back({"palm_1", std::string(f) + "_mcp"});
    set.sticks.push_back({std::string(f) + "_mcp", std::string(f) + "_pip"});
    set.sticks.push_back({std::string(f) + "_pip", std::string(f) + "_tip"});
  }
  set.sticks.push_back({"forearm_1", "palm_1"});
  set.sticks.push_back({"forearm_1", "forearm_2"});
  set.sticks.push_back({"forearm_2", "forearm_3"});
  set.sticks.push_back({"palm_1", "palm_2"});
  set.sticks.push_back({"palm_2", "palm_3"});
  set.sticks.push_back({"palm_3", "palm_1"});
  set.sticks.push_back({"head_front", "head_top"});
  set.sticks.push_back({"head_left", "head_top"});
  set.sticks.push_back({"head_right", "head_top"});
  int face = FaceCount(markers);
  int cols = std::max(1, static_cast<int>(std::lround(std::sqrt(face * 1.4))));
  for (int i = 0; i < face; ++i) {
    set.face.push_back("face_" + std::to_string(i + 1));
    if ((i + 1) % cols != 0 && i + 1 < face)
      set.sticks.push_back({set.face[static_cast<size_t>(i)], "face_" + std::to_string(i + 2)});
  }
  return set;
}

Take MakeDemoTake(const DemoTakeOptions& o) {
  if (o.markers < 30 || o.rate_hz <= 0 || o.seconds <= 0)
    throw InvalidInput("demo take: needs >= 30 markers, a positive rate and duration");
  Take take;
  take.name = o.name;
  take.rate_hz = o.rate_hz;
  take.first_frame = 1;
  take.source_units = "mm";
  MarkerSet set = DemoMarkerSet(o.markers);
  take.marker_names = set.head_cluster;
  take.marker_names.insert(take.marker_names.end(), set.forearm_cluster.begin(), set.forearm_cluster.end());
  take.marker_names.insert(take.marker_names.end(), set.palm.begin(), set.palm.end());
  for (const char* f : kFingers)
    for (const char* j : kJoints) take.marker_names.push_back(std::string(f) + "_" + j);
  take.marker_names.insert(take.marker_names.end(), set.face.begin(), set.face.end());

  std::vector<Syllable> syl = MakeSyllables(o.seconds);
  auto frames = static_cast<int64_t>(std::llround(o.seconds * o.rate_hz));
  int markers = static_cast<int>(take.marker_names.size());
  take.markers.Resize(frames, markers);

  // Head-frame face grid (front half of a sphere), and which rows follow the jaw.
  int face = FaceCount(o.markers);
  int cols = std::max(1, static_cast<int>(std::lround(std::sqrt(face * 1.4))));
  int rows = (face + cols - 1) / cols;
  std::vector<Vec> face_pts;
  std::vector<double> jaw_weight;
  for (int i = 0; i < face; ++i) {
    int r = i / cols, c = i % cols;
    double az = (-55.0 + 110.0 * (cols > 1 ? c / double(cols - 1) : 0.5)) * kPi / 180;
    double el = (25.0 - 85.0 * (rows > 1 ? r / double(rows - 1) : 0.5)) * kPi / 180;
    face_pts.push_back({95 * std::cos(el) * std::cos(az), 95 * std::cos(el) * std::sin(az), 95 * std::sin(el)});
    jaw_weight.push_back(std::clamp((-el * 180 / kPi - 15) / 45, 0.0, 1.0));
  }
  const Vec head_pts[4] = {{98, 0, 55}, {5, 82, 65}, {5, -82, 65}, {15, 0, 112}};

  size_t cursor = 0;
  for (int64_t f = 0; f < frames; ++f) {
    double t = static_cast<double>(f) / o.rate_hz;
    while (cursor + 1 < syl.size() && syl[cursor].end < t) ++cursor;
    // Jaw opening and hand target from the syllables around t.
    double open = 0;
    for (size_t s = cursor > 0 ? cursor - 1 : 0; s < std::min(syl.size(), cursor + 2); ++s) {
      if (t >= syl[s].start && t <= syl[s].end) {
        double u = (t - syl[s].start) / (syl[s].end - syl[s].start);
        open = std::max(open, syl[s].openness * std::pow(std::sin(kPi * u), 2));
      }
    }
    // The hand leads the voice: it travels to syllable s's target during
    // [start - 0.18, start - 0.02] (the cue is "reached" 20 ms before the sound).
    Vec hand_target = kTargets[0];
    if (!syl.empty()) {
      size_t s = 0;
      while (s + 1 < syl.size() && syl[s + 1].start - 0.18 <= t) ++s;
      const Vec& to = kTargets[syl[s].position];
      const Vec& from = s > 0 ? kTargets[syl[s - 1].position] : kTargets[0];
      double a = Smooth((t - (syl[s].start - 0.18)) / 0.16);
      for (int i = 0; i < 3; ++i)
        hand_target[static_cast<size_t>(i)] =
            from[static_cast<size_t>(i)] + a * (to[static_cast<size_t>(i)] - from[static_cast<size_t>(i)]);
    }
    double yaw = 0.09 * std::sin(2 * kPi * 0.21 * t), pitch = 0.05 * std::sin(2 * kPi * 0.33 * t + 1) + 0.08 * open;
    Vec head{0.0 + 6 * std::sin(2 * kPi * 0.13 * t), 0.0, 1600 + 4 * std::sin(2 * kPi * 0.4 * t)};
    auto to_lab = [&](const Vec& p) {
      Vec r = Rotate(yaw, pitch * 0.3, p);
      return Vec{head[0] + r[0], head[1] + r[1], head[2] + r[2]};
    };
    auto put = [&](int k, const Vec& p) {
      float* out = take.markers.at(f, k);
      out[0] = static_cast<float>(p[0]);
      out[1] = static_cast<float>(p[1]);
      out[2] = static_cast<float>(p[2]);
    };
    int k = 0;
    for (const Vec& p : head_pts) put(k++, to_lab(p));
    // Hand: wrist at the target, palm facing the face, forearm hanging down and out.
    Vec wrist = to_lab(hand_target);
    for (int i = 1; i <= 3; ++i) put(k++, {wrist[0] + 25.0 * i, wrist[1] - 30.0 * i, wrist[2] - 85.0 * i});
    put(k++, wrist);
    put(k++, {wrist[0] + 5, wrist[1] + 40, wrist[2] + 55});
    put(k++, {wrist[0] + 5, wrist[1] - 15, wrist[2] + 70});
    double curl = 0.5 + 0.5 * std::sin(2 * kPi * 0.7 * t);
    for (int fi = 0; fi < 5; ++fi) {
      double spread = (fi - 2) * 16.0;
      Vec base{wrist[0] + 8, wrist[1] + spread + (fi == 0 ? 30 : 0), wrist[2] + (fi == 0 ? 40 : 80)};
      for (int j = 0; j < 3; ++j) {
        double along = 25.0 * (j + 1) * (fi == 0 ? 0.8 : 1.0);
        double bend = curl * 12.0 * j;
        Vec p{base[0] + bend, base[1] + (fi == 0 ? along * 0.7 : 0), base[2] + (fi == 0 ? along * 0.4 : along) - bend};
        put(k, p);
        // Occlusions: the little finger's tip hides behind the hand now and then.
        bool hidden =
            (fi == 4 && j == 2 && std::sin(2 * kPi * 0.37 * t) > 0.8) || (fi == 3 && j == 1 && std::fmod(t, 4.0) > 3.6);
        if (hidden) take.markers.SetMissing(f, k);
        ++k;
      }
    }
    for (int i = 0; i < face; ++i) {
      Vec p = face_pts[static_cast<size_t>(i)];
      p[2] -= 14.0 * open * jaw_weight[static_cast<size_t>(i)];
      p[0] += 3.0 * open * jaw_weight[static_cast<size_t>(i)];
      put(k++, to_lab(p));
    }
  }

  // Tiers.
  LabelTier words{"words", LabelTier::Kind::kInterval, 0.0, o.seconds, {}};
  LabelTier syllables{"syllables", LabelTier::Kind::kInterval, 0.0, o.seconds, {}};
  LabelTier cues{"cues", LabelTier::Kind::kPoint, 0.0, o.seconds, {}};
  double prev_end = 0.0;
  for (size_t s = 0; s < syl.size(); ++s) {
    if (syl[s].start > prev_end) syllables.labels.push_back({prev_end, syl[s].start, ""});
    syllables.labels.push_back({syl[s].start, syl[s].end, syl[s].text});
    cues.labels.push_back({syl[s].start - 0.02, syl[s].start - 0.02, kPositions[syl[s].position]});
    prev_end = syl[s].end;
  }
  if (prev_end < o.seconds) syllables.labels.push_back({prev_end, o.seconds, ""});
  // Words: runs of 2-3 syllables without a pause.
  prev_end = 0.0;
  for (size_t s = 0; s < syl.size();) {
    size_t n = 1;
    std::string text = syl[s].text;
    while (n < 2 + (s % 2) && s + n < syl.size() && syl[s + n].start - syl[s + n - 1].end < 1e-9) {
      text += syl[s + n].text;
      ++n;
    }
    if (syl[s].start > prev_end) words.labels.push_back({prev_end, syl[s].start, ""});
    words.labels.push_back({syl[s].start, syl[s + n - 1].end, text});
    prev_end = syl[s + n - 1].end;
    s += n;
  }
  if (prev_end < o.seconds) words.labels.push_back({prev_end, o.seconds, ""});
  take.tiers = {words, syllables, cues};

  // Audio: a voiced source (harmonics of a gliding f0) shaped by the jaw opening,
  // with a short noise burst at each syllable onset.
  if (o.audio_rate_hz > 0) {
    take.audio.rate_hz = o.audio_rate_hz;
    take.audio.channels = 1;
    auto n = static_cast<int64_t>(std::llround(o.seconds * o.audio_rate_hz));
    take.audio.samples.assign(static_cast<size_t>(n), 0.0f);
    double phase = 0;
    uint32_t noise = 777;
    size_t s = 0;
    for (int64_t i = 0; i < n; ++i) {
      double t = static_cast<double>(i) / o.audio_rate_hz;
      while (s + 1 < syl.size() && syl[s].end < t) ++s;
      double env = 0, burst = 0;
      if (!syl.empty() && t >= syl[s].start && t <= syl[s].end) {
        double u = (t - syl[s].start) / (syl[s].end - syl[s].start);
        env = syl[s].openness * std::pow(std::sin(kPi * u), 2);
        if (t - syl[s].start < 0.03) burst = 0.25 * (1 - (t - syl[s].start) / 0.03);
      }
      double f0 = 120 + 20 * std::sin(2 * kPi * 0.5 * t);
      phase += 2 * kPi * f0 / o.audio_rate_hz;
      if (phase > 2 * kPi) phase -= 2 * kPi;
      double v = 0;
      for (int h = 1; h <= 5; ++h) v += std::sin(h * phase) / h;
      noise = noise * 1664525u + 1013904223u;
      double white = (noise >> 8) / static_cast<double>(1u << 23) - 1.0;
      take.audio.samples[static_cast<size_t>(i)] = static_cast<float>(0.45 * env * v + burst * white + 0.004 * white);
    }
  }
  take.provenance.csw_version = CSW_VERSION;
  take.provenance.warnings.push_back("synthetic take made by csw-workbench's demo generator");
  return take;
}

}  // namespace csw::gui
