#include "workbench/jobs/take_selection.h"

#include <algorithm>
#include <tuple>

#include "core/error.h"

namespace csw::jobs {

namespace {

InvalidInput ItemError(const std::string& item, const std::string& what) {
  return InvalidInput("take '" + item + "': " + what);
}

// Position of the last '@' not preceded by an escaping backslash, or npos.
size_t LastUnescapedAt(const std::string& s) {
  size_t found = std::string::npos;
  for (size_t i = 0; i < s.size(); ++i) {
    if (s[i] == '\\') {
      ++i;
      continue;
    }
    if (s[i] == '@') found = i;
  }
  return found;
}

int64_t ParseBound(const std::string& text, const std::string& item, bool* percent) {
  *percent = false;
  std::string t = text;
  if (!t.empty() && t.back() == '%') {
    *percent = true;
    t.pop_back();
  }
  if (t.empty() || t.find_first_not_of("0123456789") != std::string::npos || t.size() > 12) {
    throw ItemError(item, "'" + text + "' is not a frame number or a percentage (expected name@first:end)");
  }
  const int64_t v = std::stoll(t);
  if (*percent && v > 100) throw ItemError(item, "percentage above 100");
  return v;
}

// Compiles the name part of an item (escapes resolved) into tokens.
void Compile(const std::string& raw, const std::string& item, TakeItem* out) {
  for (size_t i = 0; i < raw.size(); ++i) {
    const char ch = raw[i];
    TakeItem::Token t;
    if (ch == '\\') {
      if (i + 1 == raw.size()) throw ItemError(item, "ends with a lone backslash (write \\\\ for a backslash)");
      t.c = raw[++i];
    } else if (ch == '*') {
      t.kind = TakeItem::Token::kAnyRun;
      out->pattern = true;
    } else if (ch == '?') {
      t.kind = TakeItem::Token::kAnyOne;
      out->pattern = true;
    } else if (ch == '[') {
      t.kind = TakeItem::Token::kSet;
      out->pattern = true;
      size_t j = i + 1;
      if (j < raw.size() && (raw[j] == '!' || raw[j] == '^')) {
        t.negate = true;
        ++j;
      }
      bool closed = false;
      bool first = true;
      while (j < raw.size()) {
        char lo = raw[j];
        if (lo == ']' && !first) {
          closed = true;
          break;
        }
        first = false;
        if (lo == '\\') {
          if (j + 1 == raw.size()) break;
          lo = raw[++j];
        }
        char hi = lo;
        if (j + 2 < raw.size() && raw[j + 1] == '-' && raw[j + 2] != ']') {
          j += 2;
          hi = raw[j];
          if (hi == '\\') {
            if (j + 1 == raw.size()) break;
            hi = raw[++j];
          }
          if (hi < lo) throw ItemError(item, std::string("pattern range '") + lo + "-" + hi + "' is reversed");
        }
        t.ranges.emplace_back(lo, hi);
        ++j;
      }
      if (!closed) throw ItemError(item, "pattern has '[' without a closing ']' (write \\[ for a literal '[')");
      i = j;
    } else {
      t.c = ch;
    }
    if (t.kind == TakeItem::Token::kLiteral) out->name += t.c;
    out->tokens.push_back(std::move(t));
  }
}

bool TokenMatches(const TakeItem::Token& t, char c) {
  switch (t.kind) {
    case TakeItem::Token::kLiteral:
      return t.c == c;
    case TakeItem::Token::kAnyOne:
      return true;
    case TakeItem::Token::kSet: {
      bool in = false;
      for (const auto& [lo, hi] : t.ranges) in = in || (c >= lo && c <= hi);
      return in != t.negate;
    }
    case TakeItem::Token::kAnyRun:
      return true;
  }
  return false;
}

// Glob match of the whole string (iterative, with backtracking to the last '*').
bool GlobMatch(const std::vector<TakeItem::Token>& p, const std::string& s) {
  size_t pi = 0, si = 0, star = std::string::npos, star_s = 0;
  while (si < s.size()) {
    if (pi < p.size() && p[pi].kind == TakeItem::Token::kAnyRun) {
      star = pi++;
      star_s = si;
    } else if (pi < p.size() && TokenMatches(p[pi], s[si])) {
      ++pi;
      ++si;
    } else if (star != std::string::npos) {
      pi = star + 1;
      si = ++star_s;
    } else {
      return false;
    }
  }
  while (pi < p.size() && p[pi].kind == TakeItem::Token::kAnyRun) ++pi;
  return pi == p.size();
}

bool IsPositiveInteger(const std::string& s) {
  return !s.empty() && s[0] != '0' && s.find_first_not_of("0123456789") == std::string::npos && s.size() < 10;
}

}  // namespace

std::vector<std::string> SplitTakeList(const std::vector<std::string>& arguments) {
  std::vector<std::string> items;
  for (const std::string& a : arguments) {
    if (a.empty()) continue;
    std::string cur;
    for (size_t i = 0; i < a.size(); ++i) {
      if (a[i] == '\\' && i + 1 < a.size()) {
        cur += a[i];
        cur += a[++i];
      } else if (a[i] == ',') {
        items.push_back(cur);
        cur.clear();
      } else {
        cur += a[i];
      }
    }
    items.push_back(cur);
  }
  return items;
}

std::string EscapeTakeName(const std::string& name) {
  std::string out;
  for (char c : name) {
    if (std::string("\\*?[]@,").find(c) != std::string::npos) out += '\\';
    out += c;
  }
  return out;
}

TakeItem ParseTakeItem(const std::string& item) {
  TakeItem r;
  r.text = item;
  if (item.empty()) throw InvalidInput("take selection: empty item (two commas in a row, or a comma at an end?)");
  const size_t at = LastUnescapedAt(item);
  const std::string raw_name = item.substr(0, at);
  if (raw_name.empty()) throw ItemError(item, "no take name before '@'");
  Compile(raw_name, item, &r);
  if (at == std::string::npos) return r;
  r.has_range = true;
  r.range = item.substr(at + 1);
  const auto colon = r.range.find(':');
  if (colon == std::string::npos) {
    throw ItemError(item, "expected name@first:end after '@' (frames or percentages; write \\@ for a literal '@')");
  }
  const std::string a = r.range.substr(0, colon), b = r.range.substr(colon + 1);
  if (!a.empty()) r.first_value = ParseBound(a, item, &r.first_percent);
  if (!b.empty()) r.end_value = ParseBound(b, item, &r.end_percent);
  if (!b.empty() && !r.first_percent && !r.end_percent && r.end_value <= r.first_value) {
    throw ItemError(item, "end is not after first");
  }
  return r;
}

bool TakeItem::Matches(const std::string& take_name) const {
  return pattern ? GlobMatch(tokens, take_name) : take_name == name;
}

void TakeItem::Resolve(int64_t frames, int64_t* first, int64_t* count) const {
  auto value = [&](int64_t v, bool percent) { return percent ? v * frames / 100 : v; };
  const int64_t f = value(first_value, first_percent);
  const int64_t e = end_value < 0 ? frames : value(end_value, end_percent);
  if (f < 0 || e > frames || e <= f) {
    throw ItemError(text, "frames [" + std::to_string(f) + ", " + std::to_string(e) + ") are not inside the take's " +
                              std::to_string(frames) + " frames");
  }
  *first = f;
  *count = e - f;
}

bool IsGeneratedFillVersion(const std::string& name, const std::set<std::string>& names) {
  const std::string tag = ".filled";
  for (size_t pos = name.find(tag); pos != std::string::npos; pos = name.find(tag, pos + 1)) {
    if (pos == 0) continue;
    const std::string rest = name.substr(pos + tag.size());
    const bool generated = rest.empty() || (rest[0] == '-' && IsPositiveInteger(rest.substr(1)) && rest != "-1");
    if (generated && names.count(name.substr(0, pos))) return true;
  }
  return false;
}

std::string FilledTakeName(const std::set<std::string>& existing, const std::string& take) {
  std::string name = take + ".filled";
  for (int k = 2; existing.count(name); ++k) name = take + ".filled-" + std::to_string(k);
  return name;
}

std::vector<TakeRange> SelectTakes(const std::vector<TakeInfo>& takes, const std::vector<std::string>& arguments,
                                   const std::string& where) {
  const std::string prefix = where.empty() ? "" : where + ": ";
  std::set<std::string> names;
  for (const TakeInfo& t : takes) names.insert(t.name);
  std::vector<TakeRange> out;
  std::set<std::tuple<std::string, int64_t, int64_t>> seen;
  auto add = [&](const TakeInfo& t, const std::string& spec, const TakeItem* item) {
    TakeRange r;
    r.spec = spec;
    r.take = t.name;
    r.first = 0;
    r.count = t.frames;
    if (item && item->has_range) {
      try {
        item->Resolve(t.frames, &r.first, &r.count);
      } catch (const InvalidInput& e) {
        throw InvalidInput(prefix + e.what());
      }
    }
    if (r.count <= 0) throw InvalidInput(prefix + "take '" + t.name + "' has no frames");
    if (seen.insert({r.take, r.first, r.count}).second) out.push_back(r);
  };

  const std::vector<std::string> items = SplitTakeList(arguments);
  if (items.empty()) {
    for (const TakeInfo& t : takes) {
      if (!IsGeneratedFillVersion(t.name, names)) add(t, EscapeTakeName(t.name), nullptr);
    }
  }
  for (const std::string& text : items) {
    // A take's exact name selects it whole, however many pattern characters it has.
    auto exact = std::find_if(takes.begin(), takes.end(), [&](const TakeInfo& t) { return t.name == text; });
    if (exact != takes.end()) {
      add(*exact, EscapeTakeName(exact->name), nullptr);
      continue;
    }
    TakeItem item;
    try {
      item = ParseTakeItem(text);
    } catch (const InvalidInput& e) {
      throw InvalidInput(prefix + e.what());
    }
    const std::string range_suffix = item.has_range ? "@" + item.range : "";
    if (!item.pattern) {
      auto it = std::find_if(takes.begin(), takes.end(), [&](const TakeInfo& t) { return t.name == item.name; });
      if (it == takes.end()) {
        throw InvalidInput(prefix + "no take named '" + item.name + "'" +
                           (item.name == text ? std::string() : " (item '" + text + "')"));
      }
      add(*it, EscapeTakeName(it->name) + range_suffix, &item);
      continue;
    }
    // A pattern that mentions "fill" ('*.filled', '*filled', 'x.fill*') is
    // after fill versions; the others skip them.
    const bool wants_fills = text.find("fill") != std::string::npos;
    size_t matched = 0, skipped = 0;
    for (const TakeInfo& t : takes) {
      if (!item.Matches(t.name)) continue;
      if (!wants_fills && IsGeneratedFillVersion(t.name, names)) {
        ++skipped;
        continue;
      }
      ++matched;
      add(t, EscapeTakeName(t.name) + range_suffix, &item);
    }
    if (matched == 0)
      throw InvalidInput(prefix + "no take matches the pattern '" + text + "'" +
                         (skipped > 0 ? " (" + std::to_string(skipped) +
                                            " generated fill version(s) do: patterns without \"fill\" skip them)"
                                      : std::string()));
  }
  if (out.empty()) throw InvalidInput(prefix + "no take to use");
  return out;
}

bool TrainingSpecOverlaps(const std::string& spec, const TakeRange& range, int64_t take_frames) {
  if (spec == range.take) return true;  // stored unescaped (before escapes existed) or a plain name
  TakeItem item;
  try {
    item = ParseTakeItem(spec);
  } catch (const InvalidInput&) {
    return false;
  }
  if (!item.Matches(range.take)) return false;
  int64_t first = 0, count = take_frames;
  if (item.has_range) {
    try {
      item.Resolve(take_frames, &first, &count);
    } catch (const InvalidInput&) {
      return false;
    }
  }
  return first < range.first + range.count && range.first < first + count;
}

}  // namespace csw::jobs
