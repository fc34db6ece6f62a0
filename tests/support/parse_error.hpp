#pragma once

#include "rgbl/core/error.hpp"

#include <catch2/catch.hpp>

#include <filesystem>
#include <string>

namespace rgbl::test {

// Runs f, which must throw a ParseError naming `file`; returns its message (fails the test otherwise).
template <typename F>
std::string parse_error_message(F&& f, const std::filesystem::path& file) {
  try {
    f();
  } catch (const rgbl::ParseError& e) {
    CHECK(e.file() == file);
    return e.what();
  }
  FAIL("no ParseError for " << file.string());
  return {};
}

}  // namespace rgbl::test
