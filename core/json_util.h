#pragma once
// JSON parsing with errors that name the file and the line (nlohmann-json).
#include <nlohmann/json.hpp>
#include <string>

namespace csw {

// Parses text; a syntax error throws ParseError("file: line N: invalid JSON: ...").
nlohmann::json ParseJsonText(const std::string& text, const std::string& file);

}  // namespace csw
