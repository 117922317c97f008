// C3D reader: header, parameter section (with recovery from damaged sections) and
// streaming frame decoding for Intel, DEC and MIPS files in int16 or float storage.
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>

#include "core/sha256.h"
#include "io/c3d/c3d.h"
#include "io/c3d/c3d_format.h"

namespace csw {

namespace {

using c3d::Processor;

constexpr int64_t kChunkBytes = int64_t{4} << 20;  // streaming read size
constexpr int kHeaderEventsMax = 18;

// One parameter as stored: type -1 char, 1 byte, 2 int16, 4 float.
struct Param {
  int group_id = 0;
  std::string name;  // upper case
  int type = 0;
  std::vector<int> dims;
  std::vector<unsigned char> data;
  int64_t file_offset = 0;
  int64_t Count() const {
    int64_t n = 1;
    for (int d : dims) {
      n *= d;
      if (n > (int64_t{1} << 40)) return int64_t{1} << 40;  // saturate: hostile dimensions
    }
    return n;
  }
};

std::string Upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string Trim(const std::string& s) {
  size_t b = 0;
  size_t e = s.size();
  auto blank = [](char c) { return c == ' ' || c == '\0' || c == '\t' || c == '\r' || c == '\n'; };
  while (b < e && blank(s[b])) ++b;
  while (e > b && blank(s[e - 1])) --e;
  return s.substr(b, e - b);
}

bool PrintableName(const std::string& s) {
  if (s.empty()) return false;
  for (char c : s) {
    unsigned char u = static_cast<unsigned char>(c);
    if (u < 0x20 || u > 0x7E) return false;
  }
  return true;
}

// The parsed parameter section.
class ParamTable {
 public:
  void AddGroup(int id, const std::string& name) {
    if (!groups_.count(id)) groups_[id] = Upper(name);
  }
  void AddParam(Param p) { params_.push_back(std::move(p)); }

  // First parameter GROUP:NAME (a group name may be used by more than one id).
  const Param* Find(const std::string& group, const std::string& name) const {
    for (const Param& p : params_) {
      auto it = groups_.find(p.group_id);
      if (it != groups_.end() && it->second == group && p.name == name) return &p;
    }
    return nullptr;
  }
  bool HasGroup(const std::string& group) const {
    for (const auto& [id, name] : groups_) {
      if (name == group) return true;
    }
    return false;
  }

 private:
  std::map<int, std::string> groups_;
  std::vector<Param> params_;
};

// Numeric values of a parameter (int16 signed, byte unsigned, float); empty for char.
std::vector<double> Numbers(const Param* p, Processor proc) {
  std::vector<double> out;
  if (!p) return out;
  int64_t n = p->Count();
  const unsigned char* d = p->data.data();
  for (int64_t i = 0; i < n; ++i) {
    switch (p->type) {
      case 1:
        out.push_back(d[i]);
        break;
      case 2:
        out.push_back(c3d::LoadI16(proc, d + 2 * i));
        break;
      case 4:
        out.push_back(c3d::LoadF32(proc, d + 4 * i));
        break;
      default:
        return out;
    }
  }
  return out;
}

// Raw 16-bit words of an int16 parameter, unsigned.
std::vector<uint32_t> Words(const Param* p, Processor proc) {
  std::vector<uint32_t> out;
  if (!p || p->type != 2) return out;
  for (int64_t i = 0; i < p->Count(); ++i) out.push_back(c3d::LoadU16(proc, p->data.data() + 2 * i));
  return out;
}

std::optional<double> Number(const Param* p, Processor proc) {
  std::vector<double> v = Numbers(p, proc);
  if (v.empty()) return std::nullopt;
  return v[0];
}

// Strings of a char parameter: the first dimension is the length of each string.
std::vector<std::string> Strings(const Param* p) {
  std::vector<std::string> out;
  if (!p || p->type != -1) return out;
  const char* d = reinterpret_cast<const char*>(p->data.data());
  if (p->dims.empty()) {
    out.push_back(Trim(std::string(d, 1)));
    return out;
  }
  int64_t len = p->dims[0];
  int64_t count = len > 0 ? p->Count() / len : 0;
  for (int64_t i = 0; i < count; ++i) out.push_back(Trim(std::string(d + i * len, static_cast<size_t>(len))));
  return out;
}

// GROUP:BASE, GROUP:BASE2, GROUP:BASE3, ... concatenated.
std::vector<std::string> StringSeries(const ParamTable& t, const std::string& group, const std::string& base) {
  std::vector<std::string> out = Strings(t.Find(group, base));
  for (int k = 2;; ++k) {
    const Param* p = t.Find(group, base + std::to_string(k));
    if (!p) break;
    std::vector<std::string> more = Strings(p);
    out.insert(out.end(), more.begin(), more.end());
  }
  return out;
}

std::string Quote(const std::string& s) { return "'" + s + "'"; }

// A parameter value as an integer; float-typed values may be anything (NaN, 1e30).
int64_t ToInt(double v) {
  if (!(v == v)) return 0;
  return static_cast<int64_t>(std::clamp(v, -1e12, 1e12));
}

// Converts `count` frames of raw bytes. Templated on processor and storage so
// that the inner loop has no per-sample dispatch.
struct ConvertArgs {
  const unsigned char* src;
  int64_t count;
  int64_t points;
  int64_t analog_words;
  int64_t channels;
  int64_t frame_bytes;
  float scale;           // int16 multiplier (|POINT:SCALE|)
  float mm;              // millimetres per file unit
  float residual_scale;  // |POINT:SCALE| * mm
  bool analog_unsigned;
  const float* analog_offset;
  const float* analog_scale;
  float* points_mm;
  float* residuals;
  float* analog;
};

template <Processor kP, bool kFloat>
void Convert(const ConvertArgs& a) {
  constexpr int kWord = kFloat ? 4 : 2;
  const float nan = std::numeric_limits<float>::quiet_NaN();
  for (int64_t f = 0; f < a.count; ++f) {
    const unsigned char* s = a.src + f * a.frame_bytes;
    float* out = a.points_mm ? a.points_mm + f * a.points * 3 : nullptr;
    float* res = a.residuals ? a.residuals + f * a.points : nullptr;
    for (int64_t i = 0; i < a.points; ++i, s += 4 * kWord) {
      float x, y, z, r;
      bool valid;
      if constexpr (kFloat) {
        x = c3d::LoadF32<kP>(s);
        y = c3d::LoadF32<kP>(s + 4);
        z = c3d::LoadF32<kP>(s + 8);
        float w = c3d::LoadF32<kP>(s + 12);
        valid = C3dPointSampleValid(x, y, z, w);
        int word = valid && w < 65536.0f ? static_cast<int>(w) : 0;
        r = static_cast<float>(word & 0xFF) * a.residual_scale;
        x *= a.mm;
        y *= a.mm;
        z *= a.mm;
      } else {
        float k = a.scale * a.mm;
        x = static_cast<float>(c3d::LoadI16<kP>(s)) * k;
        y = static_cast<float>(c3d::LoadI16<kP>(s + 2)) * k;
        z = static_cast<float>(c3d::LoadI16<kP>(s + 4)) * k;
        int16_t w = c3d::LoadI16<kP>(s + 6);
        valid = C3dPointSampleValid(x, y, z, static_cast<float>(w));
        r = static_cast<float>(w & 0xFF) * a.residual_scale;
      }
      if (!valid) {
        x = y = z = nan;
        r = -1.0f;
      }
      if (out) {
        out[3 * i] = x;
        out[3 * i + 1] = y;
        out[3 * i + 2] = z;
      }
      if (res) res[i] = r;
    }
    if (a.analog && a.channels > 0) {
      float* an = a.analog + f * a.analog_words;
      for (int64_t k = 0; k < a.analog_words; ++k, s += kWord) {
        int64_t c = k % a.channels;
        float raw;
        if constexpr (kFloat) {
          raw = c3d::LoadF32<kP>(s);
        } else {
          raw = a.analog_unsigned ? static_cast<float>(c3d::LoadU16<kP>(s)) : static_cast<float>(c3d::LoadI16<kP>(s));
        }
        an[k] = (raw - a.analog_offset[c]) * a.analog_scale[c];
      }
    }
  }
}

template <Processor kP, bool kFloat>
void Stats(const unsigned char* src, int64_t count, int64_t points, int64_t frame_bytes, double scale, int64_t* valid,
           double* sum) {
  constexpr int kWord = kFloat ? 4 : 2;
  int64_t n = 0;
  double total = 0.0;
  for (int64_t f = 0; f < count; ++f) {
    const unsigned char* s = src + f * frame_bytes;
    for (int64_t i = 0; i < points; ++i, s += 4 * kWord) {
      if constexpr (kFloat) {
        const float x = c3d::LoadF32<kP>(s), y = c3d::LoadF32<kP>(s + 4), z = c3d::LoadF32<kP>(s + 8);
        if (!C3dPointSampleValid(x, y, z, c3d::LoadF32<kP>(s + 12))) continue;
        total += static_cast<double>(x) + static_cast<double>(y) + static_cast<double>(z);
      } else {
        const int16_t x = c3d::LoadI16<kP>(s), y = c3d::LoadI16<kP>(s + 2), z = c3d::LoadI16<kP>(s + 4);
        if (!C3dPointSampleValid(x, y, z, static_cast<float>(c3d::LoadI16<kP>(s + 6)))) continue;
        total += (static_cast<double>(x) + y + z) * scale;
      }
      ++n;
    }
  }
  *valid += n;
  *sum += total;
}

// Walks the linked groups and parameters of a parameter section (`sec`, read from
// file offset `section_offset`). Damage ends the walk with a warning; a broken link
// is stepped over when the entry itself is intact.
ParamTable ParseParameters(const std::vector<unsigned char>& sec, int64_t section_offset, Processor proc,
                           const std::string& cut_note, const std::function<void(const std::string&)>& warn) {
  ParamTable table;
  const int64_t section_size = static_cast<int64_t>(sec.size());
  int64_t pos = 4;
  while (true) {
    if (pos + 2 > section_size) {
      warn("parameter section ends at offset " + std::to_string(section_offset + pos) + " without a terminator" +
           cut_note);
      break;
    }
    const int nchar = static_cast<int8_t>(sec[pos]);
    const int id = static_cast<int8_t>(sec[pos + 1]);
    if (nchar == 0 || id == 0) break;
    const int64_t len = std::abs(nchar);
    int64_t p = pos + 2;
    if (p + len + 2 > section_size) {
      warn("parameter entry at offset " + std::to_string(section_offset + pos) + " overruns the parameter section" +
           cut_note);
      break;
    }
    std::string name(reinterpret_cast<const char*>(sec.data() + p), static_cast<size_t>(len));
    p += len;
    const int offset = c3d::LoadI16(proc, sec.data() + p);
    const int64_t next = p + offset;
    p += 2;
    bool body_ok = true;
    if (!PrintableName(name)) {
      warn("parameter entry at offset " + std::to_string(section_offset + pos) +
           " has a non-printable name; stopping the parameter scan there");
      break;
    }
    int64_t body_end = -1;  // end of the entry's description, when readable
    auto description_end = [&](int64_t q) -> int64_t {
      return q + 1 <= section_size && q + 1 + sec[q] <= section_size ? q + 1 + sec[q] : -1;
    };
    if (id < 0) {
      body_end = description_end(p);
      if (body_end < 0) {
        body_ok = false;
      } else {
        table.AddGroup(-id, name);
      }
    } else {
      Param prm;
      prm.group_id = id;
      prm.name = Upper(name);
      prm.file_offset = section_offset + pos;
      if (p + 2 > section_size) {
        body_ok = false;
      } else {
        prm.type = static_cast<int8_t>(sec[p]);
        const int ndims = sec[p + 1];
        p += 2;
        if (p + ndims > section_size) {
          body_ok = false;
        } else {
          for (int d = 0; d < ndims; ++d) prm.dims.push_back(sec[p + d]);
          p += ndims;
          const int elem = std::abs(prm.type);
          if (elem != 1 && elem != 2 && elem != 4) {
            warn("parameter " + Quote(name) + " at offset " + std::to_string(prm.file_offset) + " has unknown type " +
                 std::to_string(prm.type) + "; ignored");
          } else {
            const int64_t bytes = prm.Count() * elem;
            if (p + bytes > section_size) {
              body_ok = false;
            } else {
              prm.data.assign(sec.begin() + p, sec.begin() + p + bytes);
              table.AddParam(std::move(prm));
              body_end = description_end(p + bytes);
            }
          }
        }
      }
    }
    if (!body_ok) {
      warn("parameter entry " + Quote(name) + " at offset " + std::to_string(section_offset + pos) +
           " overruns the parameter section" + cut_note + "; stopping the parameter scan there");
      break;
    }
    if (offset == 0) break;
    if (next <= pos || next > section_size) {
      if (body_end > pos) {
        // e.g. sample_02 sgi_*.c3d: a link stored in the wrong byte order
        warn("parameter entry " + Quote(name) + " at offset " + std::to_string(section_offset + pos) +
             " has an invalid link to the next entry (" + std::to_string(offset) +
             "); continuing right after its description");
        pos = body_end;
        continue;
      }
      warn("parameter entry " + Quote(name) + " at offset " + std::to_string(section_offset + pos) +
           " has an invalid link to the next entry (" + std::to_string(offset) +
           "); stopping the parameter scan there");
      break;
    }
    pos = next;
  }
  return table;
}

// Header events (up to 18, 4-character labels), then the EVENT group (labels,
// contexts, descriptions, times as [minutes, seconds] pairs).
std::vector<Event> ReadEvents(const unsigned char* h, const ParamTable& table, Processor proc,
                              const std::function<void(const std::string&)>& warn) {
  std::vector<Event> events;
  int num_events = c3d::LoadI16(proc, h + 300);
  if (num_events < 0 || num_events > kHeaderEventsMax) {
    warn("header event count " + std::to_string(num_events) + " at offset 300 is out of range; ignoring them");
    num_events = 0;
  }
  for (int i = 0; i < num_events; ++i) {
    Event e;
    e.time_s = c3d::LoadF32(proc, h + 304 + 4 * i);
    e.label = Trim(std::string(reinterpret_cast<const char*>(h + 396 + 4 * i), 4));
    events.push_back(e);
  }
  // BKIN Dexterit-E (sample_22) writes a Vicon-like group named EVENTS.
  std::string ev = table.Find("EVENT", "TIMES") ? "EVENT" : table.Find("EVENTS", "TIMES") ? "EVENTS" : "";
  if (ev == "EVENTS") warn("events read from the non-standard EVENTS group");
  if (!ev.empty()) {
    std::vector<std::string> labels = Strings(table.Find(ev, "LABELS"));
    std::vector<std::string> contexts = Strings(table.Find(ev, "CONTEXTS"));
    std::vector<std::string> descriptions = Strings(table.Find(ev, "DESCRIPTIONS"));
    const Param* p_times = table.Find(ev, "TIMES");
    std::vector<double> times = Numbers(p_times, proc);
    if (p_times && p_times->dims.size() == 1) {
      // a single row of seconds: make [0, seconds] pairs
      std::vector<double> pairs;
      for (double t : times) pairs.insert(pairs.end(), {0.0, t});
      times = std::move(pairs);
    }
    int64_t n = static_cast<int64_t>(times.size() / 2);
    if (auto used = Number(table.Find(ev, "USED"), proc)) {
      int64_t u = ToInt(*used);
      if (u > n) warn(ev + ":USED (" + std::to_string(u) + ") exceeds the " + std::to_string(n) + " stored times");
      n = std::clamp<int64_t>(u, 0, n);
    }
    for (int64_t i = 0; i < n; ++i) {
      Event e;
      e.time_s = 60.0 * times[2 * i] + times[2 * i + 1];
      if (i < static_cast<int64_t>(labels.size())) e.label = labels[i];
      if (i < static_cast<int64_t>(contexts.size())) e.context = contexts[i];
      if (i < static_cast<int64_t>(descriptions.size())) e.description = descriptions[i];
      events.push_back(e);
    }
  }
  return events;
}

}  // namespace

C3dReader::C3dReader(const std::string& path) : path_(path) {
  fd_ = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd_ < 0) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
  struct stat st {};
  if (::fstat(fd_, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd_);
    fd_ = -1;
    throw IoError(path, "not a regular file");
  }
  file_size_ = st.st_size;
  try {
    auto at = [&](int64_t offset) { return Location{path_, offset, std::nullopt}; };
    auto read_at = [&](int64_t offset, int64_t size, unsigned char* dst) {
      int64_t done = 0;
      while (done < size) {
        ssize_t r = ::pread(fd_, dst + done, static_cast<size_t>(size - done), offset + done);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) throw ParseError(at(offset + done), "unexpected end of file");
        done += r;
      }
    };
    auto warn = [&](const std::string& w) { info_.warnings.push_back(w); };

    // --- header block ---
    CSW_PARSE_CHECK(file_size_ > 0, at(0), "file is empty (0 bytes), not a C3D file");
    CSW_PARSE_CHECK(file_size_ >= c3d::kBlock, at(file_size_),
                    "file is " + std::to_string(file_size_) + " bytes, shorter than the 512-byte C3D header");
    unsigned char h[c3d::kBlock];
    read_at(0, c3d::kBlock, h);
    CSW_PARSE_CHECK(h[1] == c3d::kKey, at(1),
                    "not a C3D file: header key byte is " + std::to_string(h[1]) + ", expected 80 (0x50)");
    const int param_block = h[0];
    CSW_PARSE_CHECK(param_block >= 1, at(0), "header points to parameter block 0");
    const int64_t param_start = int64_t{param_block - 1} * c3d::kBlock;
    CSW_PARSE_CHECK(param_start + 4 <= file_size_, at(param_start),
                    "parameter block " + std::to_string(param_block) + " lies beyond the end of the file");
    unsigned char ph[4];
    read_at(param_start, 4, ph);
    Processor proc = Processor::kIntel;
    switch (ph[3] - c3d::kProcessorBase) {
      case 1:
        proc = Processor::kIntel;
        info_.processor = "intel";
        break;
      case 2:
        proc = Processor::kDec;
        info_.processor = "dec";
        break;
      case 3:
        proc = Processor::kMips;
        info_.processor = "mips";
        break;
      default:
        warn("unknown processor type byte " + std::to_string(ph[3]) + " at offset " + std::to_string(param_start + 3) +
             "; assuming Intel");
        info_.processor = "intel";
        break;
    }
    processor_code_ = static_cast<int>(proc);
    auto hword = [&](int word) { return c3d::LoadU16(proc, h + 2 * (word - 1)); };
    auto hfloat = [&](int word) { return c3d::LoadF32(proc, h + 2 * (word - 1)); };
    const int64_t h_points = hword(2);
    const int64_t h_analog_words = hword(3);
    const int64_t h_first = hword(4);
    const int64_t h_last = hword(5);
    const float h_scale = hfloat(7);
    const int64_t h_data_start = hword(9);
    const int64_t h_subframes = hword(10);
    const float h_rate = hfloat(11);

    // --- parameter section ---
    int64_t nblocks = ph[2];
    int64_t section_size = nblocks * c3d::kBlock;
    if (nblocks == 0) {
      warn("parameter section declares 0 blocks; reading it up to the data or the end of the file");
      section_size = std::min<int64_t>(255 * c3d::kBlock, file_size_ - param_start);
      if (h_data_start > param_block) {
        section_size = std::min(section_size, (h_data_start - param_block) * c3d::kBlock);
      }
    }
    std::string cut_note;
    if (h_data_start > param_block && nblocks > 0) {
      // The data start bounds the section: some writers under-declare the block count
      // (sample_13 Dance1.c3d), others let the section overlap the data (sample_18).
      if (h_data_start - param_block < nblocks) {
        cut_note = " (the section, declared as " + std::to_string(nblocks) + " blocks, is cut where the data starts)";
      }
      section_size = std::min<int64_t>(h_data_start - param_block, 255) * c3d::kBlock;
    }
    if (param_start + section_size > file_size_) {
      warn("parameter section (" + std::to_string(nblocks) + " blocks) runs past the end of the file");
      section_size = file_size_ - param_start;
    }
    std::vector<unsigned char> sec(static_cast<size_t>(section_size));
    read_at(param_start, section_size, sec.data());

    ParamTable table = ParseParameters(sec, param_start, proc, cut_note, warn);
    if (!table.HasGroup("POINT")) warn("no POINT group in the parameter section");

    // --- storage, scale, units ---
    const Param* p_scale = table.Find("POINT", "SCALE");
    std::optional<double> scale = Number(p_scale, proc);
    if (!scale) {
      warn("POINT:SCALE missing; using the header scale");
      scale = h_scale;
    } else if ((*scale < 0) != (h_scale < 0)) {
      warn("POINT:SCALE and the header scale disagree on the storage type; using the header");
      scale = h_scale;
    }
    info_.point_scale = *scale;
    is_float_ = *scale < 0;
    info_.storage = is_float_ ? "float" : "int16";
    scale_abs_ = std::fabs(*scale);
    if (!is_float_ && scale_abs_ == 0) warn("POINT:SCALE is 0 for int16 storage: all points read as 0");
    std::vector<std::string> units = Strings(table.Find("POINT", "UNITS"));
    info_.units = units.empty() ? "" : units[0];
    mm_per_unit_ = MillimetresPerUnit(info_.units);
    if (units.empty()) {
      warn("POINT:UNITS missing; assuming millimetres");
    } else if (mm_per_unit_ == 0) {
      warn("unknown POINT:UNITS " + Quote(info_.units) + "; assuming millimetres");
      mm_per_unit_ = 1.0;
    }

    // --- points ---
    info_.points = h_points;
    if (auto used = Number(table.Find("POINT", "USED"), proc)) {
      int64_t u = ToInt(*used) & 0xFFFF;
      if (u != h_points) {
        warn("POINT:USED (" + std::to_string(u) + ") differs from the header (" + std::to_string(h_points) +
             "); using the header");
      }
    }
    info_.point_rate_hz = h_rate;
    if (auto rate = Number(table.Find("POINT", "RATE"), proc)) {
      if (std::fabs(*rate - h_rate) > 1e-3 * std::max(1.0, std::fabs(*rate))) {
        warn("POINT:RATE (" + std::to_string(*rate) + ") differs from the header rate (" + std::to_string(h_rate) +
             ")");
      }
    }
    info_.labels = StringSeries(table, "POINT", "LABELS");
    info_.descriptions = StringSeries(table, "POINT", "DESCRIPTIONS");
    if (static_cast<int64_t>(info_.labels.size()) < info_.points) {
      if (info_.points > 0) {
        warn("POINT:LABELS has " + std::to_string(info_.labels.size()) + " labels for " + std::to_string(info_.points) +
             " points; naming the rest by number");
      }
      for (int64_t i = static_cast<int64_t>(info_.labels.size()); i < info_.points; ++i) {
        info_.labels.push_back("Point" + std::to_string(i + 1));
      }
    }
    info_.labels.resize(static_cast<size_t>(info_.points));
    if (static_cast<int64_t>(info_.descriptions.size()) > info_.points) {
      info_.descriptions.resize(static_cast<size_t>(info_.points));
    }

    // --- analog ---
    // Layout: header word 3 (values per frame) and word 10 (samples per frame). When
    // word 3 disagrees with ANALOG:USED x samples (sample_24 MotionMonitorC3D.c3d stores
    // the channel count there), the layout that matches the file size wins.
    const int64_t word_bytes = is_float_ ? 4 : 2;
    const int64_t h_data_offset = (std::max<int64_t>(h_data_start, 1) - 1) * c3d::kBlock;
    const int64_t declared_frames = h_last >= h_first ? h_last - h_first + 1 : 0;
    auto fits = [&](int64_t analog_words) {
      int64_t fb = (4 * info_.points + analog_words) * word_bytes;
      if (fb <= 0 || declared_frames == 0) return false;
      int64_t left = file_size_ - h_data_offset - declared_frames * fb;
      return left >= 0 && left < std::max<int64_t>(c3d::kBlock, fb);
    };
    std::optional<double> analog_used = Number(table.Find("ANALOG", "USED"), proc);
    int64_t subframes = h_subframes;
    analog_words_ = h_analog_words;
    if (analog_used && *analog_used > 0 && subframes > 0) {
      const int64_t used = ToInt(*analog_used) & 0xFFFF;
      if (used * subframes != h_analog_words && !fits(h_analog_words) && fits(used * subframes)) {
        warn("header analog values per frame (" + std::to_string(h_analog_words) + ") disagrees with ANALOG:USED (" +
             std::to_string(used) + ") x " + std::to_string(subframes) +
             " samples per frame; the file size matches the latter");
        analog_words_ = used * subframes;
      }
    }
    if (analog_words_ > 0) {
      if (subframes == 0) {
        throw ParseError(at(18), "header has " + std::to_string(analog_words_) +
                                     " analog values per frame but 0 analog samples per frame");
      }
      if (analog_words_ % subframes != 0) {
        warn("header analog values per frame (" + std::to_string(analog_words_) +
             ") is not a multiple of the samples per frame (" + std::to_string(subframes) + ")");
      }
      info_.analog_channels = analog_words_ / subframes;
    }
    info_.analog_subframes_per_frame = subframes;
    const int64_t channels = info_.analog_channels;
    if (auto used = Number(table.Find("ANALOG", "USED"), proc)) {
      int64_t u = ToInt(*used) & 0xFFFF;
      if (u != channels) {
        warn("ANALOG:USED (" + std::to_string(u) + ") differs from the header (" + std::to_string(channels) +
             " channels); using the header");
      }
    }
    info_.analog_rate_hz = h_rate * static_cast<double>(subframes);
    if (auto rate = Number(table.Find("ANALOG", "RATE"), proc); rate && channels > 0) {
      if (std::fabs(*rate - info_.analog_rate_hz) > 1e-3 * std::max(1.0, *rate)) {
        warn("ANALOG:RATE (" + std::to_string(*rate) + ") is not the point rate x " + std::to_string(subframes) +
             " samples per frame; using " + std::to_string(info_.analog_rate_hz) + " Hz");
      }
    }
    info_.analog_labels = StringSeries(table, "ANALOG", "LABELS");
    info_.analog_units = StringSeries(table, "ANALOG", "UNITS");
    info_.analog_descriptions = StringSeries(table, "ANALOG", "DESCRIPTIONS");
    for (int64_t i = static_cast<int64_t>(info_.analog_labels.size()); i < channels; ++i) {
      info_.analog_labels.push_back("Analog" + std::to_string(i + 1));
    }
    info_.analog_labels.resize(static_cast<size_t>(channels));
    info_.analog_units.resize(static_cast<size_t>(channels));
    if (static_cast<int64_t>(info_.analog_descriptions.size()) > channels) {
      info_.analog_descriptions.resize(static_cast<size_t>(channels));
    }
    std::vector<std::string> format = Strings(table.Find("ANALOG", "FORMAT"));
    analog_unsigned_ = !format.empty() && Upper(format[0]) == "UNSIGNED";
    if (channels > 0) {
      std::optional<double> gen = Number(table.Find("ANALOG", "GEN_SCALE"), proc);
      if (!gen) {
        warn("ANALOG:GEN_SCALE missing; using 1");
        gen = 1.0;
      }
      std::vector<double> scales = Numbers(table.Find("ANALOG", "SCALE"), proc);
      if (static_cast<int64_t>(scales.size()) < channels) {
        warn("ANALOG:SCALE has " + std::to_string(scales.size()) + " values for " + std::to_string(channels) +
             " channels; using 1 for the rest");
        scales.resize(static_cast<size_t>(channels), 1.0);
      }
      const Param* p_off = table.Find("ANALOG", "OFFSET");
      std::vector<double> offsets;
      if (p_off && p_off->type == 2) {
        for (uint32_t w : Words(p_off, proc)) {
          offsets.push_back(analog_unsigned_ ? static_cast<double>(w) : static_cast<double>(static_cast<int16_t>(w)));
        }
      } else if (p_off) {
        offsets = Numbers(p_off, proc);
        warn("ANALOG:OFFSET is stored as type " + std::to_string(p_off->type) + " instead of int16; using its values");
      }
      if (static_cast<int64_t>(offsets.size()) < channels) {
        warn("ANALOG:OFFSET has " + std::to_string(offsets.size()) + " values for " + std::to_string(channels) +
             " channels; using 0 for the rest");
        offsets.resize(static_cast<size_t>(channels), 0.0);
      }
      analog_offset_.resize(static_cast<size_t>(channels));
      analog_scale_.resize(static_cast<size_t>(channels));
      for (int64_t c = 0; c < channels; ++c) {
        analog_offset_[c] = static_cast<float>(offsets[c]);
        analog_scale_[c] = static_cast<float>(scales[c] * *gen);
      }
    }

    // --- data start and frames ---
    int64_t data_start = h_data_start;
    if (auto ds = Number(table.Find("POINT", "DATA_START"), proc)) {
      int64_t v = ToInt(*ds) & 0xFFFF;
      if (v != h_data_start) {
        warn("POINT:DATA_START (" + std::to_string(v) + ") differs from the header (" + std::to_string(h_data_start) +
             ")");
        if (h_data_start <= param_block && v > param_block) data_start = v;
      }
    }
    if (data_start <= param_block) {
      throw ParseError(at(16), "data start block " + std::to_string(data_start) +
                                   " does not follow the parameter block " + std::to_string(param_block));
    }
    frame_bytes_ = (4 * info_.points + analog_words_) * word_bytes;
    data_offset_ = (data_start - 1) * c3d::kBlock;

    int64_t first = h_first;
    int64_t frames = h_last >= h_first ? h_last - h_first + 1 : 0;
    if (h_last < h_first && !(h_first == 1 && h_last == 0)) {
      warn("header last frame " + std::to_string(h_last) + " precedes the first frame " + std::to_string(h_first));
    }
    std::vector<uint32_t> ts = Words(table.Find("TRIAL", "ACTUAL_START_FIELD"), proc);
    std::vector<uint32_t> te = Words(table.Find("TRIAL", "ACTUAL_END_FIELD"), proc);
    if (ts.size() >= 2 && te.size() >= 2) {
      int64_t t_first = ts[0] + (int64_t{ts[1]} << 16);
      int64_t t_last = te[0] + (int64_t{te[1]} << 16);
      if (t_last >= t_first && (t_last - t_first + 1 > frames || t_first > first)) {
        first = t_first;
        frames = t_last - t_first + 1;
      }
    }
    if (const Param* pf = table.Find("POINT", "FRAMES")) {
      int64_t n = -1;
      if (pf->type == 2) {
        std::vector<uint32_t> w = Words(pf, proc);
        if (!w.empty()) n = w[0];
      } else if (pf->type == 4) {
        std::optional<double> v = Number(pf, proc);
        if (v && *v >= 0 && *v < 1e12) n = static_cast<int64_t>(*v);
      }
      if (n > frames) frames = n;
    }
    if (first < 1) {
      warn("first frame " + std::to_string(first) + " is below 1; using 1");
      first = 1;
    }
    info_.first_frame = first;
    if (frame_bytes_ > 0) {
      int64_t available = data_offset_ >= file_size_ ? 0 : (file_size_ - data_offset_) / frame_bytes_;
      if (available < frames) {
        warn("file declares " + std::to_string(frames) + " frames but holds " + std::to_string(available) +
             "; reading " + std::to_string(available));
        frames = available;
      }
    }
    info_.frames = frames;

    info_.events = ReadEvents(h, table, proc, warn);
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
}

C3dReader::~C3dReader() {
  if (fd_ >= 0) ::close(fd_);
}

const unsigned char* C3dReader::LoadFrames(int64_t first, int64_t count) {
  const int64_t bytes = count * frame_bytes_;
  if (static_cast<int64_t>(buffer_.size()) < bytes) buffer_.resize(static_cast<size_t>(bytes));
  const int64_t offset = data_offset_ + first * frame_bytes_;
  int64_t done = 0;
  while (done < bytes) {
    ssize_t r = ::pread(fd_, buffer_.data() + done, static_cast<size_t>(bytes - done), offset + done);
    if (r < 0 && errno == EINTR) continue;
    if (r < 0) throw IoError(path_, std::string("read failed: ") + std::strerror(errno));
    if (r == 0) throw ParseError({path_, offset + done, std::nullopt}, "unexpected end of file in frame data");
    done += r;
  }
  return buffer_.data();
}

void C3dReader::ReadFrames(int64_t first, int64_t count, float* points_mm, float* residuals, float* analog) {
  if (first < 0 || count < 0 || first > info_.frames || count > info_.frames - first) {
    throw InvalidInput(path_ + ": frames [" + std::to_string(first) + ", " + std::to_string(first + count) +
                       ") are outside the " + std::to_string(info_.frames) + " frames of the file");
  }
  if (count == 0 || frame_bytes_ == 0) return;
  const int64_t chunk = std::max<int64_t>(1, kChunkBytes / frame_bytes_);
  const int64_t channels = info_.analog_channels;
  ConvertArgs a{};
  a.points = info_.points;
  a.analog_words = channels * info_.analog_subframes_per_frame;
  a.channels = channels;
  a.frame_bytes = frame_bytes_;
  a.scale = static_cast<float>(scale_abs_);
  a.mm = static_cast<float>(mm_per_unit_);
  a.residual_scale = static_cast<float>(scale_abs_ * mm_per_unit_);
  a.analog_unsigned = analog_unsigned_;
  a.analog_offset = analog_offset_.data();
  a.analog_scale = analog_scale_.data();
  for (int64_t done = 0; done < count; done += chunk) {
    int64_t n = std::min(chunk, count - done);
    a.src = LoadFrames(first + done, n);
    a.count = n;
    a.points_mm = points_mm ? points_mm + done * info_.points * 3 : nullptr;
    a.residuals = residuals ? residuals + done * info_.points : nullptr;
    a.analog = analog ? analog + done * a.analog_words : nullptr;
    auto proc = static_cast<Processor>(processor_code_);
    if (is_float_) {
      switch (proc) {
        case Processor::kDec:
          Convert<Processor::kDec, true>(a);
          break;
        case Processor::kMips:
          Convert<Processor::kMips, true>(a);
          break;
        case Processor::kIntel:
          Convert<Processor::kIntel, true>(a);
          break;
      }
    } else {
      switch (proc) {
        case Processor::kDec:
          Convert<Processor::kDec, false>(a);
          break;
        case Processor::kMips:
          Convert<Processor::kMips, false>(a);
          break;
        case Processor::kIntel:
          Convert<Processor::kIntel, false>(a);
          break;
      }
    }
  }
}

void C3dReader::ValidPointStats(int64_t* valid_samples, double* sum_xyz_valid) {
  *valid_samples = 0;
  *sum_xyz_valid = 0.0;
  if (frame_bytes_ == 0 || info_.points == 0) return;
  const int64_t chunk = std::max<int64_t>(1, kChunkBytes / frame_bytes_);
  auto proc = static_cast<Processor>(processor_code_);
  for (int64_t done = 0; done < info_.frames; done += chunk) {
    int64_t n = std::min(chunk, info_.frames - done);
    const unsigned char* src = LoadFrames(done, n);
    auto run = [&]<Processor kP>() {
      if (is_float_) {
        Stats<kP, true>(src, n, info_.points, frame_bytes_, scale_abs_, valid_samples, sum_xyz_valid);
      } else {
        Stats<kP, false>(src, n, info_.points, frame_bytes_, scale_abs_, valid_samples, sum_xyz_valid);
      }
    };
    switch (proc) {
      case Processor::kDec:
        run.operator()<Processor::kDec>();
        break;
      case Processor::kMips:
        run.operator()<Processor::kMips>();
        break;
      case Processor::kIntel:
        run.operator()<Processor::kIntel>();
        break;
    }
  }
}

Take ReadC3d(const std::string& path) {
  C3dReader reader(path);
  const C3dInfo& info = reader.info();
  Take take;
  take.name = std::filesystem::path(path).stem().string();
  take.rate_hz = info.point_rate_hz;
  take.first_frame = info.first_frame;
  take.marker_names = info.labels;
  take.source_units = info.units.empty() ? "mm" : info.units;
  take.markers.Resize(info.frames, info.points);
  take.analog.rate_hz = info.analog_rate_hz;
  take.analog.names = info.analog_labels;
  take.analog.units = info.analog_units;
  take.analog.descriptions = info.analog_descriptions;
  take.analog.samples = info.analog_channels > 0 ? info.frames * info.analog_subframes_per_frame : 0;
  take.analog.data.resize(static_cast<size_t>(take.analog.samples * info.analog_channels));
  reader.ReadFrames(0, info.frames, take.markers.data().data(), nullptr,
                    info.analog_channels > 0 ? take.analog.data.data() : nullptr);
  take.events = info.events;
  take.provenance.warnings = info.warnings;
  take.provenance.sources.push_back(SourceFile{path, Sha256OfFile(path), "c3d"});
  return take;
}

}  // namespace csw
