#pragma once
// One exception family for bad input (architecture.md: "Errors").
// Messages name the file and where: "take03.c3d: offset 1536: parameter block 3
// overruns the file". Programmer errors use assert, not these.
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>

namespace csw {

// Base of every error caused by data or by the user's request.
class Error : public std::runtime_error {
 public:
  explicit Error(const std::string& message) : std::runtime_error(message) {}
};

// Where in a file something went wrong.
struct Location {
  std::string file;
  std::optional<int64_t> offset;  // byte offset
  std::optional<int64_t> line;    // 1-based line number
  std::string ToString() const;   // "file: offset N" / "file: line N" / "file"
};

// A file that cannot be read as what it claims to be (truncated, damaged, hostile).
class ParseError : public Error {
 public:
  ParseError(Location where, const std::string& what);
  const Location& where() const { return where_; }
  const std::string& what_only() const { return what_; }

 private:
  Location where_;
  std::string what_;
};

// A file that cannot be opened, read, written or renamed.
class IoError : public Error {
 public:
  IoError(const std::string& file, const std::string& what);
};

// Semantically invalid input: a marker set that does not match, a bad option.
class InvalidInput : public Error {
 public:
  using Error::Error;
};

// The user asked to stop a long job.
class Cancelled : public Error {
 public:
  Cancelled() : Error("cancelled") {}
};

// Throws ParseError if cond is true.
#define CSW_PARSE_CHECK(cond, location, message)                 \
  do {                                                           \
    if (!(cond)) throw ::csw::ParseError((location), (message)); \
  } while (0)

}  // namespace csw
