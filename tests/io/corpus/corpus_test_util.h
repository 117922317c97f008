#pragma once
// Takes built from known components for the corpus tests, and an exact
// (NaN-aware, bitwise for floats) comparison.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/take.h"

namespace csw::testing {

// Smooth, deterministic marker trajectories (mm) with gaps: marker m is
// missing on frames where (f / 7 + m) % 11 == 0.
inline MarkerArray SmoothMarkers(int64_t frames, int64_t markers, bool with_gaps = true) {
  MarkerArray a(frames, markers);
  for (int64_t f = 0; f < frames; ++f) {
    for (int64_t m = 0; m < markers; ++m) {
      if (with_gaps && (f / 7 + m) % 11 == 0) continue;  // stays NaN
      float* p = a.at(f, m);
      double t = static_cast<double>(f) * 0.01;
      p[0] = static_cast<float>(100.0 * m + 20.0 * std::sin(t + 0.3 * m));
      p[1] = static_cast<float>(-50.0 + 15.0 * std::cos(1.7 * t + m));
      p[2] = static_cast<float>(1200.0 + 5.0 * std::sin(0.5 * t) + 0.25 * m);
    }
  }
  return a;
}

inline Take MakeFullTake(const std::string& name, int64_t frames = 120, int64_t markers = 4) {
  Take t;
  t.name = name;
  t.rate_hz = 100.0;
  t.first_frame = 7;
  t.source_units = "m";
  for (int64_t m = 0; m < markers; ++m) t.marker_names.push_back(m == 0 ? "Lèvre_sup" : "M" + std::to_string(m));
  t.markers = SmoothMarkers(frames, markers);
  t.analog.rate_hz = 400.0;
  t.analog.names = {"EMG1", "Force Z"};
  t.analog.units = {"mV", "N"};
  t.analog.descriptions = {"orbicularis", ""};
  t.analog.samples = frames * 4;
  for (int64_t i = 0; i < t.analog.samples * 2; ++i) t.analog.data.push_back(static_cast<float>(0.001 * i - 0.5));
  t.events = {{"Foot Strike", "Left", 0.25, "first contact"}, {"RIC", "", 1.125, "événement"}};
  LabelTier phones;
  phones.name = "phones";
  phones.kind = LabelTier::Kind::kInterval;
  phones.start_s = 0.0;
  phones.end_s = 1.2;
  phones.labels = {{0.0, 0.3, "ʁ"}, {0.3, 0.55, "é"}, {0.55, 1.2, ""}};
  LabelTier keys;
  keys.name = "keys/targets";  // a '/' in a tier name must survive
  keys.kind = LabelTier::Kind::kPoint;
  keys.start_s = 0.0;
  keys.end_s = 1.2;
  keys.labels = {{0.4, 0.4, "5"}, {0.9, 0.9, "main→bouche"}};
  t.tiers = {phones, keys};
  t.audio.rate_hz = 16000.0;
  t.audio.channels = 2;
  for (int i = 0; i < 3200; ++i) t.audio.samples.push_back(static_cast<float>(std::sin(0.01 * i) * 0.5));
  t.audio_path = "audio/" + name + ".wav";
  t.provenance.sources = {{"/data/" + name + ".c3d", std::string(64, 'a'), "c3d"},
                          {"/data/" + name + ".TextGrid", std::string(64, 'b'), "textgrid"}};
  t.provenance.csw_version = "0.1.0-test";
  t.provenance.imported_utc = "2026-01-02T03:04:05Z";
  t.provenance.warnings = {"marker M2 has 3 gaps", "unité inconnue"};
  return t;
}

inline bool SameFloats(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0);
}

inline void ExpectSameMarkers(const MarkerArray& a, const MarkerArray& b) {
  EXPECT_EQ(a.frames(), b.frames());
  EXPECT_EQ(a.markers(), b.markers());
  EXPECT_TRUE(SameFloats(a.data(), b.data())) << "marker values differ";
}

inline void ExpectSameTake(const Take& a, const Take& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.rate_hz, b.rate_hz);
  EXPECT_EQ(a.first_frame, b.first_frame);
  EXPECT_EQ(a.source_units, b.source_units);
  EXPECT_EQ(a.marker_names, b.marker_names);
  ExpectSameMarkers(a.markers, b.markers);
  EXPECT_EQ(a.analog.rate_hz, b.analog.rate_hz);
  EXPECT_EQ(a.analog.names, b.analog.names);
  EXPECT_EQ(a.analog.units, b.analog.units);
  EXPECT_EQ(a.analog.descriptions, b.analog.descriptions);
  EXPECT_EQ(a.analog.samples, b.analog.samples);
  EXPECT_TRUE(SameFloats(a.analog.data, b.analog.data)) << "analog values differ";
  ASSERT_EQ(a.events.size(), b.events.size());
  for (size_t i = 0; i < a.events.size(); ++i) {
    EXPECT_EQ(a.events[i].label, b.events[i].label);
    EXPECT_EQ(a.events[i].context, b.events[i].context);
    EXPECT_EQ(a.events[i].time_s, b.events[i].time_s);
    EXPECT_EQ(a.events[i].description, b.events[i].description);
  }
  ASSERT_EQ(a.tiers.size(), b.tiers.size());
  for (size_t i = 0; i < a.tiers.size(); ++i) {
    EXPECT_EQ(a.tiers[i].name, b.tiers[i].name);
    EXPECT_EQ(a.tiers[i].kind, b.tiers[i].kind);
    EXPECT_EQ(a.tiers[i].start_s, b.tiers[i].start_s);
    EXPECT_EQ(a.tiers[i].end_s, b.tiers[i].end_s);
    ASSERT_EQ(a.tiers[i].labels.size(), b.tiers[i].labels.size());
    for (size_t j = 0; j < a.tiers[i].labels.size(); ++j) {
      EXPECT_EQ(a.tiers[i].labels[j].start_s, b.tiers[i].labels[j].start_s);
      EXPECT_EQ(a.tiers[i].labels[j].end_s, b.tiers[i].labels[j].end_s);
      EXPECT_EQ(a.tiers[i].labels[j].text, b.tiers[i].labels[j].text);
    }
  }
  EXPECT_EQ(a.audio.rate_hz, b.audio.rate_hz);
  EXPECT_EQ(a.audio.channels, b.audio.channels);
  EXPECT_TRUE(SameFloats(a.audio.samples, b.audio.samples)) << "audio samples differ";
  EXPECT_EQ(a.audio_path, b.audio_path);
  ASSERT_EQ(a.provenance.sources.size(), b.provenance.sources.size());
  for (size_t i = 0; i < a.provenance.sources.size(); ++i) {
    EXPECT_EQ(a.provenance.sources[i].path, b.provenance.sources[i].path);
    EXPECT_EQ(a.provenance.sources[i].sha256, b.provenance.sources[i].sha256);
    EXPECT_EQ(a.provenance.sources[i].format, b.provenance.sources[i].format);
  }
  EXPECT_EQ(a.provenance.csw_version, b.provenance.csw_version);
  EXPECT_EQ(a.provenance.imported_utc, b.provenance.imported_utc);
  EXPECT_EQ(a.provenance.warnings, b.provenance.warnings);
  ASSERT_EQ(a.skeleton.size(), b.skeleton.size());
  for (size_t j = 0; j < a.skeleton.size(); ++j) {
    EXPECT_EQ(a.skeleton[j].name, b.skeleton[j].name);
    EXPECT_EQ(a.skeleton[j].parent, b.skeleton[j].parent);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(a.skeleton[j].offset_mm[k], b.skeleton[j].offset_mm[k]);
    EXPECT_EQ(a.skeleton[j].channels, b.skeleton[j].channels);
    EXPECT_EQ(a.skeleton[j].end_site, b.skeleton[j].end_site);
  }
  EXPECT_EQ(a.orientations.frames(), b.orientations.frames());
  EXPECT_EQ(a.orientations.joints(), b.orientations.joints());
  EXPECT_TRUE(SameFloats(a.orientations.data(), b.orientations.data())) << "orientations differ";
}

// MakeFullTake with a skeleton: marker 0 is the root, 1 and 2 its chain, 3
// an end site of 2; orientations are unit quaternions turning about z, with
// joint 1 missing (NaN) on frames 10-14.
inline Take MakeSkeletonTake(const std::string& name, int64_t frames = 120) {
  Take t = MakeFullTake(name, frames, 4);
  t.skeleton.resize(4);
  const char* names[4] = {"Hips", "Spine", "Neck é", "Neck é_End"};
  for (int j = 0; j < 4; ++j) {
    t.marker_names[static_cast<size_t>(j)] = names[j];
    t.skeleton[static_cast<size_t>(j)].name = names[j];
    t.skeleton[static_cast<size_t>(j)].parent = j - 1;
    t.skeleton[static_cast<size_t>(j)].offset_mm[1] = 100.0 * j + 0.125;
    t.skeleton[static_cast<size_t>(j)].offset_mm[2] = -1.0 / 3.0;
  }
  t.skeleton[0].channels = {"Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation"};
  t.skeleton[1].channels = {"Yrotation", "Xrotation", "Zrotation"};
  t.skeleton[2].channels = {"Xrotation", "Zrotation", "Yrotation"};
  t.skeleton[3].end_site = true;
  t.orientations.Resize(frames, 4);
  for (int64_t f = 0; f < frames; ++f) {
    for (int64_t j = 0; j < 4; ++j) {
      if (j == 1 && f >= 10 && f < 15) continue;  // stays NaN
      const double half = 0.5 * (0.01 * static_cast<double>(f) + 0.2 * static_cast<double>(j));
      float* q = t.orientations.at(f, j);
      q[0] = static_cast<float>(std::cos(half));
      q[1] = 0.0f;
      q[2] = 0.0f;
      q[3] = static_cast<float>(std::sin(half));
    }
  }
  return t;
}

}  // namespace csw::testing
