#pragma once
// The core data model: a take (one recording) with markers, analog channels,
// events, label tiers, an audio reference and provenance. Plain C++ + STL so that
// every module (and h5py/MATLAB readers of the corpus) sees the same layout.
#include <cmath>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

namespace csw {

inline constexpr float kMissing = std::numeric_limits<float>::quiet_NaN();
inline bool IsMissing(float v) { return std::isnan(v); }

// Marker positions, frames × markers × xyz, row-major (frame slowest), float32,
// millimetres, NaN for missing samples (all three coordinates NaN together).
class MarkerArray {
 public:
  MarkerArray() = default;
  MarkerArray(int64_t frames, int64_t markers)
      : frames_(frames), markers_(markers), data_(static_cast<size_t>(frames * markers * 3), kMissing) {}

  int64_t frames() const { return frames_; }
  int64_t markers() const { return markers_; }
  bool empty() const { return frames_ == 0 || markers_ == 0; }

  float* at(int64_t frame, int64_t marker) { return &data_[Index(frame, marker)]; }
  const float* at(int64_t frame, int64_t marker) const { return &data_[Index(frame, marker)]; }
  bool Visible(int64_t frame, int64_t marker) const { return !IsMissing(at(frame, marker)[0]); }
  void SetMissing(int64_t frame, int64_t marker) {
    float* p = at(frame, marker);
    p[0] = p[1] = p[2] = kMissing;
  }
  // Count of visible (non-NaN) marker samples.
  int64_t CountVisible() const;

  std::vector<float>& data() { return data_; }
  const std::vector<float>& data() const { return data_; }
  void Resize(int64_t frames, int64_t markers) {
    frames_ = frames;
    markers_ = markers;
    data_.assign(static_cast<size_t>(frames * markers * 3), kMissing);
  }

 private:
  size_t Index(int64_t frame, int64_t marker) const { return static_cast<size_t>((frame * markers_ + marker) * 3); }
  int64_t frames_ = 0;
  int64_t markers_ = 0;
  std::vector<float> data_;
};

// Analog channels sampled at rate_hz: samples × channels, row-major, float32,
// already scaled to physical units.
struct AnalogData {
  double rate_hz = 0.0;
  std::vector<std::string> names;
  std::vector<std::string> units;
  std::vector<std::string> descriptions;
  int64_t samples = 0;
  std::vector<float> data;  // samples * names.size()
  int64_t channels() const { return static_cast<int64_t>(names.size()); }
};

struct Event {
  std::string label;    // e.g. "Foot Strike", "RIC"
  std::string context;  // e.g. "Left", "Right", "" when unknown
  double time_s = 0.0;  // seconds from the start of the trial (first frame = 0)
  std::string description;
};

// A Praat-style label tier: intervals (start < end) or points (start == end).
struct Label {
  double start_s = 0.0;
  double end_s = 0.0;
  std::string text;  // UTF-8
};

struct LabelTier {
  enum class Kind { kInterval, kPoint };
  std::string name;
  Kind kind = Kind::kInterval;
  double start_s = 0.0;  // tier domain
  double end_s = 0.0;
  std::vector<Label> labels;
};

// Audio samples (mono or interleaved multichannel), float in [-1, 1].
struct Audio {
  double rate_hz = 0.0;
  int channels = 1;
  std::vector<float> samples;  // frames * channels, interleaved
  int64_t frames() const { return channels > 0 ? static_cast<int64_t>(samples.size()) / channels : 0; }
  double duration_s() const { return rate_hz > 0 ? static_cast<double>(frames()) / rate_hz : 0.0; }
};

// Global joint orientations of a skeleton capture (BVH), frames × joints × 4
// (w, x, y, z), row-major (frame slowest), float32: the unit quaternion that
// rotates the joint's own axes into the lab frame. Joint j is marker j of its
// take (the marker holds the joint's position); NaN when unknown.
class OrientationArray {
 public:
  OrientationArray() = default;
  OrientationArray(int64_t frames, int64_t joints)
      : frames_(frames), joints_(joints), data_(static_cast<size_t>(frames * joints * 4), kMissing) {}

  int64_t frames() const { return frames_; }
  int64_t joints() const { return joints_; }
  bool empty() const { return frames_ == 0 || joints_ == 0; }
  // Pointer to (w, x, y, z) of one joint in one frame.
  float* at(int64_t frame, int64_t joint) { return &data_[Index(frame, joint)]; }
  const float* at(int64_t frame, int64_t joint) const { return &data_[Index(frame, joint)]; }
  std::vector<float>& data() { return data_; }
  const std::vector<float>& data() const { return data_; }
  void Resize(int64_t frames, int64_t joints) {
    frames_ = frames;
    joints_ = joints;
    data_.assign(static_cast<size_t>(frames * joints * 4), kMissing);
  }

 private:
  size_t Index(int64_t frame, int64_t joint) const { return static_cast<size_t>((frame * joints_ + joint) * 4); }
  int64_t frames_ = 0;
  int64_t joints_ = 0;
  std::vector<float> data_;
};

// One joint of a skeleton hierarchy (BVH HIERARCHY section). Joints are listed
// parents first (a parent's index is smaller than its children's).
struct SkeletonJoint {
  std::string name;
  int parent = -1;                        // index of the parent joint, -1 for a root
  double offset_mm[3] = {0.0, 0.0, 0.0};  // from the parent, in the parent's axes (mm)
  std::vector<std::string> channels;      // in file order: "Xposition", "Zrotation", ... (none for end sites)
  bool end_site = false;                  // a BVH "End Site" (no channels, no children)
};

struct SourceFile {
  std::string path;    // as given at import
  std::string sha256;  // hex of the file's bytes
  std::string format;  // "c3d", "trc", "wav", "textgrid", "eaf"
};

struct Provenance {
  std::vector<SourceFile> sources;
  std::string csw_version;
  std::string imported_utc;           // ISO 8601
  std::vector<std::string> warnings;  // import report
};

struct Take {
  std::string name;
  double rate_hz = 0.0;     // marker frame rate
  int64_t first_frame = 1;  // 1-based number of the first frame in the source file
  std::vector<std::string> marker_names;
  MarkerArray markers;              // in millimetres
  std::string source_units = "mm";  // units as stored in the source, before conversion
  AnalogData analog;
  std::vector<Event> events;
  std::vector<LabelTier> tiers;
  Audio audio;             // empty when none
  std::string audio_path;  // reference to the source WAV, when any
  Provenance provenance;
  // The marker-set definition (JSON text) given at import, "" when none; the
  // corpus keeps it with the take (attribute "markerset").
  std::string markerset_json;
  // Skeleton captures (BVH) only, empty otherwise: the hierarchy (joint j is
  // marker j: marker_names[j] == skeleton[j].name) and the global orientation
  // of every joint in every frame (end sites carry their parent's).
  std::vector<SkeletonJoint> skeleton;
  OrientationArray orientations;

  int64_t frames() const { return markers.frames(); }
  double duration_s() const { return rate_hz > 0 ? static_cast<double>(frames()) / rate_hz : 0.0; }
  // Index of a marker by exact name, or -1.
  int64_t MarkerIndex(const std::string& name) const;
};

// Number of gaps (maximal runs of missing frames) of one marker.
int64_t CountGaps(const MarkerArray& markers, int64_t marker);

// Millimetres per one unit of a C3D/TRC unit string ("mm", "m", "cm", "in").
// Returns 0 for an unknown unit.
double MillimetresPerUnit(const std::string& units);

}  // namespace csw
