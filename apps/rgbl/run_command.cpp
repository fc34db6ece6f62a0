// rgbl run <dir> [input options] [--out <dir>] [--threaded]
#include "command.hpp"
#include "pipeline.hpp"
#include "run.hpp"

#include "rgbl/core/error.hpp"
#include "rgbl/core/timer.hpp"
#include "rgbl/eval/trajectory_metrics.hpp"
#include "rgbl/io/ply.hpp"
#include "rgbl/io/read_ahead.hpp"
#include "rgbl/io/svg_plot.hpp"
#include "rgbl/io/trajectory_io.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <system_error>
#include <unordered_map>
#include <vector>

namespace rgbl::cli {
namespace {

struct StageStats {
  double median = 0.0, p95 = 0.0, mean = 0.0, max = 0.0;
};

StageStats stats(std::vector<double> v) {
  StageStats s;
  if (v.empty()) return s;
  std::sort(v.begin(), v.end());
  const auto at = [&](double q) { return v[static_cast<std::size_t>(std::min<double>(v.size() - 1, std::floor(q * (v.size() - 1) + 0.5)))]; };
  s.median = at(0.5);
  s.p95 = at(0.95);
  double sum = 0.0;
  for (const double x : v) sum += x;
  s.mean = sum / static_cast<double>(v.size());
  s.max = v.back();
  return s;
}

std::string json_number(double v) { return std::isfinite(v) ? fmt::format("{:.6g}", v) : "null"; }

std::string json_string(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      out += fmt::format("\\u{:04x}", static_cast<int>(c));
      continue;
    }
    out += c;
  }
  return out + "\"";
}

// Short runs get shorter KITTI segment lengths (SPEC 6): 8 steps of a round length below the path.
KittiMetricOptions kitti_lengths_for(double path_length, std::string& description) {
  KittiMetricOptions options;
  if (path_length >= 800.0) {
    description = "100..800 m";
    return options;
  }
  const double step = std::max(1.0, std::ceil(path_length / 80.0)) * 10.0;
  options.lengths.clear();
  for (double l = step; l < path_length && options.lengths.size() < 8; l += step) options.lengths.push_back(l);
  if (options.lengths.empty()) options.lengths.push_back(std::max(1.0, std::floor(path_length / 2.0)));
  description = fmt::format("{:g}..{:g} m (short run)", options.lengths.front(), options.lengths.back());
  return options;
}

// Outputs of an earlier run in the same folder would look like this run's if it fails: remove them
// before anything can fail (a successful run overwrites them anyway).
void remove_previous_outputs(const std::filesystem::path& out_dir) {
  for (const char* name : {"trajectory_kitti.txt", "trajectory_tum.txt", "ground_truth_kitti.txt",
                           "timing.csv", "summary.json", "trajectory.svg", "map.ply"}) {
    std::error_code ec;
    std::filesystem::remove(out_dir / name, ec);
  }
}

struct FrameRecord {
  TrackResult result;
  double io_wait_ms = 0.0;
};

}  // namespace

RunOutcome run_pipeline(Pipeline& p, const std::filesystem::path& out_dir, bool threaded, bool quiet) {
  std::filesystem::create_directories(out_dir);
  remove_previous_outputs(out_dir);
  SystemOptions system_options = p.system;
  system_options.threaded_mapping = threaded;
  System system(system_options, p.calibration, p.make_depth_source(), p.make_extractor());

  ReadAheadOptions read_options;
  read_options.first = p.first;
  read_options.count = p.count;
  read_options.step = p.step;
  ReadAhead frames(*p.sequence, read_options);
  const bool tty = ::isatty(STDERR_FILENO) != 0;
  std::vector<FrameRecord> records;
  records.reserve(p.count);
  Stopwatch wall;
  Stopwatch progress_clock;
  for (;;) {
    Stopwatch wait;
    std::optional<FrameInput> input = frames.next();
    const double wait_ms = wait.elapsed_ms();
    if (!input) break;
    FrameRecord record;
    record.result = system.track(sensor_frame(*input, p.camera));
    record.io_wait_ms = wait_ms;
    records.push_back(record);
    if (!quiet && (progress_clock.elapsed_ms() > 1000.0 || records.size() == p.count)) {
      progress_clock.restart();
      const auto& r = record.result;
      const std::string line = fmt::format("frame {}/{}  {}  {:.1f} ms  {:.1f} frames/s", records.size(), p.count,
                                           to_string(r.state), r.timing.total_ms,
                                           static_cast<double>(records.size()) / (wall.elapsed_ms() / 1000.0));
      if (tty) {
        fmt::print(stderr, "\r{:<70}", line);
      } else {
        fmt::print(stderr, "{}\n", line);
      }
    }
  }
  system.finish();
  const std::vector<LoopClosure> all_closures = system.loop_closures();  // threaded: some came after the last frame
  if (!quiet && tty) fmt::print(stderr, "\n");

  RunOutcome out;
  out.wall_s = wall.elapsed_ms() / 1000.0;
  out.frames = records.size();
  for (const auto& r : records) {
    out.tracked += r.result.state == TrackState::Ok ? 1 : 0;
    out.weak += r.result.state == TrackState::Weak ? 1 : 0;
    if (r.result.state == TrackState::Ok) {
      out.min_inliers_ok = std::min(out.min_inliers_ok.value_or(r.result.inliers), r.result.inliers);
    }
    out.lost += r.result.state == TrackState::Lost ? 1 : 0;
    out.not_initialised += r.result.state == TrackState::NotInitialised ? 1 : 0;
    out.keyframes += r.result.keyframe ? 1 : 0;
  }

  // Poses of cam0 (KITTI's reference camera) in the world of the ground truth when there is one (so
  // that files line up with poses/NN.txt), else in the first frame's cam0.
  const auto trajectory = system.trajectory();
  const Eigen::Isometry3d T_cam_cam0 = p.calibration.T_cam_cam0;
  const auto& gt = p.sequence->ground_truth();
  Eigen::Isometry3d T_world_first = Eigen::Isometry3d::Identity();
  if (gt && p.first < gt->size()) T_world_first = gt->poses[p.first];
  Trajectory estimate;
  for (const auto& pose : trajectory) {
    estimate.timestamps.push_back(pose.timestamp);
    estimate.poses.push_back(T_world_first * T_cam_cam0.inverse() * pose.T_world_cam * T_cam_cam0);
  }
  write_kitti_trajectory(out_dir / "trajectory_kitti.txt", estimate.poses);
  write_tum_trajectory(out_dir / "trajectory_tum.txt", estimate);

  // timing.csv: a row per frame, a column per stage
  {
    std::ofstream csv(out_dir / "timing.csv");
    csv << "frame,timestamp,state,keyframe,keypoints,keypoints_with_depth,inliers,io_wait_ms,depth_ms,"
           "extraction_ms,tracking_ms,mapping_ms,loop_ms,total_ms\n";
    for (const auto& r : records) {
      const auto& t = r.result.timing;
      csv << fmt::format("{},{:.6f},{},{},{},{},{},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f}\n",
                         r.result.frame_index, r.result.timestamp, to_string(r.result.state), r.result.keyframe ? 1 : 0,
                         r.result.keypoints, r.result.keypoints_with_depth, r.result.inliers, r.io_wait_ms,
                         t.depth_ms, t.extraction_ms, t.tracking_ms, t.mapping_ms, t.loop_ms, t.total_ms);
    }
    if (!csv) throw Error(fmt::format("{}: cannot write", (out_dir / "timing.csv").string()));
  }

  // metrics against ground truth over the frames it covers
  std::vector<Eigen::Isometry3d> est_poses, gt_poses;
  if (gt) {
    for (std::size_t i = 0; i < estimate.poses.size() && p.first + i * p.step < gt->size(); ++i) {
      est_poses.push_back(estimate.poses[i]);
      gt_poses.push_back(gt->poses[p.first + i * p.step]);
    }
    // the ground truth of the frames run, row for row with trajectory_kitti.txt (for evo and plots;
    // a raw drive's comes from OXTS and has no file of its own)
    write_kitti_trajectory(out_dir / "ground_truth_kitti.txt", gt_poses);
  }
  std::string metrics_json = "null";
  if (gt_poses.size() >= 2) {
    const auto ate = absolute_trajectory_error(est_poses, gt_poses);
    const auto drift = end_point_drift(est_poses, gt_poses);
    const auto rpe = relative_pose_error(est_poses, gt_poses, 1);
    const auto kitti = kitti_metric(est_poses, gt_poses, kitti_lengths_for(drift.path_length, out.kitti_lengths));
    out.ate_rmse_m = ate.translation.rmse;
    out.drift_percent = drift.percent;
    out.kitti_t_err_percent = kitti.t_err_percent;
    out.kitti_r_err_deg_per_100m = kitti.r_err_deg_per_100m;
    metrics_json = fmt::format(
        "{{\"frames_with_ground_truth\": {}, \"path_length_m\": {}, \"ate_rmse_m\": {}, \"ate_max_m\": {}, "
        "\"end_point_drift_m\": {}, \"end_point_drift_percent\": {}, \"rpe_translation_rmse_m\": {}, "
        "\"rpe_rotation_rmse_deg\": {}, \"kitti\": {{\"lengths\": {}, \"segments\": {}, \"t_err_percent\": {}, "
        "\"r_err_deg_per_100m\": {}}}}}",
        gt_poses.size(), json_number(drift.path_length), json_number(ate.translation.rmse),
        json_number(ate.translation.max), json_number(drift.end_error), json_number(drift.percent),
        json_number(rpe.translation.rmse), json_number(rpe.rotation_deg.rmse), json_string(out.kitti_lengths),
        kitti.segments, json_number(kitti.t_err_percent), json_number(kitti.r_err_deg_per_100m));
  }

  // trajectory plot against ground truth
  {
    std::vector<PlotSeries> series;
    if (!gt_poses.empty()) {
      PlotSeries g{"ground truth", "#444444", {}, true};
      for (const auto& T : gt_poses) g.positions.push_back(T.translation());
      series.push_back(std::move(g));
    }
    PlotSeries e{fmt::format("rgbl ({})", p.depth_name), "#d62728", {}, false};
    for (std::size_t i = 0; i < estimate.poses.size(); ++i) {
      const bool ok = i < records.size() && has_pose(records[i].result.state);
      e.positions.push_back(ok ? Eigen::Vector3d(estimate.poses[i].translation())
                               : Eigen::Vector3d::Constant(std::nan("")));
    }
    // each loop closure joins its frame to the frame it matched, both as finally estimated
    std::vector<PlotLink> links;
    std::unordered_map<std::size_t, std::size_t> row_of_frame;  // dataset frame index -> trajectory row
    for (std::size_t i = 0; i < records.size() && i < estimate.poses.size(); ++i) {
      row_of_frame[records[i].result.frame_index] = i;
    }
    for (const LoopClosure& c : all_closures) {
      const auto current = row_of_frame.find(c.frame_index);
      const auto matched = row_of_frame.find(c.matched_frame_index);
      if (current == row_of_frame.end() || matched == row_of_frame.end()) continue;
      links.push_back({estimate.poses[current->second].translation(), estimate.poses[matched->second].translation(),
                       fmt::format("{}-{}", c.frame_index, c.matched_frame_index)});
    }
    series.push_back(std::move(e));
    write_trajectory_svg(out_dir / "trajectory.svg", series,
                         fmt::format("{}: camera {}, depth {}", p.sequence->name(), p.camera, p.depth_name), links);
  }

  // the map: landmarks and keyframe poses, in the same world frame as the trajectory files
  {
    const Map& map = system.map();
    std::shared_lock lock(map.mutex());
    const Eigen::Isometry3d T_out_world = T_world_first * T_cam_cam0.inverse();
    std::vector<Eigen::Vector3d> points;
    for (const auto id : map.landmark_ids()) {
      if (const Landmark* l = map.landmark(id)) points.push_back(T_out_world * l->position);
    }
    std::vector<Eigen::Isometry3d> cameras;
    for (const auto id : map.keyframe_ids()) {
      if (const auto T_cam_world = map.keyframe_pose(id)) cameras.push_back(T_out_world * T_cam_world->inverse() * T_cam_cam0);
    }
    out.landmarks = points.size();
    write_ply(out_dir / "map.ply", points, {}, cameras);
  }

  std::vector<double> depth_ms, extraction_ms, tracking_ms, mapping_ms, loop_ms, total_ms, front_ms, io_ms;
  for (const auto& r : records) {
    const auto& t = r.result.timing;
    depth_ms.push_back(t.depth_ms);
    extraction_ms.push_back(t.extraction_ms);
    tracking_ms.push_back(t.tracking_ms);
    mapping_ms.push_back(t.mapping_ms);
    loop_ms.push_back(t.loop_ms);
    total_ms.push_back(t.total_ms);
    front_ms.push_back(t.depth_ms + t.extraction_ms + t.tracking_ms);
    io_ms.push_back(r.io_wait_ms);
  }
  const auto depth = stats(depth_ms);
  const auto extraction = stats(extraction_ms);
  const auto tracking = stats(tracking_ms);
  const auto mapping = stats(mapping_ms);
  const auto front = stats(front_ms);
  const auto total = stats(total_ms);
  out.median_front_ms = front.median;
  out.median_total_ms = total.median;
  out.mean_total_ms = total.mean;
  const auto stage_json = [](const char* name, const StageStats& s) {
    return fmt::format("\"{}\": {{\"median\": {}, \"p95\": {}, \"mean\": {}, \"max\": {}}}", name,
                       json_number(s.median), json_number(s.p95), json_number(s.mean), json_number(s.max));
  };
  const auto frame_list = [&records](auto&& selected) {
    std::string list;
    for (const auto& r : records) {
      if (selected(r.result)) list += (list.empty() ? "" : ", ") + std::to_string(r.result.frame_index);
    }
    return list;
  };
  const std::string lost_frames = frame_list([](const TrackResult& r) { return r.state == TrackState::Lost; });
  const std::string weak_frames = frame_list([](const TrackResult& r) { return r.state == TrackState::Weak; });
  // Frames where tracking, lost beyond relocalisation, started a new map anchored at a guessed pose.
  const std::string new_map_frames = frame_list([](const TrackResult& r) { return r.new_map; });
  // Steps beyond a vehicle's reach: taken on strong evidence, or rejected (the frame placed at the prediction).
  const std::string jump_frames = frame_list([](const TrackResult& r) { return r.jump; });
  const std::string rejected_frames = frame_list([](const TrackResult& r) { return r.step_rejected; });
  // Loops closed: where, against what, how far the map moved there, and the cost.
  std::string loop_closures;
  std::vector<const LoopClosure*> closures;
  for (const LoopClosure& c : all_closures) {
    closures.push_back(&c);
    loop_closures += fmt::format(
        "{}\n    {{\"frame\": {}, \"matched_frame\": {}, \"merge\": {}, \"place\": \"{}\", \"place_similarity\": {}, "
        "\"inliers\": {}, "
        "\"correction_m\": {}, \"correction_deg\": {}, \"loop_error_before_m\": {}, \"loop_error_after_m\": {}, "
        "\"fused_landmarks\": {}, \"global_ba\": {{\"keyframes\": {}, \"held\": {}, \"landmarks\": {}, \"outliers\": {}, "
        "\"time_ms\": {}}}, \"time_ms\": {}}}",
        loop_closures.empty() ? "" : ",", c.frame_index, c.matched_frame_index, c.merged ? "true" : "false",
        c.place_source, json_number(c.place_similarity), c.inliers,
        json_number(c.correction_m), json_number(c.correction_deg), json_number(c.correction.loop_error_before_m),
        json_number(c.correction.loop_error_after_m), c.fused_landmarks, c.global_ba_keyframes, c.global_ba_held, c.global_ba_landmarks,
        c.global_ba_outliers, json_number(c.global_ba_ms), json_number(c.time_ms));
  }
  if (!loop_closures.empty()) loop_closures += "\n  ";
  const LoopClosingStats loop_stats = system.loop_statistics();
  {
    const auto file = out_dir / "summary.json";
    std::ofstream json(file);
    json << "{\n"
         << fmt::format("  \"sequence\": {},\n  \"format\": {},\n  \"camera\": {},\n  \"depth\": {},\n",
                        json_string(p.sequence->path().string()), json_string(std::string(to_string(p.sequence->format()))),
                        p.camera, json_string(p.depth_name))
         << fmt::format("  \"first_frame\": {},\n  \"step\": {},\n", p.first, p.step)
         << fmt::format("  \"frames\": {},\n  \"tracked\": {},\n  \"weak\": {},\n  \"lost\": {},\n"
                        "  \"not_initialised\": {},\n  \"weak_frames\": [{}],\n  \"lost_frames\": [{}],\n"
                        "  \"new_map_frames\": [{}],\n  \"jump_frames\": [{}],\n  \"rejected_step_frames\": [{}],\n"
                        "  \"min_inliers_ok\": {},\n  \"keyframes\": {},\n  \"landmarks\": {},\n",
                        out.frames, out.tracked, out.weak, out.lost, out.not_initialised, weak_frames, lost_frames,
                        new_map_frames, jump_frames, rejected_frames,
                        out.min_inliers_ok ? std::to_string(*out.min_inliers_ok) : "null", out.keyframes,
                        out.landmarks)
         << fmt::format("  \"loop_closing\": {},\n  \"loop_closures\": [{}],\n",
                        system.loop_closing() ? "true" : "false", loop_closures)
         << fmt::format("  \"loop_candidates\": {{\"keyframes\": {}, \"candidates\": {}, \"verified\": {}, "
                        "\"implausible\": {}, \"consistent\": {}, \"confirming\": {}, \"closures\": {}, "
                        "\"merges\": {}, \"time_ms\": {}}},\n",
                        loop_stats.keyframes, loop_stats.candidates, loop_stats.verified, loop_stats.implausible,
                        loop_stats.consistent, loop_stats.confirming, loop_stats.closures, loop_stats.merges,
                        json_number(loop_stats.time_ms))
         << fmt::format("  \"threaded_mapping\": {},\n  \"wall_s\": {},\n", threaded ? "true" : "false",
                        json_number(out.wall_s))
         << "  \"stage_ms\": {\n    " << stage_json("io_wait", stats(io_ms)) << ",\n    "
         << stage_json("depth", depth) << ",\n    " << stage_json("extraction", extraction)
         << ",\n    " << stage_json("tracking", tracking) << ",\n    " << stage_json("mapping", mapping)
         << ",\n    " << stage_json("loop", stats(loop_ms))
         << ",\n    " << stage_json("depth_extraction_tracking", front) << ",\n    " << stage_json("total", total)
         << "\n  },\n"
         << "  \"metrics\": " << metrics_json << "\n}\n";
    if (!json) throw Error(fmt::format("{}: cannot write", file.string()));
  }

  fmt::print("\n{} ({}), camera {}, depth {}: {} frames in {:.1f} s\n", p.sequence->name(),
             to_string(p.sequence->format()), p.camera, p.depth_name, out.frames, out.wall_s);
  fmt::print("  ok {}, weak {}, lost {}, not initialised {}; {} keyframes, {} landmarks\n", out.tracked,
             out.weak, out.lost, out.not_initialised, out.keyframes, out.landmarks);
  if (!jump_frames.empty()) fmt::print("  steps beyond a vehicle's reach taken at frame(s) {}\n", jump_frames);
  if (!new_map_frames.empty()) fmt::print("  lost beyond relocalisation: new map started at frame(s) {}\n", new_map_frames);
  if (loop_stats.implausible > 0) {
    fmt::print("  loop closing refused {} verified loop(s) asking for more correction than odometry can drift\n",
               loop_stats.implausible);
  }
  for (const LoopClosure* c : closures) {
    fmt::print("  {} at frame {} with frame {}: map moved {:.2f} m / {:.2f} deg there, {} landmarks fused, "
               "{:.0f} ms (global BA of {} keyframes {:.0f} ms)\n",
               c->merged ? "maps merged" : "loop closed", c->frame_index, c->matched_frame_index, c->correction_m,
               c->correction_deg, c->fused_landmarks,
               c->time_ms, c->global_ba_keyframes, c->global_ba_ms);
  }
  fmt::print("  per frame (median / p95 ms): depth {:.2f} / {:.2f}, extraction {:.2f} / {:.2f}, tracking {:.2f} / "
             "{:.2f}, mapping {:.2f} / {:.2f}\n",
             depth.median, depth.p95, extraction.median, extraction.p95, tracking.median, tracking.p95,
             mapping.median, mapping.p95);
  fmt::print("  depth+extraction+tracking {:.2f} ms median; total {:.2f} ms median, {:.2f} ms mean\n", front.median,
             total.median, total.mean);
  if (out.ate_rmse_m) {
    fmt::print("  ATE RMSE {:.3f} m, end-point drift {:.2f} %, KITTI metric ({}) {:.2f} % / {:.3f} deg/100m\n",
               *out.ate_rmse_m, *out.drift_percent, out.kitti_lengths, *out.kitti_t_err_percent,
               *out.kitti_r_err_deg_per_100m);
  } else {
    fmt::print("  no ground truth: no accuracy figures\n");
  }
  fmt::print("  outputs in {}: trajectory_kitti.txt trajectory_tum.txt timing.csv summary.json trajectory.svg "
             "map.ply\n",
             out_dir.string());
  return out;
}

Command add_run_command(CLI::App& parent) {
  auto* app = parent.add_subcommand("run", "Track a dataset and write trajectories, timings, a summary, a plot and the map");
  auto options = std::make_shared<InputOptions>();
  auto out_dir = std::make_shared<std::string>("rgbl_output");
  auto threaded = std::make_shared<bool>(false);
  auto no_loop_closing = std::make_shared<bool>(false);
  add_input_options(*app, *options);
  app->add_option("--out", *out_dir, "Output folder")->capture_default_str();
  app->add_flag("--threaded", *threaded, "Local mapping and loop closing in threads of their own (default: inline, bit-for-bit reproducible)");
  app->add_flag("--no-loop-closing", *no_loop_closing,
                "Do not close loops (default: closed on every keyframe, inline, or in a thread of its own with --threaded)");
  return {app, [options, out_dir, threaded, no_loop_closing, app] {
            remove_previous_outputs(*out_dir);
            Pipeline pipeline = make_pipeline(*options);
            if (*no_loop_closing) pipeline.system.loop_closing.enabled = false;
            const bool quiet = app->get_parent()->get_option("--quiet")->as<bool>();
            for (const auto& note : pipeline.notes) fmt::print(stderr, "note: {}\n", note);
            run_pipeline(pipeline, *out_dir, *threaded, quiet);
            return 0;
          }};
}

}  // namespace rgbl::cli
