// C3D writer: Intel processor, float (or int16) storage, millimetres.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>

#include "io/c3d/c3d.h"
#include "io/c3d/c3d_format.h"

namespace csw {

namespace {

constexpr float kPointScale = -0.1f;       // float storage; residual unit 0.1 mm
constexpr int64_t kMaxParamBytes = 32000;  // a parameter's link is a signed 16-bit offset
constexpr int64_t kMaxDim = 255;           // dimensions are stored in one byte

// Builds a parameter section: groups and parameters with their links.
class ParamWriter {
 public:
  void Group(int id, const std::string& name, const std::string& description) {
    std::vector<unsigned char> body;
    AppendString(&body, description);
    Entry(-id, name, body);
  }
  void Strings(int group, const std::string& name, const std::vector<std::string>& values) {
    size_t len = 1;
    for (const std::string& v : values) len = std::max(len, v.size());
    if (len > kMaxDim) throw InvalidInput("C3D: a " + name + " string is longer than 255 characters");
    std::vector<unsigned char> body{static_cast<unsigned char>(static_cast<int8_t>(-1))};
    if (values.size() == 1) {
      body.push_back(1);
      body.push_back(static_cast<unsigned char>(len));
    } else {
      body.push_back(2);
      body.push_back(static_cast<unsigned char>(len));
      body.push_back(static_cast<unsigned char>(values.size()));
    }
    for (const std::string& v : values) {
      std::string padded = v;
      padded.resize(len, ' ');
      body.insert(body.end(), padded.begin(), padded.end());
    }
    Finish(group, name, &body);
  }
  // Strings split into NAME, NAME2, NAME3... of at most 255 entries and ~32 KB each.
  void StringSeries(int group, const std::string& name, const std::vector<std::string>& values) {
    size_t len = 1;
    for (const std::string& v : values) len = std::max(len, v.size());
    const size_t per = static_cast<size_t>(std::min<int64_t>(kMaxDim, kMaxParamBytes / static_cast<int64_t>(len)));
    size_t start = 0;
    int k = 1;
    do {
      size_t end = std::min(values.size(), start + per);
      std::vector<std::string> part(values.begin() + static_cast<std::ptrdiff_t>(start),
                                    values.begin() + static_cast<std::ptrdiff_t>(end));
      if (part.empty()) part.push_back("");
      Strings(group, k == 1 ? name : name + std::to_string(k), part);
      start = end;
      ++k;
    } while (start < values.size());
  }
  void Int16(int group, const std::string& name, const std::vector<uint16_t>& values, bool scalar) {
    std::vector<unsigned char> body{2};
    Dims(&body, values.size(), scalar);
    for (uint16_t v : values) {
      body.push_back(static_cast<unsigned char>(v & 0xFF));
      body.push_back(static_cast<unsigned char>(v >> 8));
    }
    Finish(group, name, &body);
  }
  void Float(int group, const std::string& name, const std::vector<float>& values, bool scalar,
             std::vector<int> dims = {}) {
    std::vector<unsigned char> body{4};
    if (!dims.empty()) {
      body.push_back(static_cast<unsigned char>(dims.size()));
      for (int d : dims) body.push_back(static_cast<unsigned char>(d));
    } else {
      Dims(&body, values.size(), scalar);
    }
    for (float v : values) {
      unsigned char b[4];
      c3d::StoreF32Le(b, v);
      body.insert(body.end(), b, b + 4);
    }
    Finish(group, name, &body);
  }
  // The section padded to whole blocks, with its 4-byte preamble.
  std::vector<unsigned char> Section() const {
    std::vector<unsigned char> out{1, c3d::kKey, 0, c3d::kProcessorBase + 1};
    std::vector<unsigned char> entries = bytes_;
    if (last_link_ >= 0) {
      entries[static_cast<size_t>(last_link_)] = 0;
      entries[static_cast<size_t>(last_link_) + 1] = 0;
    }
    out.insert(out.end(), entries.begin(), entries.end());
    out.push_back(0);
    out.push_back(0);
    size_t blocks = (out.size() + c3d::kBlock - 1) / c3d::kBlock;
    if (blocks > 255) throw InvalidInput("C3D: the parameter section exceeds 255 blocks (too many labels)");
    out[2] = static_cast<unsigned char>(blocks);
    out.resize(blocks * c3d::kBlock, 0);
    return out;
  }

 private:
  static void AppendString(std::vector<unsigned char>* body, const std::string& s) {
    std::string t = s.substr(0, 127);
    body->push_back(static_cast<unsigned char>(t.size()));
    body->insert(body->end(), t.begin(), t.end());
  }
  static void Dims(std::vector<unsigned char>* body, size_t n, bool scalar) {
    if (scalar) {
      body->push_back(0);
      return;
    }
    if (static_cast<int64_t>(n) > kMaxDim) throw InvalidInput("C3D: more than 255 values in one parameter");
    body->push_back(1);
    body->push_back(static_cast<unsigned char>(n));
  }
  void Finish(int group, const std::string& name, std::vector<unsigned char>* body) {
    AppendString(body, "");
    Entry(group, name, *body);
  }
  void Entry(int id, const std::string& name, const std::vector<unsigned char>& body) {
    if (static_cast<int64_t>(body.size()) + 2 > kMaxParamBytes + 1024) {
      throw InvalidInput("C3D: parameter " + name + " is too large");
    }
    bytes_.push_back(static_cast<unsigned char>(name.size()));
    bytes_.push_back(static_cast<unsigned char>(static_cast<int8_t>(id)));
    bytes_.insert(bytes_.end(), name.begin(), name.end());
    last_link_ = static_cast<int64_t>(bytes_.size());
    uint16_t link = static_cast<uint16_t>(body.size() + 2);
    bytes_.push_back(static_cast<unsigned char>(link & 0xFF));
    bytes_.push_back(static_cast<unsigned char>(link >> 8));
    bytes_.insert(bytes_.end(), body.begin(), body.end());
  }

  std::vector<unsigned char> bytes_;
  int64_t last_link_ = -1;
};

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

}  // namespace

void WriteC3d(const std::string& path, const Take& take) { WriteC3d(path, take, C3dWriteOptions{}); }

void WriteC3d(const std::string& path, const Take& take, const C3dWriteOptions& options) {
  const bool int16 = options.storage == C3dWriteOptions::Storage::kInt16;
  if (int16 && !(options.point_scale_mm > 0 && std::isfinite(options.point_scale_mm)))
    throw InvalidInput(path + ": int16 storage needs a positive point scale");
  const float point_scale = int16 ? static_cast<float>(options.point_scale_mm) : kPointScale;
  const int64_t points = static_cast<int64_t>(take.marker_names.size());
  const int64_t frames = take.markers.frames();
  if (take.markers.markers() != points && !(take.markers.data().empty() && frames == 0)) {
    throw InvalidInput(path + ": take has " + std::to_string(points) + " marker names but " +
                       std::to_string(take.markers.markers()) + " marker columns");
  }
  if (points > 32767) throw InvalidInput(path + ": C3D holds at most 32767 points");
  if (!(take.rate_hz > 0)) throw InvalidInput(path + ": the take has no frame rate");
  if (take.first_frame < 1) throw InvalidInput(path + ": first frame must be at least 1");
  const AnalogData& an = take.analog;
  const int64_t channels = an.channels();
  int64_t subframes = 0;
  if (channels > 0) {
    if (static_cast<int64_t>(an.data.size()) != an.samples * channels) {
      throw InvalidInput(path + ": analog data size does not match samples x channels");
    }
    if (frames > 0) {
      if (an.samples % frames != 0) {
        throw InvalidInput(path + ": " + std::to_string(an.samples) + " analog samples are not a whole number per " +
                           std::to_string(frames) + " frames");
      }
      subframes = an.samples / frames;
    } else {
      subframes = std::max<int64_t>(1, std::llround(an.rate_hz / take.rate_hz));
    }
    if (channels > kMaxDim) throw InvalidInput(path + ": C3D writer supports at most 255 analog channels");
    if (subframes * channels > 65535) throw InvalidInput(path + ": too many analog values per frame");
  }
  if (take.events.size() > static_cast<size_t>(kMaxDim)) {
    throw InvalidInput(path + ": C3D writer supports at most 255 events");
  }
  const int64_t last_frame = take.first_frame + std::max<int64_t>(frames, 1) - 1;
  // Int16: per-channel analog scales mapping each channel's largest magnitude to 32000.
  std::vector<float> analog_scale(static_cast<size_t>(channels), 1.0f);
  if (int16) {
    const double limit = 32767.0 * static_cast<double>(point_scale);
    for (float v : take.markers.data()) {
      if (!std::isnan(v) && std::abs(static_cast<double>(v)) > limit) {
        throw InvalidInput(path + ": coordinate " + std::to_string(v) + " mm does not fit int16 storage at scale " +
                           std::to_string(point_scale) + " mm (limit " + std::to_string(limit) + " mm)");
      }
    }
    for (int64_t c = 0; c < channels; ++c) {
      double peak = 0.0;
      for (int64_t i = c; i < static_cast<int64_t>(an.data.size()); i += channels)
        if (std::isfinite(an.data[static_cast<size_t>(i)]))
          peak = std::max(peak, std::abs(static_cast<double>(an.data[static_cast<size_t>(i)])));
      analog_scale[static_cast<size_t>(c)] = peak > 0 ? static_cast<float>(peak / 32000.0) : 1.0f;
    }
  }

  // --- parameters ---
  ParamWriter pw;
  enum { kPoint = 1, kAnalog = 2, kTrial = 3, kEvent = 4, kManufacturer = 5 };
  pw.Group(kPoint, "POINT", "3-D point parameters");
  pw.Int16(kPoint, "USED", {static_cast<uint16_t>(points)}, true);
  pw.Float(kPoint, "SCALE", {point_scale}, true);
  pw.Float(kPoint, "RATE", {static_cast<float>(take.rate_hz)}, true);
  if (frames > 65535) {
    pw.Float(kPoint, "FRAMES", {static_cast<float>(frames)}, true);
  } else {
    pw.Int16(kPoint, "FRAMES", {static_cast<uint16_t>(frames)}, true);
  }
  pw.Strings(kPoint, "UNITS", {"mm"});
  pw.StringSeries(kPoint, "LABELS", take.marker_names);
  pw.Group(kAnalog, "ANALOG", "Analog data parameters");
  pw.Int16(kAnalog, "USED", {static_cast<uint16_t>(channels)}, true);
  pw.Float(kAnalog, "RATE", {static_cast<float>(channels > 0 ? an.rate_hz : 0.0)}, true);
  pw.Float(kAnalog, "GEN_SCALE", {1.0f}, true);
  if (channels > 0) {
    pw.StringSeries(kAnalog, "LABELS", an.names);
    std::vector<std::string> units = an.units;
    units.resize(static_cast<size_t>(channels));
    pw.StringSeries(kAnalog, "UNITS", units);
    if (!an.descriptions.empty()) {
      std::vector<std::string> desc = an.descriptions;
      desc.resize(static_cast<size_t>(channels));
      pw.StringSeries(kAnalog, "DESCRIPTIONS", desc);
    }
    pw.Float(kAnalog, "SCALE", analog_scale, false);
    pw.Int16(kAnalog, "OFFSET", std::vector<uint16_t>(static_cast<size_t>(channels), 0), false);
  }
  pw.Group(kTrial, "TRIAL", "Trial parameters");
  auto split = [](int64_t v) {
    return std::vector<uint16_t>{static_cast<uint16_t>(v & 0xFFFF), static_cast<uint16_t>((v >> 16) & 0xFFFF)};
  };
  pw.Int16(kTrial, "ACTUAL_START_FIELD", split(take.first_frame), false);
  pw.Int16(kTrial, "ACTUAL_END_FIELD", split(last_frame), false);
  pw.Group(kEvent, "EVENT", "Events");
  const int64_t num_events = static_cast<int64_t>(take.events.size());
  pw.Int16(kEvent, "USED", {static_cast<uint16_t>(num_events)}, true);
  if (num_events > 0) {
    std::vector<std::string> labels, contexts, descriptions;
    std::vector<float> times;
    for (const Event& e : take.events) {
      labels.push_back(e.label);
      contexts.push_back(e.context);
      descriptions.push_back(e.description);
      double minutes = std::floor(e.time_s / 60.0);
      times.push_back(static_cast<float>(minutes));
      times.push_back(static_cast<float>(e.time_s - 60.0 * minutes));
    }
    pw.Strings(kEvent, "LABELS", labels);
    pw.Strings(kEvent, "CONTEXTS", contexts);
    pw.Strings(kEvent, "DESCRIPTIONS", descriptions);
    pw.Float(kEvent, "TIMES", times, false, {2, static_cast<int>(num_events)});
  }
  pw.Group(kManufacturer, "MANUFACTURER", "Software that wrote the file");
  pw.Strings(kManufacturer, "COMPANY", {"csw"});
  pw.Strings(kManufacturer, "SOFTWARE", {"Cued Speech Workbench"});
  // DATA_START depends on the section size, which a 2-byte scalar does not change
  // by more than one block boundary: size the section with a placeholder first.
  ParamWriter sized = pw;
  sized.Int16(kPoint, "DATA_START", {0}, true);
  const int64_t param_blocks = static_cast<int64_t>(sized.Section().size()) / c3d::kBlock;
  const int64_t data_start = 2 + param_blocks;
  if (data_start > 65535) throw InvalidInput(path + ": parameter section too large");
  pw.Int16(kPoint, "DATA_START", {static_cast<uint16_t>(data_start)}, true);
  std::vector<unsigned char> section = pw.Section();

  // --- header ---
  std::vector<unsigned char> header(c3d::kBlock, 0);
  header[0] = 2;
  header[1] = c3d::kKey;
  auto word = [&](int w, uint16_t v) { c3d::StoreU16Le(header.data() + 2 * (w - 1), v); };
  word(2, static_cast<uint16_t>(points));
  word(3, static_cast<uint16_t>(subframes * channels));
  word(4, static_cast<uint16_t>(std::min<int64_t>(take.first_frame, 65535)));
  word(5, static_cast<uint16_t>(frames == 0 ? 0 : std::min<int64_t>(last_frame, 65535)));
  if (frames == 0) word(4, 1);
  word(6, 10);
  c3d::StoreF32Le(header.data() + 12, point_scale);
  word(9, static_cast<uint16_t>(data_start));
  word(10, static_cast<uint16_t>(subframes));
  c3d::StoreF32Le(header.data() + 20, static_cast<float>(take.rate_hz));
  word(150, 12345);

  // --- write ---
  std::unique_ptr<std::FILE, FileCloser> f(std::fopen(path.c_str(), "wb"));
  if (!f) throw IoError(path, std::string("cannot create: ") + std::strerror(errno));
  auto put = [&](const unsigned char* d, size_t n) {
    if (n > 0 && std::fwrite(d, 1, n, f.get()) != n) throw IoError(path, "write failed");
  };
  put(header.data(), header.size());
  put(section.data(), section.size());
  const int64_t frame_floats = 4 * points + subframes * channels;
  const int64_t word_bytes = int16 ? 2 : 4;
  const int64_t chunk = std::max<int64_t>(1, (int64_t{1} << 20) / std::max<int64_t>(1, frame_floats));
  std::vector<unsigned char> buf;
  const float* mk = take.markers.data().data();
  auto to_i16 = [](double v) {
    double r = std::nearbyint(v);
    return static_cast<uint16_t>(static_cast<int16_t>(std::clamp(r, -32767.0, 32767.0)));
  };
  for (int64_t f0 = 0; f0 < frames && int16; f0 += chunk) {
    const int64_t n = std::min(chunk, frames - f0);
    buf.resize(static_cast<size_t>(n * frame_floats * word_bytes));
    unsigned char* o = buf.data();
    for (int64_t fr = f0; fr < f0 + n; ++fr) {
      for (int64_t m = 0; m < points; ++m, o += 8) {
        const float* p = mk + (fr * points + m) * 3;
        if (std::isnan(p[0]) || std::isnan(p[1]) || std::isnan(p[2])) {
          for (int k = 0; k < 3; ++k) c3d::StoreU16Le(o + 2 * k, 0);
          c3d::StoreU16Le(o + 6, 0xFFFF);  // residual word -1: missing
        } else {
          for (int k = 0; k < 3; ++k) c3d::StoreU16Le(o + 2 * k, to_i16(p[k] / static_cast<double>(point_scale)));
          c3d::StoreU16Le(o + 6, 0);
        }
      }
      const float* a = channels > 0 ? an.data.data() + fr * subframes * channels : nullptr;
      for (int64_t k = 0; k < subframes * channels; ++k, o += 2) {
        double v = std::isfinite(a[k]) ? a[k] : 0.0;
        c3d::StoreU16Le(o, to_i16(v / static_cast<double>(analog_scale[static_cast<size_t>(k % channels)])));
      }
    }
    put(buf.data(), buf.size());
  }
  for (int64_t f0 = 0; f0 < frames && !int16; f0 += chunk) {
    const int64_t n = std::min(chunk, frames - f0);
    buf.resize(static_cast<size_t>(n * frame_floats * 4));
    unsigned char* o = buf.data();
    for (int64_t fr = f0; fr < f0 + n; ++fr) {
      for (int64_t m = 0; m < points; ++m, o += 16) {
        const float* p = mk + (fr * points + m) * 3;
        float v[4] = {p[0], p[1], p[2], 0.0f};
        if (std::isnan(v[0]) || std::isnan(v[1]) || std::isnan(v[2])) {
          v[0] = v[1] = v[2] = 0.0f;
          v[3] = -1.0f;
        }
        for (int k = 0; k < 4; ++k) c3d::StoreF32Le(o + 4 * k, v[k]);
      }
      const float* a = channels > 0 ? an.data.data() + fr * subframes * channels : nullptr;
      for (int64_t k = 0; k < subframes * channels; ++k, o += 4) c3d::StoreF32Le(o, a[k]);
    }
    put(buf.data(), buf.size());
  }
  // pad the data to a whole block, as most readers expect
  const int64_t data_bytes = frames * frame_floats * word_bytes;
  const int64_t pad = (c3d::kBlock - data_bytes % c3d::kBlock) % c3d::kBlock;
  std::vector<unsigned char> zeros(static_cast<size_t>(pad), 0);
  put(zeros.data(), zeros.size());
  if (std::fflush(f.get()) != 0) throw IoError(path, "write failed");
  if (std::fclose(f.release()) != 0) throw IoError(path, "close failed");
}

}  // namespace csw
