// rgbl_jump: a gap in a drive, tracked through. Frames 0..last are fed, then resume..end (the frames
// between never arrive; their time passes), three ways: without a gap, with the gap, and with the gap
// but without bridging it (MapBridgeOptions). Each run is compared with the truth (ATE over the frames
// tracked, aligned as ATE is) and the runs with the gap with the run without it (the frames after the
// gap, in the tracker's world, which all three start at the first frame): how much the gap costs,
// which a truth with its own heading error (KITTI raw's OXTS) does not blur. One line per run
// (scripts/jump-table.sh runs a table of them).
#include "rgbl/core/log.hpp"
#include "rgbl/core/task_pool.hpp"
#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/geometry/se3.hpp"
#include "rgbl/pipeline/pipeline.hpp"
#include "rgbl/tracking/system.hpp"

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <exception>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

namespace {

double degrees(const Eigen::Matrix3d& R) { return rgbl::rotation_angle(R) * 180.0 / std::numbers::pi; }

struct Run {
  std::vector<std::size_t> frames;                  // fed, in order
  std::vector<rgbl::TrackResult> results;
  std::vector<rgbl::TrajectoryPose> trajectory;     // per fed frame
  std::vector<Eigen::Isometry3d> truth;             // T_world_cam0 per fed frame
};

Run track(const rgbl::Pipeline& pipeline, std::size_t last, std::size_t resume, bool bridge,
          const std::shared_ptr<rgbl::TaskPool>& pool) {
  rgbl::SystemOptions options = pipeline.system_options();
  options.loop_closing.bridge.enabled = bridge;
  rgbl::System system(options, pipeline.calibration(), pipeline.make_depth_source(), pipeline.make_extractor());
  system.use_task_pool(pool);  // the scans' registration across the gap and the bridge
  const rgbl::Sequence& sequence = pipeline.sequence();
  Run run;
  for (std::size_t i = 0; i < sequence.size(); ++i) {
    if (i > last && i < resume) continue;
    const rgbl::FrameInput input = sequence.load(i);
    if (!input.T_world_cam0) throw std::invalid_argument(fmt::format("frame {} has no ground truth", i));
    run.frames.push_back(i);
    run.truth.push_back(*input.T_world_cam0);
    run.results.push_back(system.track(pipeline.sensor_frame(input)));
  }
  system.finish();
  run.trajectory = system.trajectory();
  return run;
}

// ATE (m) over the frames tracked ok, cam0 poses against the truth.
double ate(const Run& run, const Eigen::Isometry3d& T_cam_cam0) {
  std::vector<Eigen::Isometry3d> estimate, truth;
  for (std::size_t k = 0; k < run.trajectory.size(); ++k) {
    if (run.trajectory[k].state != rgbl::TrackState::Ok) continue;
    estimate.push_back(run.trajectory[k].T_world_cam * T_cam_cam0);
    truth.push_back(run.truth[k]);
  }
  return rgbl::absolute_trajectory_error(estimate, truth).translation.rmse;
}

// The largest distance of a frame tracked ok from `resume` on from the same frame of the run without a gap.
double deviation_after(const Run& run, const Run& whole, std::size_t resume) {
  double worst = 0.0;
  for (std::size_t k = 0; k < run.frames.size(); ++k) {
    if (run.frames[k] < resume || run.trajectory[k].state != rgbl::TrackState::Ok) continue;
    const Eigen::Isometry3d& a = run.trajectory[k].T_world_cam;
    const Eigen::Isometry3d& b = whole.trajectory[run.frames[k]].T_world_cam;
    worst = std::max(worst, (a.translation() - b.translation()).norm());
  }
  return worst;
}

// The new maps and closures, each closure with how far its two frames' written relative pose is from
// the truth's (m, deg): a false bridge shows there.
std::string events(const Run& run, const Eigen::Isometry3d& T_cam_cam0) {
  const auto at = [&](std::size_t frame) {
    return static_cast<std::size_t>(std::find(run.frames.begin(), run.frames.end(), frame) - run.frames.begin());
  };
  std::string out;
  for (std::size_t k = 0; k < run.results.size(); ++k) {
    const rgbl::TrackResult& r = run.results[k];
    if (r.new_map) out += fmt::format(" new map at {};", run.frames[k]);
    if (!r.loop_closure) continue;
    const auto& c = *r.loop_closure;
    const std::size_t a = at(c.frame_index), b = at(c.matched_frame_index);
    std::string error;
    if (a < run.frames.size() && b < run.frames.size()) {
      const Eigen::Isometry3d estimate = (run.trajectory[b].T_world_cam * T_cam_cam0).inverse() *
                                         (run.trajectory[a].T_world_cam * T_cam_cam0);
      const Eigen::Isometry3d truth = run.truth[b].inverse() * run.truth[a];
      const Eigen::Isometry3d e = truth.inverse() * estimate;
      error = fmt::format(" (pair off by {:.3f} m, {:.2f} deg)", e.translation().norm(), degrees(e.linear()));
    }
    out += fmt::format(" {} {} with {}{};", c.bridged ? "bridged" : c.merged ? "merged" : "loop closed", c.frame_index,
                       c.matched_frame_index, error);
  }
  return out.empty() ? " -" : out;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Track a drive with a gap in it, with and without bridging, against the truth and the run without the gap"};
  std::string dir;
  std::size_t last = 0, resume = 0;
  app.add_option("dir", dir, "Dataset folder (as `rgbl run`)")->required();
  app.add_option("--last", last, "Last frame fed before the gap")->required();
  app.add_option("--resume", resume, "First frame fed after the gap")->required();
  std::string settings;
  app.add_option("--settings", settings, "Settings YAML (as `rgbl run --settings`); default: the built-in settings")
      ->check(CLI::ExistingFile);
  bool per_frame = false;
  app.add_flag("--per-frame", per_frame,
               "Also print each frame of the bridged run against the gapless run: as written and as tracked");
  int threads = 0;
  app.add_option("--threads", threads,
                 "Threads for the scans' registration across the gap (0 = the machine's; the result is the same)")
      ->check(CLI::NonNegativeNumber);
  bool verbose = false;
  app.add_flag("-v,--verbose", verbose, "Print the library's debug messages (why a frame was placed where it was)");
  CLI11_PARSE(app, argc, argv);
  rgbl::logger()->set_level(verbose ? spdlog::level::debug : spdlog::level::info);
  try {
    if (resume <= last + 1) throw std::invalid_argument("--resume must leave a gap after --last");
    rgbl::PipelineOptions options;
    options.dataset = dir;
    options.settings = settings;
    const rgbl::Pipeline pipeline(options);
    if (resume >= pipeline.sequence().size()) throw std::invalid_argument("--resume beyond the last frame");
    const Eigen::Isometry3d T_cam_cam0 = pipeline.calibration().T_cam_cam0;
    const auto pool = std::make_shared<rgbl::TaskPool>(threads);
    const Run whole = track(pipeline, pipeline.sequence().size(), pipeline.sequence().size(), true, pool);
    const Run bridged = track(pipeline, last, resume, true, pool);
    const Run apart = track(pipeline, last, resume, false, pool);
    if (per_frame) {
      for (std::size_t k = 0; k < bridged.frames.size(); ++k) {
        const std::size_t f = bridged.frames[k];
        const Eigen::Isometry3d e = bridged.trajectory[k].T_world_cam.inverse() * whole.trajectory[f].T_world_cam;
        const Eigen::Isometry3d e0 = bridged.results[k].T_world_cam.inverse() * whole.trajectory[f].T_world_cam;
        fmt::print("frame {}: {} vs gapless {:.3f} m {:.2f} deg; as tracked {:.3f} m {:.2f} deg\n", f,
                   rgbl::to_string(bridged.results[k].state), e.translation().norm(), degrees(e.linear()),
                   e0.translation().norm(), degrees(e0.linear()));
      }
    }
    const auto lost = [](const Run& run) {
      return std::count_if(run.results.begin(), run.results.end(),
                           [](const rgbl::TrackResult& r) { return r.state != rgbl::TrackState::Ok; });
    };
    fmt::print("{} gap {}-{} | ATE without gap {:.3f} m | bridging: ATE {:.3f} m, off the gapless run by <= {:.3f} m, "
               "{} not ok;{} | without: ATE {:.3f} m, <= {:.3f} m, {} not ok;{}\n",
               dir, last + 1, resume - 1, ate(whole, T_cam_cam0), ate(bridged, T_cam_cam0),
               deviation_after(bridged, whole, resume), lost(bridged), events(bridged, T_cam_cam0),
               ate(apart, T_cam_cam0),
               deviation_after(apart, whole, resume), lost(apart), events(apart, T_cam_cam0));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "rgbl_jump: %s\n", e.what());
    return 1;
  }
}
