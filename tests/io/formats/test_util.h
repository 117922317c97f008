#pragma once
// Small helpers for the io/formats tests: writing fixture bytes, checking that a
// reader throws one ParseError naming the file and a place.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <string>

#include "core/error.h"

namespace csw::testing {

inline void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

inline std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

// Runs fn and checks that it throws csw::ParseError whose message names the
// file (by its file name) and, when expect_line > 0, that line; when
// expect_line == 0 it requires a line or an offset; when expect_line < 0 (audio
// decoded by libsndfile) only the file name. Returns the message.
inline std::string ExpectParseError(const std::function<void()>& fn, const std::string& path, int64_t expect_line = 0) {
  try {
    fn();
  } catch (const csw::ParseError& e) {
    const std::string msg = e.what();
    const std::string name = path.substr(path.find_last_of('/') + 1);
    EXPECT_NE(msg.find(name), std::string::npos) << msg;
    if (expect_line > 0) {
      EXPECT_EQ(e.where().line.value_or(-1), expect_line) << msg;
    } else if (expect_line == 0) {
      EXPECT_TRUE(e.where().line.has_value() || e.where().offset.has_value()) << msg;
    }
    return msg;
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected csw::ParseError, got: " << e.what();
    return "";
  }
  ADD_FAILURE() << "expected csw::ParseError, nothing thrown for " << path;
  return "";
}

}  // namespace csw::testing
