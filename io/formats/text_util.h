#pragma once
// Helpers shared by the text-format readers of io/formats (TRC, TextGrid, EAF):
// bounded file reading, encoding detection (UTF-8 / UTF-16 LE/BE with or without
// BOM, Latin-1 fallback), locale-independent number parsing and shortest
// round-trip number formatting. Internal to csw_io_formats; not a public API.
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

namespace csw::formats_internal {

// Largest file the text readers accept (bytes). Larger files are rejected with a
// ParseError instead of being loaded whole.
inline constexpr int64_t kMaxTextFileBytes = int64_t{1} << 30;

// Reads a whole file. Throws IoError when it cannot be opened or read, and
// ParseError when it is larger than max_bytes.
std::string ReadFileBytes(const std::string& path, int64_t max_bytes = kMaxTextFileBytes);

enum class TextEncoding { kUtf8, kUtf8Bom, kUtf16Le, kUtf16Be, kLatin1 };
const char* EncodingName(TextEncoding encoding);

// Decodes text to UTF-8. A BOM selects UTF-8/UTF-16LE/UTF-16BE; without a BOM,
// a zero byte in the first code unit selects UTF-16 of the matching endianness;
// otherwise the bytes must be UTF-8, and bytes that are not valid UTF-8 are read
// as Latin-1 (old Praat and Windows tools wrote such files). The BOM is dropped.
// Throws ParseError (file, byte offset) for an odd-length UTF-16 text or an
// unpaired surrogate.
std::string DecodeText(std::string_view bytes, const std::string& path, TextEncoding* encoding = nullptr);

// UTF-16 code units (raw bytes, no BOM) to UTF-8. base_offset is added to the
// byte offsets reported in errors.
std::string Utf16ToUtf8(std::string_view bytes, bool big_endian, const std::string& path, int64_t base_offset = 0);

// True when bytes are well-formed UTF-8 (no overlongs, no surrogates, <= U+10FFFF).
bool IsValidUtf8(std::string_view bytes);
std::string Latin1ToUtf8(std::string_view bytes);

// Parses a whole token as a finite double (accepts a leading '+', decimal or
// exponent notation, never hex, "inf" or "nan"; independent of the C locale).
std::optional<double> ParseFiniteDouble(std::string_view token);
// Parses a whole token as a base-10 integer (leading '+' accepted).
std::optional<int64_t> ParseInt(std::string_view token);

// Shortest text that reads back to exactly the same double / float
// (std::to_chars); -0 is written as "0".
std::string FormatDouble(double value);
std::string FormatFloat(float value);

// Leading and trailing spaces, tabs, CR and LF removed.
std::string_view Trim(std::string_view s);

// 1-based line number of a byte offset in text (counts '\n').
int64_t LineOfOffset(std::string_view text, int64_t offset);

}  // namespace csw::formats_internal
