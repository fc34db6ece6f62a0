#pragma once
// Exceptions thrown at rgbl's IO and configuration edges. Everything inside the pipeline reports
// "no result" with std::optional and tracking loss as a state, never by throwing.

#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>

namespace rgbl {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// A file that is missing, unreadable or not in the expected format. The message names the file, the
// line (when the format has lines; 0 otherwise) and what was expected.
class ParseError : public Error {
 public:
  ParseError(std::filesystem::path file, std::size_t line, const std::string& expected);

  const std::filesystem::path& file() const noexcept { return file_; }
  std::size_t line() const noexcept { return line_; }

 private:
  std::filesystem::path file_;
  std::size_t line_;
};

// An option or settings key with a value that cannot work. The message names the key and what it
// must be.
class ConfigError : public Error {
 public:
  ConfigError(std::string key, const std::string& expected);

  const std::string& key() const noexcept { return key_; }
  const std::string& expected() const noexcept { return expected_; }

 private:
  std::string key_;
  std::string expected_;
};

// Throws ConfigError(key, expected) unless condition holds: the one-liner for options' validate().
inline void require(bool condition, const char* key, const char* expected) {
  if (!condition) throw ConfigError(key, expected);
}

}  // namespace rgbl
