#include "io/formats/bvh.h"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <filesystem>
#include <fstream>
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
using formats_internal::Trim;

constexpr double kPi = 3.14159265358979323846;
constexpr double kDegToRad = kPi / 180.0;
constexpr double kMaxPositionMm = 1e12;
constexpr double kMinFrameTimeS = 1e-7;
constexpr double kMaxFrameTimeS = 1e6;

// Channel codes: 0-2 = X/Y/Z position, 3-5 = X/Y/Z rotation.
constexpr const char* kChannelNames[6] = {"Xposition", "Yposition", "Zposition", "Xrotation", "Yrotation", "Zrotation"};

int ChannelCode(std::string_view name) {
  for (int c = 0; c < 6; ++c) {
    std::string_view known(kChannelNames[c]);
    if (name.size() != known.size()) continue;
    bool same = true;
    for (size_t i = 0; i < name.size() && same; ++i) {
      same = std::tolower(static_cast<unsigned char>(name[i])) == std::tolower(static_cast<unsigned char>(known[i]));
    }
    if (same) return c;
  }
  return -1;
}

bool EqualsNoCase(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) return false;
  }
  return true;
}

bool IsSpace(char c) { return c == ' ' || c == '\t' || c == '\v' || c == '\f'; }

// The hierarchy's tokens: words split on whitespace, '{' and '}' always alone.
struct Token {
  std::string_view text;
  int64_t line = 0;
};

// Scans text from pos up to the token MOTION (or the end); returns the tokens,
// sets *motion_end to the offset just after MOTION (npos when absent) and
// *line to the line there.
std::vector<Token> Tokenize(std::string_view text, size_t* motion_end, int64_t* line) {
  std::vector<Token> tokens;
  size_t i = 0;
  int64_t ln = 1;
  *motion_end = std::string_view::npos;
  while (i < text.size()) {
    const char c = text[i];
    if (c == '\n') {
      ++ln;
      ++i;
      continue;
    }
    if (c == '\r') {
      if (i + 1 >= text.size() || text[i + 1] != '\n') ++ln;  // a lone CR ends a line
      ++i;
      continue;
    }
    if (IsSpace(c)) {
      ++i;
      continue;
    }
    if (c == '{' || c == '}') {
      tokens.push_back({text.substr(i, 1), ln});
      ++i;
      continue;
    }
    size_t j = i;
    while (j < text.size() && !IsSpace(text[j]) && text[j] != '\n' && text[j] != '\r' && text[j] != '{' &&
           text[j] != '}') {
      ++j;
    }
    std::string_view word = text.substr(i, j - i);
    i = j;
    if (word == "MOTION") {
      *motion_end = i;
      break;
    }
    tokens.push_back({word, ln});
  }
  *line = ln;
  return tokens;
}

// Walks the lines of the MOTION section; '\n', "\r\n" and a lone '\r' end a line.
class LineCursor {
 public:
  LineCursor(std::string_view text, size_t pos, int64_t line) : text_(text), pos_(pos), line_(line - 1) {}
  bool Next(std::string_view* line) {
    if (pos_ >= text_.size()) return false;
    size_t end = pos_;
    while (end < text_.size() && text_[end] != '\n' && text_[end] != '\r') ++end;
    *line = text_.substr(pos_, end - pos_);
    if (end < text_.size() && text_[end] == '\r' && end + 1 < text_.size() && text_[end + 1] == '\n') ++end;
    pos_ = end + 1;
    ++line_;
    return true;
  }
  int64_t line() const { return line_; }
  size_t remaining() const { return pos_ < text_.size() ? text_.size() - pos_ : 0; }

 private:
  std::string_view text_;
  size_t pos_;
  int64_t line_;
};

// Quaternion of one axis rotation.
Eigen::Quaterniond AxisQuaternion(int axis, double angle_rad) {
  const double h = 0.5 * angle_rad;
  const double s = std::sin(h);
  Eigen::Quaterniond q(std::cos(h), 0, 0, 0);
  q.coeffs()[axis] = s;  // coeffs() is (x, y, z, w)
  return q;
}

// The per-joint plan of forward kinematics, precomputed from the skeleton.
struct JointPlan {
  int parent = -1;
  int first_channel = 0;         // index of the joint's first value in a motion row
  std::vector<int> codes;        // channel codes in file order
  double offset[3] = {0, 0, 0};  // file units
};

// Forward kinematics of one frame in file units: positions (3 per joint) and
// orientations (Eigen quaternions), for a row of channel values.
void ForwardKinematics(const std::vector<JointPlan>& plan, const double* row, std::vector<Eigen::Vector3d>* positions,
                       std::vector<Eigen::Quaterniond>* orientations) {
  for (size_t j = 0; j < plan.size(); ++j) {
    const JointPlan& p = plan[j];
    Eigen::Vector3d t(p.offset[0], p.offset[1], p.offset[2]);
    Eigen::Quaterniond local = Eigen::Quaterniond::Identity();
    for (size_t k = 0; k < p.codes.size(); ++k) {
      const int code = p.codes[k];
      const double v = row[p.first_channel + static_cast<int>(k)];
      if (code < 3) {
        t[code] = v;
      } else {
        local = local * AxisQuaternion(code - 3, v * kDegToRad);
      }
    }
    if (p.parent < 0) {
      (*positions)[j] = t;
      (*orientations)[j] = local;
    } else {
      const Eigen::Quaterniond& parent_q = (*orientations)[static_cast<size_t>(p.parent)];
      (*positions)[j] = (*positions)[static_cast<size_t>(p.parent)] + parent_q * t;
      (*orientations)[j] = parent_q * local;
    }
  }
}

// Parses one number at text[*i], which must end at whitespace or the end.
bool ParseNumber(std::string_view text, size_t* i, double* value) {
  const char* begin = text.data() + *i;
  const char* end = text.data() + text.size();
  if (begin < end && *begin == '+') ++begin;
  if (begin >= end) return false;
  const char c0 = *begin;
  if (!((c0 >= '0' && c0 <= '9') || c0 == '.' || c0 == '-')) return false;
  auto [ptr, ec] = std::from_chars(begin, end, *value, std::chars_format::general);
  if (ec != std::errc() || !std::isfinite(*value)) return false;
  if (ptr < end && !IsSpace(*ptr)) return false;
  *i = static_cast<size_t>(ptr - text.data());
  return true;
}

std::string Quote(std::string_view s) { return "'" + std::string(s.substr(0, 40)) + "'"; }

}  // namespace

double SkeletonRestSize(const std::vector<SkeletonJoint>& skeleton) {
  if (skeleton.empty()) return 0.0;
  std::vector<Eigen::Vector3d> pos(skeleton.size());
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  Eigen::Vector3d hi = -lo;
  for (size_t j = 0; j < skeleton.size(); ++j) {
    const SkeletonJoint& s = skeleton[j];
    Eigen::Vector3d o(s.offset_mm[0], s.offset_mm[1], s.offset_mm[2]);
    const bool root = s.parent < 0 || static_cast<size_t>(s.parent) >= j;
    pos[j] = root ? o : pos[static_cast<size_t>(s.parent)] + o;
    lo = lo.cwiseMin(pos[j]);
    hi = hi.cwiseMax(pos[j]);
  }
  return (hi - lo).maxCoeff();
}

bool IsBvhUnit(const std::string& units) {
  return units == "mm" || units == "cm" || units == "dm" || units == "m" || units == "in";
}

BvhUnitGuess GuessBvhUnits(double size) {
  BvhUnitGuess g;
  g.size = size;
  if (size < std::sqrt(1.7 * 17.0)) {
    g.units = "m";
  } else if (size < std::sqrt(17.0 * 67.0)) {
    g.units = "dm";
  } else if (size < std::sqrt(67.0 * 170.0)) {
    g.units = "in";
  } else if (size < std::sqrt(170.0 * 1700.0)) {
    g.units = "cm";
  } else {
    g.units = "mm";
  }
  g.mm_per_unit = MillimetresPerUnit(g.units);
  return g;
}

Take ParseBvh(std::string_view text, const std::string& path, const BvhReadOptions& options) {
  double mm_per_unit = 0.0;
  if (!options.units.empty()) {
    if (IsBvhUnit(options.units)) {
      mm_per_unit = MillimetresPerUnit(options.units);
    } else {
      throw InvalidInput("BVH units must be mm, cm, dm, m or in, not '" + options.units + "'");
    }
  }
  auto error = [&](int64_t line, const std::string& what) -> ParseError {
    return ParseError({path, std::nullopt, line}, what);
  };
  if (Trim(text).empty()) throw error(1, "file is empty; not a BVH file");

  Take take;
  take.name = std::filesystem::path(path).stem().string();
  std::vector<std::string>& warnings = take.provenance.warnings;

  size_t motion_end = 0;
  int64_t motion_line = 0;
  const std::vector<Token> tokens = Tokenize(text, &motion_end, &motion_line);
  if (tokens.empty() || !EqualsNoCase(tokens[0].text, "HIERARCHY")) {
    throw error(tokens.empty() ? motion_line : tokens[0].line, "not a BVH file (it does not start with HIERARCHY)");
  }

  // The hierarchy, with an explicit stack of open blocks (no recursion).
  std::vector<SkeletonJoint>& skeleton = take.skeleton;
  std::vector<JointPlan> plan;
  std::vector<int64_t> joint_line;
  struct Open {
    int joint;
    bool has_offset;
    bool has_channels;
  };
  std::vector<Open> stack;
  int total_channels = 0;
  size_t i = 1;
  auto need = [&](size_t count, int64_t line, const std::string& what) {
    if (i + count > tokens.size()) throw error(line, "unexpected end of the hierarchy: " + what);
  };
  while (i < tokens.size()) {
    const Token& t = tokens[i];
    const bool is_root = t.text == "ROOT";
    const bool is_joint = t.text == "JOINT";
    const bool is_end = t.text == "End";
    if (is_root || is_joint || is_end) {
      if (is_root && !stack.empty()) throw error(t.line, "ROOT inside a joint's block");
      if ((is_joint || is_end) && stack.empty())
        throw error(t.line, t.text == "End" ? "End Site outside a joint" : "JOINT outside a ROOT's block");
      if (!stack.empty() && skeleton[static_cast<size_t>(stack.back().joint)].end_site) {
        throw error(t.line, "an End Site cannot have children");
      }
      if (static_cast<int>(stack.size()) >= kBvhMaxDepth) {
        throw error(t.line, "joints nested deeper than " + std::to_string(kBvhMaxDepth) + " levels");
      }
      if (static_cast<int>(skeleton.size()) >= kBvhMaxJoints) {
        throw error(t.line, "more than " + std::to_string(kBvhMaxJoints) + " joints");
      }
      ++i;
      SkeletonJoint joint;
      joint.parent = stack.empty() ? -1 : stack.back().joint;
      if (is_end) {
        if (i >= tokens.size() || !EqualsNoCase(tokens[i].text, "Site"))
          throw error(t.line, "'End' not followed by 'Site'");
        const int64_t site_line = tokens[i].line;
        ++i;
        while (i < tokens.size() && tokens[i].line == site_line && tokens[i].text != "{") ++i;  // a name, ignored
        joint.end_site = true;
        joint.name = "End";  // named after the parent once names are unique
      } else {
        std::string name;
        while (i < tokens.size() && tokens[i].line == t.line && tokens[i].text != "{" && tokens[i].text != "}") {
          if (!name.empty()) name += ' ';
          name += tokens[i].text;
          ++i;
        }
        if (name.empty()) throw error(t.line, std::string(t.text) + " without a name");
        joint.name = std::move(name);
      }
      need(1, t.line, "'{' expected after " + std::string(t.text));
      if (tokens[i].text != "{") throw error(tokens[i].line, "'{' expected, found " + Quote(tokens[i].text));
      ++i;
      stack.push_back({static_cast<int>(skeleton.size()), false, false});
      skeleton.push_back(std::move(joint));
      JointPlan p;
      p.parent = skeleton.back().parent;
      plan.push_back(p);
      joint_line.push_back(t.line);
      continue;
    }
    if (t.text == "}") {
      if (stack.empty()) throw error(t.line, "'}' without a matching '{'");
      if (!stack.back().has_offset) {
        throw error(t.line, "joint '" + skeleton[static_cast<size_t>(stack.back().joint)].name + "' has no OFFSET");
      }
      stack.pop_back();
      ++i;
      continue;
    }
    if (stack.empty()) throw error(t.line, "unexpected " + Quote(t.text) + " outside a joint (ROOT expected)");
    Open& open = stack.back();
    SkeletonJoint& joint = skeleton[static_cast<size_t>(open.joint)];
    JointPlan& p = plan[static_cast<size_t>(open.joint)];
    if (t.text == "OFFSET") {
      if (open.has_offset) throw error(t.line, "second OFFSET in joint '" + joint.name + "'");
      need(4, t.line, "OFFSET needs 3 numbers");
      for (int k = 0; k < 3; ++k) {
        const Token& v = tokens[i + 1 + static_cast<size_t>(k)];
        std::optional<double> d = ParseFiniteDouble(v.text);
        if (!d) throw error(v.line, "OFFSET: not a finite number: " + Quote(v.text));
        p.offset[k] = *d;
      }
      open.has_offset = true;
      i += 4;
      continue;
    }
    if (t.text == "CHANNELS") {
      if (joint.end_site) throw error(t.line, "CHANNELS in an End Site");
      if (open.has_channels) throw error(t.line, "second CHANNELS in joint '" + joint.name + "'");
      need(2, t.line, "CHANNELS needs a count");
      std::optional<int64_t> n = formats_internal::ParseInt(tokens[i + 1].text);
      if (!n || *n < 0 || *n > 6) {
        throw error(tokens[i + 1].line, "CHANNELS count must be 0 to 6, found " + Quote(tokens[i + 1].text));
      }
      need(2 + static_cast<size_t>(*n), t.line, "CHANNELS lists fewer names than its count");
      bool seen[6] = {false, false, false, false, false, false};
      for (int64_t k = 0; k < *n; ++k) {
        const Token& c = tokens[i + 2 + static_cast<size_t>(k)];
        const int code = ChannelCode(c.text);
        if (code < 0)
          throw error(c.line, "unknown channel " + Quote(c.text) + " (CHANNELS count " + std::to_string(*n) + ")");
        if (seen[code]) throw error(c.line, "channel " + Quote(c.text) + " repeated in joint '" + joint.name + "'");
        seen[code] = true;
        p.codes.push_back(code);
        joint.channels.emplace_back(kChannelNames[code]);
      }
      p.first_channel = total_channels;
      total_channels += static_cast<int>(*n);
      open.has_channels = true;
      i += 2 + static_cast<size_t>(*n);
      continue;
    }
    throw error(t.line, "unexpected " + Quote(t.text) + " in joint '" + joint.name + "'");
  }
  if (!stack.empty()) {
    throw error(motion_line, "unbalanced braces: joint '" + skeleton[static_cast<size_t>(stack.back().joint)].name +
                                 "' (line " + std::to_string(joint_line[static_cast<size_t>(stack.back().joint)]) +
                                 ") is not closed");
  }
  if (skeleton.empty()) throw error(motion_line, "the HIERARCHY has no ROOT");
  if (motion_end == std::string_view::npos) throw error(motion_line, "unexpected end of file: MOTION is missing");

  // Unique names: joints first, then end sites named after their (renamed) parent.
  for (bool end_sites : {false, true}) {
    if (end_sites) {
      for (SkeletonJoint& s : skeleton) {
        if (s.end_site) s.name = skeleton[static_cast<size_t>(s.parent)].name + "_End";
      }
    }
    std::set<std::string> used;
    for (const SkeletonJoint& s : skeleton) {
      if (end_sites || !s.end_site) used.insert(s.name);
    }
    std::set<std::string> seen;
    for (SkeletonJoint& s : skeleton) {
      if (!end_sites && s.end_site) continue;
      if (seen.insert(s.name).second) continue;
      const std::string base = s.name;
      int k = 2;
      while (used.count(base + "_" + std::to_string(k))) ++k;
      s.name = base + "_" + std::to_string(k);
      used.insert(s.name);
      seen.insert(s.name);
      warnings.push_back(std::string("BVH: duplicate ") + (s.end_site ? "end-site" : "joint") + " name '" + base +
                         "' renamed '" + s.name + "'");
    }
  }

  // Units.
  for (size_t j = 0; j < skeleton.size(); ++j) {
    for (int k = 0; k < 3; ++k) skeleton[j].offset_mm[k] = plan[j].offset[k];
  }
  if (mm_per_unit > 0) {
    take.source_units = options.units;
  } else {
    const BvhUnitGuess guess = GuessBvhUnits(SkeletonRestSize(skeleton));
    mm_per_unit = guess.mm_per_unit;
    take.source_units = guess.units;
    warnings.push_back("BVH has no length unit: guessed '" + guess.units + "' from the skeleton's size of " +
                       formats_internal::FormatDouble(std::round(guess.size * 1000) / 1000) +
                       " file units (taken for a person about 1.7 m tall); give the unit (--units mm|cm|dm|m|in) "
                       "if this is wrong");
  }
  for (SkeletonJoint& s : skeleton) {
    for (double& o : s.offset_mm) {
      o *= mm_per_unit;
      if (std::abs(o) > kMaxPositionMm) {
        throw error(joint_line[static_cast<size_t>(&s - skeleton.data())],
                    "OFFSET of '" + s.name + "' is out of range");
      }
    }
  }

  // MOTION header.
  LineCursor cursor(text, motion_end, motion_line);
  std::string_view line;
  auto next_nonblank = [&](const char* what) {
    while (true) {
      if (!cursor.Next(&line)) {
        throw error(cursor.line() + 1, std::string("unexpected end of file: ") + what + " is missing");
      }
      line = Trim(line);
      if (!line.empty()) return;
    }
  };
  // The rest of MOTION's own line must be blank.
  if (cursor.Next(&line) && !Trim(line).empty())
    throw error(cursor.line(), "unexpected " + Quote(Trim(line)) + " after MOTION");
  auto header_value = [&](std::string_view key) -> std::string_view {
    std::string_view l = line;
    size_t k = 0;
    // The key's words, with any spacing, then ':'.
    for (char c : key) {
      if (c == ' ') {
        while (k < l.size() && IsSpace(l[k])) ++k;
        continue;
      }
      if (k >= l.size() ||
          std::tolower(static_cast<unsigned char>(l[k])) != std::tolower(static_cast<unsigned char>(c))) {
        throw error(cursor.line(), "'" + std::string(key) + ":' expected, found " + Quote(l));
      }
      ++k;
    }
    while (k < l.size() && IsSpace(l[k])) ++k;
    if (k >= l.size() || l[k] != ':')
      throw error(cursor.line(), "'" + std::string(key) + ":' expected, found " + Quote(l));
    return Trim(l.substr(k + 1));
  };
  next_nonblank("the 'Frames:' line");
  std::string_view frames_text = header_value("Frames");
  std::optional<int64_t> declared = formats_internal::ParseInt(frames_text);
  if (!declared || *declared < 0) throw error(cursor.line(), "Frames: not a frame count: " + Quote(frames_text));
  const int64_t frames_line = cursor.line();
  next_nonblank("the 'Frame Time:' line");
  std::string_view time_text = header_value("Frame Time");
  std::optional<double> frame_time = ParseFiniteDouble(time_text);
  if (!frame_time || *frame_time < kMinFrameTimeS || *frame_time > kMaxFrameTimeS) {
    throw error(cursor.line(), "Frame Time must be a number of seconds in [1e-7, 1e6], found " + Quote(time_text));
  }
  take.rate_hz = 1.0 / *frame_time;

  const int64_t frames = *declared;
  const int64_t markers = static_cast<int64_t>(skeleton.size());
  const int64_t bytes_left = static_cast<int64_t>(cursor.remaining());
  if (frames > 0 && total_channels == 0) {
    throw error(frames_line, "Frames: " + std::to_string(frames) + " but the hierarchy declares no channels");
  }
  // Every value needs at least one character and one separator.
  if (frames > 0 &&
      (frames > (bytes_left + 1) / 2 / total_channels || frames > (8 * (bytes_left + 1) + 4096) / markers)) {
    throw error(frames_line, "Frames: " + std::to_string(frames) + " rows of " + std::to_string(total_channels) +
                                 " values cannot fit in the " + std::to_string(bytes_left) +
                                 " bytes left in the file (truncated or damaged)");
  }

  take.marker_names.reserve(skeleton.size());
  for (const SkeletonJoint& s : skeleton) take.marker_names.push_back(s.name);
  take.markers.Resize(frames, markers);
  take.orientations.Resize(frames, markers);
  std::vector<double> row(static_cast<size_t>(total_channels));
  std::vector<Eigen::Vector3d> positions(skeleton.size());
  std::vector<Eigen::Quaterniond> orientations(skeleton.size());
  const double max_position_units = kMaxPositionMm / mm_per_unit;
  int64_t f = 0;
  while (f < frames) {
    if (!cursor.Next(&line)) {
      throw error(cursor.line() + 1, "unexpected end of file: Frames: " + std::to_string(frames) + " but only " +
                                         std::to_string(f) + " motion rows (truncated file)");
    }
    size_t k = 0;
    int count = 0;
    while (true) {
      while (k < line.size() && IsSpace(line[k])) ++k;
      if (k >= line.size()) break;
      double v = 0;
      const size_t start = k;
      if (!ParseNumber(line, &k, &v)) {
        size_t e = start;
        while (e < line.size() && !IsSpace(line[e])) ++e;
        throw error(cursor.line(), "value " + std::to_string(count + 1) +
                                       ": not a finite number: " + Quote(line.substr(start, e - start)));
      }
      if (count < total_channels) row[static_cast<size_t>(count)] = v;
      ++count;
    }
    if (count == 0) continue;  // blank line
    if (count != total_channels) {
      throw error(cursor.line(), "motion row " + std::to_string(f + 1) + " has " + std::to_string(count) +
                                     " values, the hierarchy declares " + std::to_string(total_channels) + " channels");
    }
    ForwardKinematics(plan, row.data(), &positions, &orientations);
    float* out_p = take.markers.at(f, 0);
    float* out_q = take.orientations.at(f, 0);
    for (size_t j = 0; j < positions.size(); ++j) {
      const Eigen::Vector3d& p = positions[j];
      if (!(std::abs(p.x()) <= max_position_units && std::abs(p.y()) <= max_position_units &&
            std::abs(p.z()) <= max_position_units)) {
        throw error(cursor.line(), "position of joint '" + skeleton[j].name + "' is out of range (> 1e12 mm)");
      }
      for (int c = 0; c < 3; ++c) out_p[3 * j + static_cast<size_t>(c)] = static_cast<float>(p[c] * mm_per_unit);
      Eigen::Quaterniond q = orientations[j].normalized();
      if (q.w() < 0) q.coeffs() = -q.coeffs();
      out_q[4 * j + 0] = static_cast<float>(q.w());
      out_q[4 * j + 1] = static_cast<float>(q.x());
      out_q[4 * j + 2] = static_cast<float>(q.y());
      out_q[4 * j + 3] = static_cast<float>(q.z());
    }
    ++f;
  }
  while (cursor.Next(&line)) {
    if (!Trim(line).empty()) {
      throw error(cursor.line(), "more motion rows than Frames: " + std::to_string(frames) + " declares");
    }
  }
  if (frames == 0) warnings.push_back("BVH: Frames: 0 (no motion)");
  return take;
}

Take ReadBvh(const std::string& path, const BvhReadOptions& options) {
  const std::string bytes = formats_internal::ReadFileBytes(path);
  if (bytes.empty()) throw ParseError({path, 0, std::nullopt}, "file is empty (0 bytes); not a BVH file");
  const std::string text = formats_internal::DecodeText(bytes, path);
  Take take = ParseBvh(text, path, options);
  take.provenance.sources.push_back({path, Sha256OfFile(path), "bvh"});
  take.provenance.csw_version = CSW_VERSION;
  take.provenance.imported_utc = UtcNow();
  return take;
}

void QuaternionToEuler(const double q_wxyz[4], const int axes[3], double angles[3]) {
  const Eigen::Matrix3d r =
      Eigen::Quaterniond(q_wxyz[0], q_wxyz[1], q_wxyz[2], q_wxyz[3]).normalized().toRotationMatrix();
  const int i = axes[0], j = axes[1], k = axes[2];
  // +1 when (i, j, k) is a cyclic permutation of (x, y, z).
  const double s = ((j - i + 3) % 3 == 1) ? 1.0 : -1.0;
  const double sin_b = std::clamp(s * r(i, k), -1.0, 1.0);
  angles[1] = std::asin(sin_b);
  if (std::abs(sin_b) < 1.0 - 1e-12) {
    angles[0] = std::atan2(-s * r(j, k), r(k, k));
    angles[2] = std::atan2(-s * r(i, j), r(i, i));
  } else {
    // Gimbal lock: only a + c (or a - c) is determined; c = 0, and column j
    // of R = R_i(a)·R_j(b) is R_i(a)·e_j.
    angles[0] = std::atan2(s * r(k, j), r(j, j));
    angles[2] = 0.0;
  }
}

std::string FormatBvh(const Take& take, const BvhWriteOptions& options) {
  const std::vector<SkeletonJoint>& skeleton = take.skeleton;
  const int64_t joints = static_cast<int64_t>(skeleton.size());
  if (joints == 0) throw InvalidInput("WriteBvh: take '" + take.name + "' has no skeleton");
  if (!(take.rate_hz > 0) || !std::isfinite(take.rate_hz)) {
    throw InvalidInput("WriteBvh: take '" + take.name + "' has no positive frame rate");
  }
  if (take.markers.markers() != joints || static_cast<int64_t>(take.marker_names.size()) != joints) {
    throw InvalidInput("WriteBvh: take '" + take.name + "' has " + std::to_string(take.markers.markers()) +
                       " markers and " + std::to_string(take.marker_names.size()) + " names for " +
                       std::to_string(joints) + " skeleton joints");
  }
  const int64_t frames = take.markers.frames();
  if (take.orientations.joints() != joints || take.orientations.frames() != frames) {
    throw InvalidInput("WriteBvh: take '" + take.name + "' has orientations of " +
                       std::to_string(take.orientations.frames()) + " frames x " +
                       std::to_string(take.orientations.joints()) + " joints for " + std::to_string(frames) +
                       " frames x " + std::to_string(joints) + " joints");
  }
  std::string units = options.units;
  if (units.empty()) {
    const std::string& su = take.source_units;
    units = IsBvhUnit(su) ? su : "mm";
  }
  if (!IsBvhUnit(units)) {
    throw InvalidInput("WriteBvh: units must be mm, cm, dm, m or in, not '" + units + "'");
  }
  const double unit_per_mm = 1.0 / MillimetresPerUnit(units);

  // Validate the skeleton and plan the channels.
  std::vector<std::vector<int>> children(static_cast<size_t>(joints));
  std::vector<std::vector<int>> codes(static_cast<size_t>(joints));
  for (int64_t j = 0; j < joints; ++j) {
    const SkeletonJoint& s = skeleton[static_cast<size_t>(j)];
    if (s.parent >= j || s.parent < -1) {
      throw InvalidInput("WriteBvh: joint '" + s.name + "' has parent " + std::to_string(s.parent) +
                         " (parents must come before their children)");
    }
    if (s.parent >= 0) {
      if (skeleton[static_cast<size_t>(s.parent)].end_site) {
        throw InvalidInput("WriteBvh: joint '" + s.name + "' is the child of an End Site");
      }
      children[static_cast<size_t>(s.parent)].push_back(static_cast<int>(j));
    }
    if (s.end_site && !s.channels.empty()) throw InvalidInput("WriteBvh: End Site '" + s.name + "' has channels");
    if (s.end_site && s.parent < 0) throw InvalidInput("WriteBvh: End Site '" + s.name + "' has no parent");
    bool seen[6] = {false, false, false, false, false, false};
    for (const std::string& c : s.channels) {
      const int code = ChannelCode(c);
      if (code < 0 || seen[code]) {
        throw InvalidInput("WriteBvh: joint '" + s.name + "' has an unknown or repeated channel '" + c + "'");
      }
      seen[code] = true;
      codes[static_cast<size_t>(j)].push_back(code);
    }
    for (double o : s.offset_mm) {
      if (!std::isfinite(o)) throw InvalidInput("WriteBvh: joint '" + s.name + "' has a non-finite offset");
    }
  }

  std::string out;
  out.reserve(static_cast<size_t>(256 + joints * 96 + frames * (joints * 40)));
  out += "HIERARCHY\n";
  auto clean_name = [&](int64_t j) {
    std::string n = skeleton[static_cast<size_t>(j)].name;
    for (char& c : n) {
      if (c == '\t' || c == '\n' || c == '\r' || c == '{' || c == '}' || c == '\v' || c == '\f') c = '_';
    }
    n = std::string(Trim(n));
    if (n.empty() || n == "End" || n == "MOTION") n = "joint" + std::to_string(j + 1) + n;
    return n;
  };
  // Depth-first, iteratively: (joint, next child index).
  std::vector<std::pair<int, size_t>> stack;
  for (int64_t r = 0; r < joints; ++r) {
    if (skeleton[static_cast<size_t>(r)].parent != -1) continue;
    stack.push_back({static_cast<int>(r), 0});
    bool opening = true;
    while (!stack.empty()) {
      auto& [j, next] = stack.back();
      const SkeletonJoint& s = skeleton[static_cast<size_t>(j)];
      const std::string indent(stack.size() - 1, '\t');
      if (opening) {
        if (s.end_site) {
          out += indent + "End Site\n";
        } else {
          out += indent + (s.parent < 0 ? "ROOT " : "JOINT ") + clean_name(j) + "\n";
        }
        out += indent + "{\n";
        out += indent + "\tOFFSET";
        for (double o : s.offset_mm) out += " " + formats_internal::FormatDouble(o * unit_per_mm);
        out += "\n";
        if (!s.end_site) {
          out += indent + "\tCHANNELS " + std::to_string(s.channels.size());
          for (int code : codes[static_cast<size_t>(j)]) out += std::string(" ") + kChannelNames[code];
          out += "\n";
        }
        opening = false;
      }
      const std::vector<int>& ch = children[static_cast<size_t>(j)];
      if (next < ch.size()) {
        const int c = ch[next++];
        stack.push_back({c, 0});
        opening = true;
        continue;
      }
      out += indent + "}\n";
      stack.pop_back();
    }
  }
  out += "MOTION\n";
  out += "Frames: " + std::to_string(frames) + "\n";
  out += "Frame Time: " + formats_internal::FormatDouble(1.0 / take.rate_hz) + "\n";

  char buf[64];
  auto append_float = [&](float v) {
    if (v == 0.0f) v = 0.0f;  // no "-0"
    auto [p, ec] = std::to_chars(buf, buf + sizeof(buf), v);
    (void)ec;
    out.append(buf, p);
  };
  auto append_angle = [&](double deg) {
    auto [p, ec] = std::to_chars(buf, buf + sizeof(buf), deg, std::chars_format::fixed, 6);
    (void)ec;
    const char* begin = buf;
    if (p - buf == 9 && std::string_view(buf, 9) == "-0.000000") ++begin;  // no negative zero
    out.append(begin, static_cast<size_t>(p - begin));
  };
  auto quaternion = [&](int64_t f, int64_t j) -> Eigen::Quaterniond {
    const float* q = take.orientations.at(f, j);
    if (IsMissing(q[0]) || IsMissing(q[1]) || IsMissing(q[2]) || IsMissing(q[3]) ||
        !(std::abs(q[0]) + std::abs(q[1]) + std::abs(q[2]) + std::abs(q[3]) > 0.5f) ||
        !std::isfinite(q[0] + q[1] + q[2] + q[3])) {
      throw InvalidInput("WriteBvh: take '" + take.name + "' frame " + std::to_string(f) + ": joint '" +
                         skeleton[static_cast<size_t>(j)].name + "' has no orientation");
    }
    return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
  };
  auto position = [&](int64_t f, int64_t j) -> Eigen::Vector3d {
    const float* p = take.markers.at(f, j);
    if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2])) {
      throw InvalidInput("WriteBvh: take '" + take.name + "' frame " + std::to_string(f) + ": joint '" +
                         skeleton[static_cast<size_t>(j)].name + "' has no position");
    }
    return Eigen::Vector3d(p[0], p[1], p[2]);
  };
  for (int64_t f = 0; f < frames; ++f) {
    bool first = true;
    for (int64_t j = 0; j < joints; ++j) {
      const std::vector<int>& jc = codes[static_cast<size_t>(j)];
      if (jc.empty()) continue;
      const int parent = skeleton[static_cast<size_t>(j)].parent;
      bool has_rotation = false, has_position = false;
      for (int c : jc) (c < 3 ? has_position : has_rotation) = true;
      Eigen::Vector3d translation = Eigen::Vector3d::Zero();
      if (has_position) {
        if (parent < 0) {
          translation = position(f, j) * unit_per_mm;
        } else {
          translation = quaternion(f, parent).conjugate() * (position(f, j) - position(f, parent)) * unit_per_mm;
        }
      }
      double angles[3] = {0, 0, 0};
      int axes[3] = {0, 0, 0};
      if (has_rotation) {
        int n = 0;
        bool used[3] = {false, false, false};
        for (int c : jc) {
          if (c >= 3) {
            axes[n++] = c - 3;
            used[c - 3] = true;
          }
        }
        for (int a = 0; a < 3; ++a) {
          if (!used[a]) axes[n++] = a;
        }
        Eigen::Quaterniond local = quaternion(f, j);
        if (parent >= 0) local = quaternion(f, parent).conjugate() * local;
        const double q[4] = {local.w(), local.x(), local.y(), local.z()};
        QuaternionToEuler(q, axes, angles);
      }
      int rotation_index = 0;
      for (int c : jc) {
        if (!first) out += ' ';
        first = false;
        if (c < 3) {
          append_float(static_cast<float>(translation[c]));
        } else {
          append_angle(angles[rotation_index++] / kDegToRad);
        }
      }
    }
    out += '\n';
  }
  return out;
}

double SkeletonPositionMismatchMm(const Take& take) {
  const int64_t joints = static_cast<int64_t>(take.skeleton.size());
  if (take.markers.markers() != joints || take.orientations.joints() != joints ||
      take.orientations.frames() != take.markers.frames()) {
    throw InvalidInput("SkeletonPositionMismatchMm: take '" + take.name +
                       "' has markers, orientations and skeleton of different sizes");
  }
  double worst = 0.0;
  for (int64_t f = 0; f < take.markers.frames(); ++f) {
    for (int64_t j = 0; j < joints; ++j) {
      const SkeletonJoint& s = take.skeleton[static_cast<size_t>(j)];
      if (s.parent < 0 || s.parent >= j) continue;
      bool has_position = false;
      for (const std::string& c : s.channels) has_position = has_position || ChannelCode(c) < 3;
      if (has_position) continue;
      const float* p = take.markers.at(f, j);
      const float* pp = take.markers.at(f, s.parent);
      const float* q = take.orientations.at(f, s.parent);
      if (IsMissing(p[0]) || IsMissing(pp[0]) || IsMissing(q[0])) continue;
      const Eigen::Quaterniond qp = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized();
      const Eigen::Vector3d expected =
          Eigen::Vector3d(pp[0], pp[1], pp[2]) + qp * Eigen::Vector3d(s.offset_mm[0], s.offset_mm[1], s.offset_mm[2]);
      worst = std::max(worst, (expected - Eigen::Vector3d(p[0], p[1], p[2])).norm());
    }
  }
  return worst;
}

void WriteBvh(const std::string& path, const Take& take, const BvhWriteOptions& options) {
  const std::string out = FormatBvh(take, options);
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw IoError(path, "cannot open for writing");
  file.write(out.data(), static_cast<std::streamsize>(out.size()));
  file.close();
  if (!file) throw IoError(path, "write failed");
}

}  // namespace csw
