#pragma once
#include <string>

namespace csw {
// Hex SHA-256 of a file's bytes (OpenSSL EVP). Throws IoError.
std::string Sha256OfFile(const std::string& path);
}  // namespace csw
