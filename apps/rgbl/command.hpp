#pragma once
// The `rgbl` command's subcommands. Each one lives in its own <name>_command.cpp: it declares its
// options on the parent app and returns the function main() calls when that subcommand was chosen.
// Adding a subcommand (run, depth, demo) = one new file + one line in main.cpp.

#include <CLI/App.hpp>

#include <functional>

namespace rgbl::cli {

struct Command {
  CLI::App* app = nullptr;
  std::function<int()> run;  // returns the exit code; throws on failure (main prints "error: ...")
};

Command add_eval_command(CLI::App& parent);
Command add_info_command(CLI::App& parent);
Command add_run_command(CLI::App& parent);
Command add_depth_command(CLI::App& parent);
Command add_demo_command(CLI::App& parent);
Command add_vocab_command(CLI::App& parent);

}  // namespace rgbl::cli
