#pragma once
// The `rgbl` command's subcommands. Each one lives in its own <name>_command.cpp: it declares its
// options on the parent app and returns the function main() calls when that subcommand was chosen.
// Adding a subcommand (run, depth, demo) = one new file + one line in main.cpp.

#include <CLI/App.hpp>
#include <CLI/Validators.hpp>
#include <fmt/format.h>

#include <charconv>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <system_error>

namespace rgbl::cli {

struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;  // returns the exit code; throws on failure (main prints "error: ...")
};

// Check of a count or index option: a whole number in [min, max]. CLI11 alone reads "-1" and 2^64
// into an unsigned option as its largest value, and PositiveNumber's message prints a 309-digit range.
inline CLI::Validator whole_number(std::uint64_t min, std::uint64_t max = 1'000'000'000) {
  return {[min, max](std::string& text) -> std::string {
            std::uint64_t value = 0;
            const char* end = text.data() + text.size();
            const auto [stop, error] = std::from_chars(text.data(), end, value);
            if (error != std::errc() || stop != end || value < min || value > max) {
              return fmt::format("expected a whole number from {} to {}, found '{}'", min, max, text);
            }
            return {};
          },
          fmt::format("INT in {}..{}", min, max)};
}

// Check of a real-valued option: a finite number above `min`, or from `min` on when inclusive.
// (CLI11's PositiveNumber prints a 309-digit range for 0.)
inline CLI::Validator finite_number(double min, bool inclusive) {
  return {[min, inclusive](std::string& text) -> std::string {
            double value = 0.0;
            const char* end = text.data() + text.size();
            const auto [stop, error] = std::from_chars(text.data(), end, value);
            const bool in_range = inclusive ? value >= min : value > min;
            if (error != std::errc() || stop != end || !std::isfinite(value) || !in_range) {
              return fmt::format("expected a finite number {} {}, found '{}'", inclusive ? "from" : "above", min, text);
            }
            return {};
          },
          fmt::format("NUMBER {} {}", inclusive ? ">=" : ">", min)};
}

Command add_eval_command(CLI::App& parent);
Command add_info_command(CLI::App& parent);
Command add_run_command(CLI::App& parent);
Command add_depth_command(CLI::App& parent);
Command add_demo_command(CLI::App& parent);
Command add_vocab_command(CLI::App& parent);

}  // namespace rgbl::cli
