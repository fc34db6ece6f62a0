// rgbl run <dir> [input options] [--out <dir>] [--threads N] [--threaded] [--realtime | --rate R] [--no-loop-closing]
#include "command.hpp"
#include "input_options.hpp"

#include <memory>
#include <string>

namespace rgbl::cli {

Command add_run_command(CLI::App& parent) {
  auto* app = parent.add_subcommand("run", "Track a dataset and write trajectories, timings, a summary, a plot and the map");
  auto options = std::make_shared<PipelineOptions>();
  auto out_dir = std::make_shared<std::string>("rgbl_output");
  auto no_loop_closing = std::make_shared<bool>(false);
  add_input_options(*app, *options);
  app->add_option("--out", *out_dir, "Output folder")->capture_default_str();
  app->add_option("--threads", options->threads,
                  "Threads for each frame's work: with 2 or more the next frame is built while this one is tracked "
                  "(the same trajectory for every count; default 0: the machine's hardware threads)")
      ->check(whole_number(0, 256))
      ->capture_default_str();
  app->add_flag("--threaded", options->threaded,
                "Local mapping and loop closing in threads of their own (default: inline, bit-for-bit reproducible)");
  auto* realtime = app->add_flag_callback(
      "--realtime", [options] { options->playback_rate = 1.0; },
      "Feed frames at the recording's pace (frame i waits until its timestamp): what threaded mapping has in the car");
  app->add_option("--rate", options->playback_rate,
                  "Feed frames at this multiple of the recording's pace (1 = --realtime; default 0: as fast as tracked)")
      ->check(CLI::Range(0.0, 1000.0))
      ->excludes(realtime);
  app->add_flag("--no-loop-closing", *no_loop_closing,
                "Do not close loops (default: closed on every keyframe, inline, or in a thread of its own with --threaded)");
  return {app, [options, out_dir, no_loop_closing, app] {
            const InterruptScope interrupt;
            // first of all: a folder that cannot be written, or that another run writes into, is refused
            // before any work (and before this run removes anything there)
            const OutputFolder out(*out_dir);
            remove_run_outputs(out.path());  // before anything can fail: stale outputs would look like this run's
            options->loop_closing = !*no_loop_closing;
            const Pipeline pipeline(*options);
            run_and_report(pipeline, out, app->get_parent()->get_option("--quiet")->as<bool>(), interrupt);
            // outputs written, partial or not: an interrupted run still exits 128 + the signal
            return interrupt.interrupted() ? interrupt.exit_code() : 0;
          }};
}

}  // namespace rgbl::cli
