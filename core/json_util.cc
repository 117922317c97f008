#include "core/json_util.h"

#include <algorithm>
#include <optional>

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
  } catch (const nlohmann::json::exception& e) {
    // E.g. out_of_range 406, "number overflow parsing '1e999'": no position, but
    // the number is quoted; its first occurrence gives the line.
    std::string msg = e.what();
    if (const size_t b = msg.find("] "); b != std::string::npos) msg = msg.substr(b + 2);
    std::optional<int64_t> line;
    const size_t q = msg.find('\'');
    const size_t r = msg.rfind('\'');
    if (q != std::string::npos && r > q + 1) {
      if (const size_t at = text.find(msg.substr(q + 1, r - q - 1)); at != std::string::npos)
        line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n');
    }
    throw ParseError({file, std::nullopt, line}, "invalid JSON: " + msg);
  }
}

}  // namespace csw
