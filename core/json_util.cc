#include "core/json_util.h"

#include <algorithm>

#include "core/error.h"

namespace csw {

nlohmann::json ParseJsonText(const std::string& text, const std::string& file) {
  try {
    return nlohmann::json::parse(text);
  } catch (const nlohmann::json::parse_error& e) {
    // e.byte is the 1-based position of the error; report its line.
    const auto end = text.begin() + static_cast<std::ptrdiff_t>(std::min<size_t>(e.byte, text.size()));
    const int64_t line = 1 + std::count(text.begin(), end, '\n');
    const std::string msg = e.what();
    const auto p = msg.find("parse error");
    throw ParseError({file, std::nullopt, line}, "invalid JSON: " + (p == std::string::npos ? msg : msg.substr(p)));
  }
}

}  // namespace csw
