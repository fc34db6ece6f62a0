#pragma once
// Helpers shared by io's text parsers and writers (internal).

#include <filesystem>
#include <fstream>
#include <functional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace rgbl::detail {

// Whole-token double; accepts what std::from_chars accepts (no leading '+', no "inf"/"nan" check).
bool parse_double(std::string_view token, double& out);
// Whitespace-separated tokens of a line (a trailing '\r' is dropped).
std::vector<std::string_view> split(std::string_view line);
// True for blank lines and '#' comments.
bool is_comment_or_blank(std::string_view line);

// Opens a dataset's text file for reading or throws ParseError(file, 0, "... (expected <what>)"): it
// must be a regular file (rgbl::require_input_file), never a FIFO that could block forever.
std::ifstream open_for_reading(const std::filesystem::path& file, std::string_view what);

// std::getline that also counts lines and drops a UTF-8 byte order mark at the start of line 1.
bool read_line(std::istream& in, std::string& line, std::size_t& line_no);

// Reads a file of numeric records (any readable file, pipes too: `rgbl eval <(...)`), one per line (blank lines and '#' comments skipped): calls
// on_record(line_no, numbers) with exactly `count` finite numbers, or throws ParseError(file, line,
// "expected <record>, found N fields") / ("field K '...' is not a finite number"). `what` describes
// the file for open_for_reading.
void for_each_record(const std::filesystem::path& file, std::string_view what, std::size_t count,
                     std::string_view record,
                     const std::function<void(std::size_t line_no, std::span<const double> numbers)>& on_record);

// The same on a stream already open; `file` names it in errors.
void for_each_record(std::istream& in, const std::filesystem::path& file, std::size_t count, std::string_view record,
                     const std::function<void(std::size_t line_no, std::span<const double> numbers)>& on_record);

// Sorted indices of files named <digits><extension> in `dir`, keyed by their number.
std::vector<std::size_t> numbered_files(const std::filesystem::path& dir, std::string_view extension);

}  // namespace rgbl::detail
