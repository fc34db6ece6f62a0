#include "rgbl/core/error.hpp"

#include <fmt/format.h>

namespace rgbl {
namespace {

std::string parse_message(const std::filesystem::path& file, std::size_t line, const std::string& expected) {
  if (line == 0) return fmt::format("{}: {}", file.string(), expected);
  return fmt::format("{}:{}: {}", file.string(), line, expected);
}

}  // namespace

ParseError::ParseError(std::filesystem::path file, std::size_t line, const std::string& expected)
    : Error(parse_message(file, line, expected)), file_(std::move(file)), line_(line) {}

ConfigError::ConfigError(std::string key, const std::string& expected)
    : Error(fmt::format("invalid option '{}': expected {}", key, expected)), key_(std::move(key)), expected_(expected) {}

}  // namespace rgbl
