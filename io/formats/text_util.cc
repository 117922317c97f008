#include "io/formats/text_util.h"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <system_error>

#include "core/error.h"

namespace csw::formats_internal {

namespace fs = std::filesystem;

std::string ReadFileBytes(const std::string& path, int64_t max_bytes) {
  std::error_code ec;
  fs::file_status status = fs::status(path, ec);
  if (ec || !fs::exists(status)) throw IoError(path, "no such file");
  if (!fs::is_regular_file(status)) throw IoError(path, "not a regular file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
  in.seekg(0, std::ios::end);
  const std::streamoff size = in.tellg();
  if (size < 0) throw IoError(path, "cannot determine the file size");
  if (size > max_bytes) {
    throw ParseError({path, max_bytes, std::nullopt},
                     "file is too large (" + std::to_string(size) + " bytes; limit " + std::to_string(max_bytes) + ")");
  }
  in.seekg(0, std::ios::beg);
  std::string bytes(static_cast<size_t>(size), '\0');
  if (size > 0 && !in.read(bytes.data(), size)) throw IoError(path, "read failed");
  return bytes;
}

const char* EncodingName(TextEncoding encoding) {
  switch (encoding) {
    case TextEncoding::kUtf8:
      return "UTF-8";
    case TextEncoding::kUtf8Bom:
      return "UTF-8 with BOM";
    case TextEncoding::kUtf16Le:
      return "UTF-16LE";
    case TextEncoding::kUtf16Be:
      return "UTF-16BE";
    case TextEncoding::kLatin1:
      return "Latin-1";
  }
  return "?";
}

namespace {

void AppendUtf8(uint32_t cp, std::string* out) {
  if (cp < 0x80) {
    out->push_back(static_cast<char>(cp));
  } else if (cp < 0x800) {
    out->push_back(static_cast<char>(0xC0 | (cp >> 6)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else if (cp < 0x10000) {
    out->push_back(static_cast<char>(0xE0 | (cp >> 12)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  } else {
    out->push_back(static_cast<char>(0xF0 | (cp >> 18)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 12) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | ((cp >> 6) & 0x3F)));
    out->push_back(static_cast<char>(0x80 | (cp & 0x3F)));
  }
}

}  // namespace

std::string Utf16ToUtf8(std::string_view bytes, bool big_endian, const std::string& path, int64_t base_offset) {
  if (bytes.size() % 2 != 0) {
    throw ParseError({path, base_offset + static_cast<int64_t>(bytes.size()) - 1, std::nullopt},
                     "UTF-16 text has an odd number of bytes (truncated?)");
  }
  auto unit = [&](size_t i) -> uint32_t {
    const auto b0 = static_cast<unsigned char>(bytes[i]);
    const auto b1 = static_cast<unsigned char>(bytes[i + 1]);
    return big_endian ? (uint32_t{b0} << 8 | b1) : (uint32_t{b1} << 8 | b0);
  };
  std::string out;
  out.reserve(bytes.size() / 2 + bytes.size() / 8);
  for (size_t i = 0; i < bytes.size(); i += 2) {
    uint32_t u = unit(i);
    if (u >= 0xD800 && u <= 0xDBFF) {
      if (i + 2 >= bytes.size()) {
        throw ParseError({path, base_offset + static_cast<int64_t>(i), std::nullopt},
                         "UTF-16 high surrogate at the end of the text");
      }
      uint32_t low = unit(i + 2);
      if (low < 0xDC00 || low > 0xDFFF) {
        throw ParseError({path, base_offset + static_cast<int64_t>(i), std::nullopt},
                         "UTF-16 high surrogate not followed by a low surrogate");
      }
      AppendUtf8(0x10000 + ((u - 0xD800) << 10) + (low - 0xDC00), &out);
      i += 2;
    } else if (u >= 0xDC00 && u <= 0xDFFF) {
      throw ParseError({path, base_offset + static_cast<int64_t>(i), std::nullopt}, "unpaired UTF-16 low surrogate");
    } else {
      AppendUtf8(u, &out);
    }
  }
  return out;
}

bool IsValidUtf8(std::string_view s) {
  size_t i = 0;
  const size_t n = s.size();
  while (i < n) {
    const auto c = static_cast<unsigned char>(s[i]);
    if (c < 0x80) {
      ++i;
      continue;
    }
    int len;
    uint32_t cp;
    if (c >= 0xC2 && c <= 0xDF) {
      len = 2;
      cp = c & 0x1F;
    } else if (c >= 0xE0 && c <= 0xEF) {
      len = 3;
      cp = c & 0x0F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      len = 4;
      cp = c & 0x07;
    } else {
      return false;
    }
    if (n - i < static_cast<size_t>(len)) return false;
    for (int k = 1; k < len; ++k) {
      const auto cc = static_cast<unsigned char>(s[i + k]);
      if ((cc & 0xC0) != 0x80) return false;
      cp = (cp << 6) | (cc & 0x3F);
    }
    if ((len == 3 && cp < 0x800) || (len == 4 && cp < 0x10000) || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) {
      return false;
    }
    i += static_cast<size_t>(len);
  }
  return true;
}

std::string Latin1ToUtf8(std::string_view bytes) {
  std::string out;
  out.reserve(bytes.size() + bytes.size() / 4);
  for (char ch : bytes) AppendUtf8(static_cast<unsigned char>(ch), &out);
  return out;
}

std::string DecodeText(std::string_view bytes, const std::string& path, TextEncoding* encoding) {
  auto set = [&](TextEncoding e) {
    if (encoding) *encoding = e;
  };
  auto b = [&](size_t i) { return static_cast<unsigned char>(bytes[i]); };
  if (bytes.size() >= 3 && b(0) == 0xEF && b(1) == 0xBB && b(2) == 0xBF) {
    std::string_view rest = bytes.substr(3);
    if (IsValidUtf8(rest)) {
      set(TextEncoding::kUtf8Bom);
      return std::string(rest);
    }
    set(TextEncoding::kLatin1);
    return Latin1ToUtf8(rest);
  }
  if (bytes.size() >= 2 && b(0) == 0xFF && b(1) == 0xFE) {
    set(TextEncoding::kUtf16Le);
    return Utf16ToUtf8(bytes.substr(2), false, path, 2);
  }
  if (bytes.size() >= 2 && b(0) == 0xFE && b(1) == 0xFF) {
    set(TextEncoding::kUtf16Be);
    return Utf16ToUtf8(bytes.substr(2), true, path, 2);
  }
  if (bytes.size() >= 2 && b(0) == 0 && b(1) != 0) {
    set(TextEncoding::kUtf16Be);
    return Utf16ToUtf8(bytes, true, path, 0);
  }
  if (bytes.size() >= 2 && b(0) != 0 && b(1) == 0) {
    set(TextEncoding::kUtf16Le);
    return Utf16ToUtf8(bytes, false, path, 0);
  }
  if (IsValidUtf8(bytes)) {
    set(TextEncoding::kUtf8);
    return std::string(bytes);
  }
  set(TextEncoding::kLatin1);
  return Latin1ToUtf8(bytes);
}

std::optional<double> ParseFiniteDouble(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return std::nullopt;
  // from_chars would accept "inf"/"nan"; only digits, '.', '-' may start a number here.
  const char c0 = token.front();
  if (!(std::isdigit(static_cast<unsigned char>(c0)) || c0 == '.' || c0 == '-')) return std::nullopt;
  double value = 0.0;
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value, std::chars_format::general);
  if (ec != std::errc() || ptr != end || !std::isfinite(value)) return std::nullopt;
  return value;
}

std::optional<int64_t> ParseInt(std::string_view token) {
  if (!token.empty() && token.front() == '+') token.remove_prefix(1);
  if (token.empty()) return std::nullopt;
  int64_t value = 0;
  const char* end = token.data() + token.size();
  auto [ptr, ec] = std::from_chars(token.data(), end, value, 10);
  if (ec != std::errc() || ptr != end) return std::nullopt;
  return value;
}

std::string FormatDouble(double value) {
  if (value == 0.0) return "0";
  char buf[64];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  return ec == std::errc() ? std::string(buf, ptr) : std::string("0");
}

std::string FormatFloat(float value) {
  if (value == 0.0f) return "0";
  char buf[64];
  auto [ptr, ec] = std::to_chars(buf, buf + sizeof(buf), value);
  return ec == std::errc() ? std::string(buf, ptr) : std::string("0");
}

std::string_view Trim(std::string_view s) {
  auto is_space = [](char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; };
  while (!s.empty() && is_space(s.front())) s.remove_prefix(1);
  while (!s.empty() && is_space(s.back())) s.remove_suffix(1);
  return s;
}

int64_t LineOfOffset(std::string_view text, int64_t offset) {
  offset = std::clamp<int64_t>(offset, 0, static_cast<int64_t>(text.size()));
  return 1 + std::count(text.begin(), text.begin() + offset, '\n');
}

}  // namespace csw::formats_internal
