#pragma once
#include <cstddef>
#include <string>

namespace csw {
// Hex SHA-256 of a file's bytes (OpenSSL EVP). Throws IoError.
std::string Sha256OfFile(const std::string& path);
// Hex SHA-256 of a byte buffer.
std::string Sha256OfBytes(const void* data, size_t size);
}  // namespace csw
