#pragma once
// What `rgbl run`, `rgbl depth` and `rgbl demo` share: the input options on the command line, as a
// PipelineOptions, and tracking with progress and a one-screen summary.

#include "rgbl/pipeline/pipeline.hpp"

#include <CLI/App.hpp>

#include <filesystem>

namespace rgbl::cli {

// Declares dir, --format, --camera, --depth, --config, --frames, --first and --step on `app`.
void add_input_options(CLI::App& app, PipelineOptions& options);

// Prints the pipeline's notes, runs it (progress on stderr unless quiet), writes every output into
// out_dir and prints the summary to stdout.
RunResult run_and_report(const Pipeline& pipeline, const std::filesystem::path& out_dir, bool quiet);

}  // namespace rgbl::cli
