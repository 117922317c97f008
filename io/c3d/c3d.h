#pragma once
// C3D motion-capture files (https://www.c3d.org): a streaming reader for Intel,
// DEC and MIPS processors with int16 or float storage, and a writer (Intel, float,
// millimetres). Damaged files are read as far as they can be, with warnings;
// anything unreadable throws csw::ParseError naming the file and the byte offset.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "core/error.h"
#include "core/take.h"

namespace csw {

// The one rule for a valid point sample, used by every path that reads point
// data (C3dReader::ReadFrames for import/ReadC3d and C3dReader::ValidPointStats
// for inspect): the residual word (int16) or fourth float is >= 0 AND none of
// the coordinates is NaN. Some pipelines (Vicon, pyCGM2) mark missing samples
// with NaN coordinates and a residual >= 0; those are missing. Coordinates are
// as stored in the file (before any scaling).
inline bool C3dPointSampleValid(float x, float y, float z, float residual_word) {
  return residual_word >= 0.0f && !std::isnan(x + y + z);
}

struct C3dInfo {
  std::string processor;    // "intel", "dec", "mips"
  std::string storage;      // "int16" or "float"
  int64_t points = 0;       // POINT:USED
  int64_t first_frame = 1;  // 1-based (header word, or TRIAL:ACTUAL_START_FIELD for long trials)
  int64_t frames = 0;       // frames actually available (clamped to what the file holds)
  double point_rate_hz = 0;
  int64_t analog_channels = 0;
  int64_t analog_subframes_per_frame = 0;
  double analog_rate_hz = 0;
  double point_scale = 0;           // POINT:SCALE
  std::string units;                // POINT:UNITS as stored
  std::vector<std::string> labels;  // POINT:LABELS, LABELS2.. (trimmed)
  std::vector<std::string> descriptions;
  std::vector<std::string> analog_labels, analog_units;
  std::vector<std::string> analog_descriptions;  // ANALOG:DESCRIPTIONS (trimmed)
  std::vector<Event> events;                     // header events + EVENT group, times in seconds
  std::vector<std::string> warnings;
};

// Streaming reader: the constructor parses the header and the parameter section;
// frames are read on demand in chunks, so memory is O(frames requested).
class C3dReader {
 public:
  // Throws ParseError (damaged/unsupported file) or IoError (cannot open).
  explicit C3dReader(const std::string& path);
  ~C3dReader();
  C3dReader(const C3dReader&) = delete;
  C3dReader& operator=(const C3dReader&) = delete;

  const C3dInfo& info() const { return info_; }

  // Reads `count` frames starting at `first` (0-based, first + count <= frames)
  // into points_mm[count * points * 3] in millimetres (NaN for invalid samples),
  // residuals[count * points] in millimetres (-1 for invalid; may be null) and
  // analog[count * subframes * channels], scaled as (raw - offset) * scale * gen_scale
  // (may be null). Throws InvalidInput for a bad range, ParseError/IoError on read failure.
  void ReadFrames(int64_t first, int64_t count, float* points_mm, float* residuals, float* analog);

  // Over all frames: the number of valid point samples and the sum of x + y + z over
  // them, in the file's units after POINT:SCALE (not converted to millimetres).
  void ValidPointStats(int64_t* valid_samples, double* sum_xyz_valid);

 private:
  // Reads `count` whole frames from `first` into buffer_ and returns a pointer to them.
  const unsigned char* LoadFrames(int64_t first, int64_t count);

  std::string path_;
  int fd_ = -1;
  int64_t file_size_ = 0;
  C3dInfo info_;
  int processor_code_ = 1;  // 1 Intel, 2 DEC, 3 MIPS
  bool is_float_ = false;
  bool analog_unsigned_ = false;
  double scale_abs_ = 1.0;  // |POINT:SCALE| (int16 storage multiplier)
  double mm_per_unit_ = 1.0;
  int64_t data_offset_ = 0;  // byte offset of the first frame to read
  int64_t frame_bytes_ = 0;
  int64_t analog_words_ = 0;  // analog values per frame (channels * subframes)
  std::vector<float> analog_offset_;
  std::vector<float> analog_scale_;  // scale * gen_scale per channel
  std::vector<unsigned char> buffer_;
};

// Whole take in millimetres with analog channels and events; reader warnings go to
// take.provenance.warnings. Throws ParseError/IoError.
Take ReadC3d(const std::string& path);

// Writes an Intel, float-storage C3D in millimetres: labels beyond 255 go to
// POINT:LABELS2..., events to the EVENT group, more than 65535 frames through
// POINT:FRAMES (float) and TRIAL:ACTUAL_START_FIELD/ACTUAL_END_FIELD.
// Throws InvalidInput for a take C3D cannot hold, IoError when the file cannot be written.
void WriteC3d(const std::string& path, const Take& take);

// Storage of a written C3D. Int16 halves the file: coordinates are rounded to
// multiples of point_scale_mm (a take whose |coordinates| exceed 32767 × scale is
// refused with InvalidInput) and analog channels get a per-channel scale so their
// largest magnitude maps to 32000 counts.
struct C3dWriteOptions {
  enum class Storage { kFloat, kInt16 };
  Storage storage = Storage::kFloat;
  double point_scale_mm = 0.1;  // kInt16 only
};
void WriteC3d(const std::string& path, const Take& take, const C3dWriteOptions& options);

}  // namespace csw
