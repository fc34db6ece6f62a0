// rgbl_longrun [--frames N] [--laps L] [--threads N] [--threaded] [--csv FILE]
// Tracks a long synthetic drive (laps of the simulator's loop, rendered in memory, never written to
// disk) through the same Pipeline as `rgbl run`, and reports how the per-frame time, the resident
// memory and the map's size evolve over the run. scripts/longrun.sh checks issue 17's figures on it.
#include "rgbl/core/error.hpp"
#include "rgbl/core/log.hpp"
#include "rgbl/pipeline/pipeline.hpp"
#include "rgbl/sim/sim_sequence.hpp"
#include "rgbl/sim/synthetic.hpp"

#include <CLI/CLI.hpp>
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <fstream>
#include <string>
#include <vector>

namespace {

// Resident and peak resident memory of this process, MB (Linux: /proc/self/status).
struct Memory {
  double rss_mb = 0.0, peak_mb = 0.0;
};
Memory memory() {
  Memory m;
  std::ifstream status("/proc/self/status");
  std::string key;
  double kb = 0.0;
  while (status >> key) {
    if (key == "VmRSS:" && status >> kb) m.rss_mb = kb / 1024.0;
    if (key == "VmHWM:" && status >> kb) m.peak_mb = kb / 1024.0;
  }
  return m;
}

struct Row {
  std::size_t frame;
  rgbl::TrackState state;
  double front_ms, total_ms, rss_mb;
  std::size_t keyframes, landmarks;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Track a long synthetic drive in memory; report time, memory and map size over the run"};
  int frames = 3000;
  int laps = 25;
  std::uint64_t seed = 1;
  std::string csv;
  rgbl::PipelineOptions options;
  options.threads = 0;
  app.add_option("--frames", frames, "frames to drive")->check(CLI::Range(100, 1000000))->capture_default_str();
  app.add_option("--laps", laps, "laps of the loop over those frames (the drive revisits every place)")
      ->check(CLI::Range(1, 10000))
      ->capture_default_str();
  app.add_option("--seed", seed, "seed of the scene and all noise")->capture_default_str();
  app.add_option("--threads", options.threads, "frame threads (0: the machine's)")->check(CLI::Range(0, 256));
  app.add_flag("--threaded", options.threaded, "local mapping and loop closing in threads of their own");
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "the tracker's warnings too (e.g. at the loop's corners)");
  app.add_option("--csv", csv, "write a row per frame (state, front_ms, total_ms, rss_mb, keyframes, landmarks)");
  CLI11_PARSE(app, argc, argv);
  rgbl::logger()->set_level(verbose ? spdlog::level::info : spdlog::level::err);

  try {
    rgbl::SyntheticOptions sim;
    sim.seed = seed;
    sim.frames = frames;
    sim.path.kind = rgbl::PathKind::loop;
    rgbl::fit_loop(sim, laps);
    sim.cameras = {true, false, false, false};
    sim.render_depth = false;
    sim.threads = 1;  // the renderer (one frame ahead, on the read-ahead thread) takes a core less from tracking
    const rgbl::Pipeline pipeline(rgbl::make_synthetic_sequence(sim), options);

    std::vector<Row> rows;
    rows.reserve(static_cast<std::size_t>(frames));
    const auto progress = [&](const rgbl::FrameRecord& r, std::size_t done, std::size_t total) {
      const auto& t = r.result.timing;
      rows.push_back({r.result.frame_index, r.result.state, t.front_ms, t.total_ms, memory().rss_mb,
                      r.result.map_keyframes, r.result.map_landmarks});
      if (done % 250 == 0 || done == total) {
        const Row& last = rows.back();
        std::fprintf(stderr, "frame %zu/%zu  rss %.0f MB  keyframes %zu  landmarks %zu\n", done, total, last.rss_mb,
                     last.keyframes, last.landmarks);
      }
    };
    const rgbl::RunResult run = pipeline.run(progress);
    const Memory end = memory();

    if (!csv.empty()) {
      std::ofstream out(csv);
      if (!out) throw rgbl::Error(fmt::format("{}: cannot write the per-frame table", csv));
      out << "frame,state,front_ms,total_ms,rss_mb,keyframes,landmarks\n";
      for (const Row& r : rows) {
        out << fmt::format("{},{},{:.3f},{:.3f},{:.1f},{},{}\n", r.frame, rgbl::to_string(r.state), r.front_ms,
                           r.total_ms, r.rss_mb, r.keyframes, r.landmarks);
      }
    }
    // per-frame time over the run: windows of 300 frames
    const auto window = [&](std::size_t from, std::size_t to, auto field) {
      std::vector<double> v;
      for (std::size_t i = from; i < std::min(to, rows.size()); ++i) v.push_back(field(rows[i]));
      return rgbl::stage_stats(std::move(v)).median;
    };
    const auto front = [](const Row& r) { return r.front_ms; };
    const auto total = [](const Row& r) { return r.total_ms; };
    fmt::print("frames {} (loop of {} laps, {:.0f} m), threads {}{}\n", rows.size(), laps, sim.driven_length(),
               run.threads, options.threaded ? ", threaded mapping" : "");
    fmt::print("{:>11} {:>10} {:>10} {:>8} {:>10} {:>10}\n", "frames", "front_ms", "total_ms", "rss_MB", "keyframes",
               "landmarks");
    for (std::size_t from = 0; from < rows.size(); from += 300) {
      const Row& last = rows[std::min(rows.size(), from + 300) - 1];
      fmt::print("{:>5}-{:<5} {:>10.2f} {:>10.2f} {:>8.0f} {:>10} {:>10}\n", from, std::min(rows.size(), from + 300) - 1,
                 window(from, from + 300, front), window(from, from + 300, total), last.rss_mb, last.keyframes,
                 last.landmarks);
    }
    const double early = window(100, 400, total);
    const double late = window(rows.size() - std::min<std::size_t>(300, rows.size()), rows.size(), total);
    const std::size_t lost = run.count(rgbl::TrackState::Lost) + run.count(rgbl::TrackState::NotInitialised);
    fmt::print("median total ms, last 300 frames / frames 100-400: {:.2f} / {:.2f} = {:.2f}x\n", late, early,
               early > 0.0 ? late / early : 0.0);
    fmt::print("peak resident memory: {:.1f} MB\n", end.peak_mb);
    fmt::print("frames lost or not initialised: {}; weak: {}\n", lost, run.count(rgbl::TrackState::Weak));
    fmt::print("map at the end: {} keyframes, {} landmarks; {} loop closures\n", rows.back().keyframes,
               rows.back().landmarks, run.loop_closures.size());
    if (run.metrics) {
      fmt::print("ATE {:.3f} m, drift {:.2f} %\n", run.metrics->evaluation.ate.translation.rmse,
                 run.metrics->evaluation.drift.percent);
    }
    fmt::print("wall {:.1f} s\n", run.wall_s);
    return 0;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
}
