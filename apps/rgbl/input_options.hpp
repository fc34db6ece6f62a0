#pragma once
// What `rgbl run`, `rgbl depth` and `rgbl demo` share: the input options on the command line, as a
// PipelineOptions, and tracking with progress and a one-screen summary.

#include "interrupt.hpp"

#include "rgbl/core/file.hpp"
#include "rgbl/pipeline/pipeline.hpp"

#include <CLI/App.hpp>

#include <filesystem>

namespace rgbl::cli {

// Declares dir, --format, --camera, --depth, --config, --frames, --first and --step on `app`.
void add_input_options(CLI::App& app, PipelineOptions& options);

// Prints the pipeline's notes, runs it (progress on stderr unless quiet), writes every output into
// out_dir and prints the summary to stdout. A signal seen by `interrupt` stops the run before its
// next frame; what was tracked is written as partial outputs (summary.json: "partial": true).
RunResult run_and_report(const Pipeline& pipeline, const OutputFolder& out_dir, bool quiet,
                         const InterruptScope& interrupt);

}  // namespace rgbl::cli
