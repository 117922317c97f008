#include "io/formats/trc.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <string_view>
#include <vector>

#include "core/error.h"
#include "core/file_util.h"
#include "core/sha256.h"
#include "io/formats/text_util.h"

namespace csw {

namespace {

using formats_internal::ParseFiniteDouble;
using formats_internal::ParseInt;
using formats_internal::Trim;

// Walks the lines of a text without copying them; strips a trailing '\r'.
class LineCursor {
 public:
  explicit LineCursor(std::string_view text) : text_(text) {}
  bool Next(std::string_view* line) {
    if (pos_ >= text_.size()) return false;
    size_t end = text_.find('\n', pos_);
    if (end == std::string_view::npos) end = text_.size();
    std::string_view l = text_.substr(pos_, end - pos_);
    if (!l.empty() && l.back() == '\r') l.remove_suffix(1);
    pos_ = end + 1;
    ++line_;
    *line = l;
    return true;
  }
  int64_t line() const { return line_; }

 private:
  std::string_view text_;
  size_t pos_ = 0;
  int64_t line_ = 0;
};

// Tab-separated fields; a line without any tab is split on runs of spaces.
void SplitFields(std::string_view line, std::vector<std::string_view>* fields) {
  fields->clear();
  if (line.find('\t') != std::string_view::npos) {
    size_t start = 0;
    while (true) {
      size_t tab = line.find('\t', start);
      if (tab == std::string_view::npos) {
        fields->push_back(line.substr(start));
        break;
      }
      fields->push_back(line.substr(start, tab - start));
      start = tab + 1;
    }
    return;
  }
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && line[i] == ' ') ++i;
    if (i >= line.size()) break;
    size_t j = i;
    while (j < line.size() && line[j] != ' ') ++j;
    fields->push_back(line.substr(i, j - i));
    i = j;
  }
}

bool StartsWithNoCase(std::string_view s, std::string_view prefix) {
  if (s.size() < prefix.size()) return false;
  for (size_t i = 0; i < prefix.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(s[i])) != std::tolower(static_cast<unsigned char>(prefix[i]))) {
      return false;
    }
  }
  return true;
}

bool IsNanToken(std::string_view s) {
  if (!s.empty() && (s.front() == '-' || s.front() == '+')) s.remove_prefix(1);
  return s.size() == 3 && StartsWithNoCase(s, "nan");
}

// Largest |coordinate| in millimetres accepted from a file.
constexpr double kMaxCoordinateMm = 1e12;
// Accepted frame rates and frame numbers.
constexpr double kMinRateHz = 1e-6;
constexpr double kMaxRateHz = 1e7;
constexpr int64_t kMaxFrameNumber = int64_t{1} << 50;

}  // namespace

Take ReadTrc(const std::string& path) {
  const std::string bytes = formats_internal::ReadFileBytes(path);
  if (bytes.empty()) {
    throw ParseError({path, 0, std::nullopt}, "file is empty (0 bytes); not a TRC file");
  }
  const std::string text = formats_internal::DecodeText(bytes, path);
  const int64_t file_size = static_cast<int64_t>(bytes.size());
  auto error = [&](int64_t line, const std::string& what) -> ParseError {
    return ParseError({path, std::nullopt, line}, what);
  };

  Take take;
  take.name = std::filesystem::path(path).stem().string();
  std::vector<std::string>& warnings = take.provenance.warnings;

  LineCursor cursor(text);
  std::string_view line;
  std::vector<std::string_view> fields;

  // Line 1: PathFileType.
  if (!cursor.Next(&line) || !StartsWithNoCase(Trim(line), "PathFileType")) {
    throw error(1, "not a TRC file (the first line does not start with PathFileType)");
  }
  // Lines 2 and 3: header keys and values.
  std::string_view keys_line, values_line;
  if (!cursor.Next(&keys_line)) {
    throw error(2, "unexpected end of file: the header keys line (DataRate ...) is missing");
  }
  if (!cursor.Next(&values_line)) {
    throw error(3, "unexpected end of file: the header values line is missing");
  }
  std::vector<std::string_view> keys;
  SplitFields(keys_line, &keys);
  SplitFields(values_line, &fields);
  std::map<std::string, std::string> header;
  for (size_t i = 0; i < keys.size(); ++i) {
    std::string key(Trim(keys[i]));
    if (key.empty()) continue;
    if (i < fields.size()) {
      header[key] = std::string(Trim(fields[i]));
    } else {
      warnings.push_back("TRC header: no value for " + key);
    }
  }
  auto header_number = [&](const std::string& key) -> std::optional<double> {
    auto it = header.find(key);
    if (it == header.end()) return std::nullopt;
    return ParseFiniteDouble(it->second);
  };
  auto plausible = [](std::optional<double> r) { return r && *r >= kMinRateHz && *r <= kMaxRateHz; };
  std::optional<double> rate = header_number("DataRate");
  if (!plausible(rate)) {
    std::optional<double> camera = header_number("CameraRate");
    if (!plausible(camera)) {
      throw error(3,
                  "no valid DataRate or CameraRate in the header (a number between 1e-6 and "
                  "1e7 Hz is required)");
    }
    warnings.push_back("TRC header: DataRate missing or invalid; CameraRate " +
                       formats_internal::FormatDouble(*camera) + " Hz used");
    rate = camera;
  }
  take.rate_hz = *rate;
  double mm_per_unit = 1.0;
  if (auto it = header.find("Units"); it == header.end() || it->second.empty()) {
    warnings.push_back("TRC header: no Units; millimetres assumed");
    take.source_units = "mm";
  } else {
    take.source_units = it->second;
    mm_per_unit = MillimetresPerUnit(it->second);
    if (mm_per_unit <= 0) {
      warnings.push_back("TRC header: unknown Units '" + it->second + "'; millimetres assumed");
      mm_per_unit = 1.0;
    }
  }
  std::optional<int64_t> declared_frames, declared_markers;
  if (auto v = header_number("NumFrames"); v && *v >= 0 && *v == std::floor(*v) && *v < 1e15) {
    declared_frames = static_cast<int64_t>(*v);
  }
  if (auto v = header_number("NumMarkers"); v && *v >= 0 && *v == std::floor(*v) && *v < 1e15) {
    declared_markers = static_cast<int64_t>(*v);
  }

  // Line 4: Frame# Time name ...
  if (!cursor.Next(&line)) {
    throw error(4, "unexpected end of file: the marker names line (Frame# Time ...) is missing");
  }
  SplitFields(line, &fields);
  if (fields.empty() || !StartsWithNoCase(Trim(fields[0]), "Frame")) {
    throw error(4, "expected the marker names line starting with Frame#");
  }
  std::vector<std::string> names;
  {
    bool off_grid = false;
    for (size_t i = 2; i < fields.size(); ++i) {
      if ((i - 2) % 3 != 0 && !Trim(fields[i]).empty()) off_grid = true;
    }
    if (off_grid) {
      for (size_t i = 2; i < fields.size(); ++i) {
        if (!Trim(fields[i]).empty()) names.emplace_back(Trim(fields[i]));
      }
      warnings.push_back("TRC: marker names are not every third column; read in order");
    } else {
      size_t last = 0;
      for (size_t i = 2; i < fields.size(); i += 3) {
        if (!Trim(fields[i]).empty()) last = (i - 2) / 3 + 1;
      }
      for (size_t m = 0; m < last; ++m) names.emplace_back(Trim(fields[2 + 3 * m]));
    }
  }

  // Data rows, kept compactly until the marker count is known.
  std::vector<float> cells;          // row-major, each row as wide as its own cells
  std::vector<size_t> row_start;     // index into cells
  std::vector<int64_t> row_markers;  // markers present in the row
  int64_t widest_row = 0, widest_line = 0;
  int64_t partial_samples = 0, frame_jumps = 0;
  int64_t first_jump_line = 0;
  int64_t previous_frame = 0;
  bool first_data_line = true;
  bool seen_line5 = false;
  while (cursor.Next(&line)) {
    const int64_t ln = cursor.line();
    if (Trim(line).empty()) continue;
    SplitFields(line, &fields);
    if (!seen_line5) {
      seen_line5 = true;
      // Line 5 holds X1 Y1 Z1 ...; accept files where data follows directly.
      if (!ParseFiniteDouble(Trim(fields[0]))) continue;
    }
    std::string_view frame_field = Trim(fields[0]);
    int64_t frame = 0;
    if (auto f = ParseInt(frame_field)) {
      frame = *f;
    } else if (auto d = ParseFiniteDouble(frame_field); d && *d == std::floor(*d) && std::abs(*d) < 1e15) {
      frame = static_cast<int64_t>(*d);
    } else {
      throw error(ln, "column 1: frame number expected, found '" + std::string(frame_field.substr(0, 40)) + "'");
    }
    if (fields.size() > 1) {
      std::string_view time_field = Trim(fields[1]);
      if (!time_field.empty() && !ParseFiniteDouble(time_field)) {
        throw error(ln, "column 2: time is not a finite number: '" + std::string(time_field.substr(0, 40)) + "'");
      }
    }
    if (frame > kMaxFrameNumber || frame < -kMaxFrameNumber) {
      throw error(ln, "column 1: frame number " + std::string(frame_field.substr(0, 40)) + " is out of range");
    }
    if (first_data_line) {
      take.first_frame = frame;
      first_data_line = false;
    } else if (frame != previous_frame + 1) {
      if (frame_jumps++ == 0) first_jump_line = ln;
    }
    previous_frame = frame;

    size_t last = 0;  // index + 1 of the last non-empty coordinate field
    for (size_t i = 2; i < fields.size(); ++i) {
      if (!Trim(fields[i]).empty()) last = i + 1;
    }
    const int64_t markers_here = last == 0 ? 0 : static_cast<int64_t>((last - 3) / 3 + 1);
    row_start.push_back(cells.size());
    row_markers.push_back(markers_here);
    if (markers_here > widest_row) {
      widest_row = markers_here;
      widest_line = ln;
    }
    for (int64_t m = 0; m < markers_here; ++m) {
      double xyz[3];
      int present = 0;
      for (int k = 0; k < 3; ++k) {
        const size_t col = 2 + 3 * static_cast<size_t>(m) + static_cast<size_t>(k);
        std::string_view cell = col < fields.size() ? Trim(fields[col]) : std::string_view();
        xyz[k] = std::nan("");
        if (cell.empty() || IsNanToken(cell)) continue;
        std::optional<double> v = ParseFiniteDouble(cell);
        if (!v) {
          throw error(ln, "column " + std::to_string(col + 1) + ": not a finite number: '" +
                              std::string(cell.substr(0, 40)) + "'");
        }
        const double mm = *v * mm_per_unit;
        if (std::abs(mm) > kMaxCoordinateMm) {
          throw error(ln, "column " + std::to_string(col + 1) + ": coordinate " + std::string(cell.substr(0, 40)) +
                              " is out of range");
        }
        xyz[k] = mm;
        ++present;
      }
      if (present == 3) {
        for (double c : xyz) cells.push_back(static_cast<float>(c));
      } else {
        if (present > 0) ++partial_samples;
        for (int k = 0; k < 3; ++k) cells.push_back(kMissing);
      }
    }
  }

  const int64_t frames = static_cast<int64_t>(row_start.size());
  const int64_t markers = std::max<int64_t>(static_cast<int64_t>(names.size()), widest_row);
  // Every stored sample needs at least a separator in the file; refuse tables
  // that would be far larger than anything the file can describe.
  if (frames > 0 && markers > 0 && frames * markers * 3 > 8 * file_size + 3 * 4096) {
    throw error(widest_line > 0 ? widest_line : 4, "table of " + std::to_string(frames) + " frames x " +
                                                       std::to_string(markers) + " markers is too large for a " +
                                                       std::to_string(file_size) + "-byte file");
  }
  take.markers.Resize(frames, markers);
  for (int64_t f = 0; f < frames; ++f) {
    const float* src = cells.data() + row_start[static_cast<size_t>(f)];
    std::copy(src, src + row_markers[static_cast<size_t>(f)] * 3, take.markers.at(f, 0));
  }

  // Names: trimmed, generated when absent, made unique.
  names.resize(static_cast<size_t>(markers));
  std::set<std::string> used;
  int64_t generated = 0;
  for (size_t m = 0; m < names.size(); ++m) {
    if (names[m].empty()) {
      names[m] = "unnamed_" + std::to_string(m + 1);
      ++generated;
    }
  }
  for (const std::string& n : names) used.insert(n);
  std::set<std::string> seen;
  for (std::string& n : names) {
    if (seen.insert(n).second) continue;
    std::string base = n;
    int k = 2;
    while (used.count(base + "_" + std::to_string(k))) ++k;
    n = base + "_" + std::to_string(k);
    used.insert(n);
    seen.insert(n);
    warnings.push_back("TRC: duplicate marker name '" + base + "' renamed '" + n + "'");
  }
  take.marker_names = std::move(names);

  if (generated > 0) {
    warnings.push_back("TRC: " + std::to_string(generated) +
                       " marker column(s) without a name were named unnamed_<column>");
  }
  if (declared_markers && *declared_markers != markers) {
    warnings.push_back("TRC header: NumMarkers=" + std::to_string(*declared_markers) + " but " +
                       std::to_string(take.marker_names.size() - generated) + " names and data for " +
                       std::to_string(markers) + " markers; the data are trusted");
  }
  if (declared_frames && *declared_frames != frames) {
    warnings.push_back("TRC header: NumFrames=" + std::to_string(*declared_frames) + " but " + std::to_string(frames) +
                       " data rows" + (frames < *declared_frames ? " (file truncated?)" : ""));
  }
  if (frames == 0) warnings.push_back("TRC: no data rows");
  if (partial_samples > 0) {
    warnings.push_back("TRC: " + std::to_string(partial_samples) +
                       " marker sample(s) with only some of X/Y/Z filled read as missing");
  }
  if (frame_jumps > 0) {
    warnings.push_back("TRC: frame numbers are not consecutive " + std::to_string(frame_jumps) +
                       " time(s) (first at line " + std::to_string(first_jump_line) + "); rows are kept in file order");
  }

  take.provenance.sources.push_back({path, Sha256OfFile(path), "trc"});
  take.provenance.csw_version = CSW_VERSION;
  take.provenance.imported_utc = UtcNow();
  return take;
}

void WriteTrc(const std::string& path, const Take& take) {
  if (!(take.rate_hz > 0) || !std::isfinite(take.rate_hz)) {
    throw InvalidInput("WriteTrc: the take has no positive frame rate");
  }
  if (static_cast<int64_t>(take.marker_names.size()) != take.markers.markers()) {
    throw InvalidInput("WriteTrc: " + std::to_string(take.marker_names.size()) + " marker names for " +
                       std::to_string(take.markers.markers()) + " marker columns");
  }
  const int64_t frames = take.markers.frames();
  const int64_t markers = take.markers.markers();
  const std::string rate = formats_internal::FormatDouble(take.rate_hz);
  std::string out;
  out.reserve(static_cast<size_t>(256 + markers * 40 + frames * (16 + markers * 30)));
  out += "PathFileType\t4\t(X/Y/Z)\t" + std::filesystem::path(path).filename().string() + "\n";
  out +=
      "DataRate\tCameraRate\tNumFrames\tNumMarkers\tUnits\tOrigDataRate\tOrigDataStartFrame"
      "\tOrigNumFrames\n";
  out += rate + "\t" + rate + "\t" + std::to_string(frames) + "\t" + std::to_string(markers) + "\tmm\t" + rate + "\t" +
         std::to_string(take.first_frame) + "\t" + std::to_string(frames) + "\n";
  out += "Frame#\tTime";
  for (const std::string& name : take.marker_names) {
    std::string clean(Trim(name));
    std::replace_if(
        clean.begin(), clean.end(), [](char c) { return c == '\t' || c == '\n' || c == '\r'; }, ' ');
    out += "\t" + clean + "\t\t";
  }
  out += "\n\t";
  for (int64_t m = 1; m <= markers; ++m) {
    const std::string k = std::to_string(m);
    out += "\tX" + k + "\tY" + k + "\tZ" + k;
  }
  out += "\n\n";
  char time_buf[48];
  for (int64_t f = 0; f < frames; ++f) {
    std::snprintf(time_buf, sizeof(time_buf), "%.6f", static_cast<double>(f) / take.rate_hz);
    out += std::to_string(take.first_frame + f);
    out += '\t';
    out += time_buf;
    for (int64_t m = 0; m < markers; ++m) {
      const float* p = take.markers.at(f, m);
      if (IsMissing(p[0]) || IsMissing(p[1]) || IsMissing(p[2])) {
        out += "\t\t\t";
        continue;
      }
      if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
        throw InvalidInput("WriteTrc: infinite coordinate at frame " + std::to_string(f) + ", marker " +
                           take.marker_names[static_cast<size_t>(m)]);
      }
      for (int k = 0; k < 3; ++k) {
        out += '\t';
        out += formats_internal::FormatFloat(p[k]);
      }
    }
    out += '\n';
  }
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw IoError(path, "cannot open for writing");
  file.write(out.data(), static_cast<std::streamsize>(out.size()));
  file.close();
  if (!file) throw IoError(path, "write failed");
}

}  // namespace csw
