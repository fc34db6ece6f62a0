#include "text.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <system_error>

namespace rgbl::detail {

bool parse_double(std::string_view token, double& out) {
  if (token.empty()) return false;
  const char* end = token.data() + token.size();
  const auto result = std::from_chars(token.data(), end, out);
  return result.ec == std::errc() && result.ptr == end;
}

std::vector<std::string_view> split(std::string_view line) {
  if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
  std::vector<std::string_view> tokens;
  std::size_t pos = 0;
  while (pos < line.size()) {
    const auto start = line.find_first_not_of(" \t,", pos);
    if (start == std::string_view::npos) break;
    const auto stop = std::min(line.find_first_of(" \t,", start), line.size());
    tokens.push_back(line.substr(start, stop - start));
    pos = stop;
  }
  return tokens;
}

bool is_comment_or_blank(std::string_view line) {
  const auto start = line.find_first_not_of(" \t\r");
  return start == std::string_view::npos || line[start] == '#';
}

std::ifstream open_for_reading(const std::filesystem::path& file, std::string_view what) {
  return open_input_file(file, what);
}

bool read_line(std::istream& in, std::string& line, std::size_t& line_no) {
  if (!std::getline(in, line)) return false;
  if (++line_no == 1 && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);
  return true;
}

void for_each_record(const std::filesystem::path& file, std::string_view what, std::size_t count,
                     std::string_view record,
                     const std::function<void(std::size_t line_no, std::span<const double> numbers)>& on_record) {
  std::error_code ec;
  if (std::filesystem::is_directory(file, ec)) {
    throw ParseError(file, 0, fmt::format("is a directory (expected {})", what));
  }
  std::ifstream in(file);
  if (!in) throw ParseError(file, 0, fmt::format("cannot open the file (expected {})", what));
  for_each_record(in, file, count, record, on_record);
}

void for_each_record(std::istream& in, const std::filesystem::path& file, std::size_t count, std::string_view record,
                     const std::function<void(std::size_t line_no, std::span<const double> numbers)>& on_record) {
  std::vector<double> numbers(count);
  std::string line;
  std::size_t line_no = 0;
  while (read_line(in, line, line_no)) {
    if (is_comment_or_blank(line)) continue;
    const auto tokens = split(line);
    if (tokens.size() != count) {
      throw ParseError(file, line_no, fmt::format("expected {}, found {} fields", record, tokens.size()));
    }
    for (std::size_t k = 0; k < count; ++k) {
      if (!parse_double(tokens[k], numbers[k]) || !std::isfinite(numbers[k])) {
        throw ParseError(file, line_no, fmt::format("field {} '{}' is not a finite number", k + 1, tokens[k]));
      }
    }
    on_record(line_no, numbers);
  }
}

std::vector<std::size_t> numbered_files(const std::filesystem::path& dir, std::string_view extension) {
  std::vector<std::size_t> indices;
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(dir, ec)) {
    const auto name = entry.path().filename().string();
    if (name.size() <= extension.size() || !name.ends_with(extension)) continue;
    const std::string_view stem(name.data(), name.size() - extension.size());
    if (!std::all_of(stem.begin(), stem.end(), [](char c) { return std::isdigit(static_cast<unsigned char>(c)); })) {
      continue;
    }
    std::size_t index = 0;
    const auto result = std::from_chars(stem.data(), stem.data() + stem.size(), index);
    if (result.ec == std::errc()) indices.push_back(index);
  }
  if (ec) throw ParseError(dir, 0, fmt::format("cannot list the folder: {}", ec.message()));
  std::sort(indices.begin(), indices.end());
  return indices;
}

}  // namespace rgbl::detail
