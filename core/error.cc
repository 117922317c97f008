#include "core/error.h"

namespace csw {

std::string Location::ToString() const {
  std::string s = file.empty() ? std::string("<input>") : file;
  if (offset) s += ": offset " + std::to_string(*offset);
  if (line) s += ": line " + std::to_string(*line);
  return s;
}

ParseError::ParseError(Location where, const std::string& what)
    : Error(where.ToString() + ": " + what), where_(std::move(where)), what_(what) {}

IoError::IoError(const std::string& file, const std::string& what)
    : Error((file.empty() ? std::string("<output>") : file) + ": " + what) {}

}  // namespace csw
