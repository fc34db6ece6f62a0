// A run's files: trajectories (KITTI and TUM, which evo reads), timing.csv, summary.json, the plot
// and the map. Every file is written whole and renamed into place.
#include "rgbl/core/error.hpp"
#include "rgbl/core/file.hpp"
#include "rgbl/io/ply.hpp"
#include "rgbl/io/svg_plot.hpp"
#include "rgbl/pipeline/pipeline.hpp"

#include "json.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <cmath>
#include <iterator>
#include <system_error>
#include <unordered_map>

namespace rgbl {
namespace {

using detail::Json;
using detail::json_number;

Json stage(const StageStats& s) {
  return {{"median", json_number(s.median)},
          {"p95", json_number(s.p95)},
          {"mean", json_number(s.mean)},
          {"max", json_number(s.max)}};
}

Json closure_json(const LoopClosure& c) {
  return {{"frame", c.frame_index},
          {"matched_frame", c.matched_frame_index},
          {"merge", c.merged},
          {"bridge", c.bridged},
          {"place", c.place_source},
          {"place_similarity", json_number(c.place_similarity)},
          {"inliers", c.inliers},
          {"correction_m", json_number(c.correction_m)},
          {"correction_deg", json_number(c.correction_deg)},
          {"loop_error_before_m", json_number(c.correction.loop_error_before_m)},
          {"loop_error_after_m", json_number(c.correction.loop_error_after_m)},
          {"fused_landmarks", c.fused_landmarks},
          {"global_ba",
           {{"keyframes", c.global_ba_keyframes},
            {"held", c.global_ba_held},
            {"landmarks", c.global_ba_landmarks},
            {"outliers", c.global_ba_outliers},
            {"time_ms", json_number(c.global_ba_ms)}}},
          {"time_ms", json_number(c.time_ms)}};
}

Json metrics_json(const RunMetrics& m) {
  const TrajectoryEvaluation& e = m.evaluation;
  const Json tracked = m.tracked_ate ? Json{{"ate_rmse_m", json_number(m.tracked_ate->translation.rmse)},
                                             {"ate_max_m", json_number(m.tracked_ate->translation.max)}}
                                     : Json(nullptr);
  return {{"frames_with_ground_truth", m.frames_with_ground_truth},
          {"frames_tracked", m.frames_tracked},
          {"tracked", tracked},  // ATE over the tracked frames alone; the figures below cover every frame
          {"path_length_m", json_number(e.path_length)},  // the ground truth's
          {"estimated_path_length_m", json_number(e.estimated_path_length)},
          {"ate_rmse_m", json_number(e.ate.translation.rmse)},
          {"ate_max_m", json_number(e.ate.translation.max)},
          {"end_point_drift_m", json_number(e.drift.end_error)},
          {"end_point_drift_percent", json_number(e.drift.percent)},
          {"rpe_translation_rmse_m", json_number(e.rpe.translation.rmse)},
          {"rpe_rotation_rmse_deg", json_number(e.rpe.rotation_deg.rmse)},
          {"kitti",
           {{"lengths", m.kitti_lengths},
            {"segments", e.kitti.segments},
            {"t_err_percent", json_number(e.kitti.t_err_percent)},
            {"r_err_deg_per_100m", json_number(e.kitti.r_err_deg_per_100m)}}}};
}

void write_text(const std::filesystem::path& file, const std::string& text) {
  write_atomically(file, [&](std::ofstream& out) { out << text; });
}

std::string timing_csv(const RunResult& run) {
  std::string csv =
      "frame,timestamp,state,keyframe,keypoints,keypoints_with_depth,inliers,io_wait_ms,depth_ms,"
      "extraction_ms,tracking_ms,mapping_ms,loop_ms,front_ms,total_ms\n";
  for (const auto& r : run.frames) {
    const auto& t = r.result.timing;
    csv += fmt::format("{},{:.6f},{},{},{},{},{},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f},{:.3f}\n",
                       r.result.frame_index, r.result.timestamp, to_string(r.result.state), r.result.keyframe ? 1 : 0,
                       r.result.keypoints, r.result.keypoints_with_depth, r.result.inliers, r.io_wait_ms,
                       t.depth_ms, t.extraction_ms, t.tracking_ms, t.mapping_ms, t.loop_ms, t.front_ms, t.total_ms);
  }
  return csv;
}

void write_plot(const RunResult& run, const std::filesystem::path& file) {
  std::vector<PlotSeries> series;
  if (!run.ground_truth.empty()) {
    PlotSeries g{"ground truth", "#444444", {}, true};
    for (const auto& T : run.ground_truth) g.positions.push_back(T.translation());
    series.push_back(std::move(g));
  }
  const auto& poses = run.trajectory.poses;
  PlotSeries e{fmt::format("rgbl ({})", run.depth), "#d62728", {}, false};
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const bool ok = i < run.frames.size() && has_pose(run.frames[i].result.state);
    e.positions.push_back(ok ? Eigen::Vector3d(poses[i].translation()) : Eigen::Vector3d::Constant(std::nan("")));
  }
  series.push_back(std::move(e));
  // each loop closure joins its frame to the frame it matched, both as finally estimated
  std::unordered_map<std::size_t, std::size_t> row_of_frame;  // dataset frame index -> trajectory row
  for (std::size_t i = 0; i < run.frames.size() && i < poses.size(); ++i) {
    row_of_frame[run.frames[i].result.frame_index] = i;
  }
  std::vector<PlotLink> links;
  for (const LoopClosure& c : run.loop_closures) {
    const auto current = row_of_frame.find(c.frame_index);
    const auto matched = row_of_frame.find(c.matched_frame_index);
    if (current == row_of_frame.end() || matched == row_of_frame.end()) continue;
    links.push_back({poses[current->second].translation(), poses[matched->second].translation(),
                     fmt::format("{}-{}", c.frame_index, c.matched_frame_index)});
  }
  std::string title = fmt::format("{}: camera {}, depth {}", run.sequence_name, run.camera, run.depth);
  if (run.stopped) title += fmt::format(" (partial: stopped after {} of {} frames)", run.frames.size(), run.frames_planned);
  write_trajectory_svg(file, series, title, links);
}

}  // namespace

const std::vector<std::string>& run_output_files() {
  static const std::vector<std::string> files = {"trajectory_kitti.txt", "trajectory_tum.txt",
                                                 "ground_truth_kitti.txt", "timing.csv",
                                                 "summary.json", "trajectory.svg", "map.ply"};
  return files;
}

void remove_run_outputs(const std::filesystem::path& out_dir) {
  for (const auto& name : run_output_files()) {
    std::error_code ec;
    std::filesystem::remove(out_dir / name, ec);
    // and what a run killed while writing it left (the caller holds the folder's lock)
    remove_temporaries_of(out_dir / name);
  }
}

std::string summary_json(const RunResult& run) {
  const RunTimings t = run.timings();
  const LoopClosingStats& l = run.loop_statistics;
  Json closures = Json::array();
  for (const auto& c : run.loop_closures) closures.push_back(closure_json(c));
  const auto min_inliers = run.min_inliers_ok();
  Json j;
  j["sequence"] = run.sequence_path.string();
  j["format"] = std::string(to_string(run.format));
  j["camera"] = run.camera;
  j["depth"] = run.depth;
  j["first_frame"] = run.first;
  j["step"] = run.step;
  j["frames"] = run.frames.size();
  // a run stopped before its last frame (Ctrl-C): every output holds only the frames tracked
  j["partial"] = run.stopped;
  j["frames_planned"] = run.frames_planned;
  j["tracked"] = run.count(TrackState::Ok);
  j["weak"] = run.count(TrackState::Weak);
  j["lost"] = run.count(TrackState::Lost);
  j["not_initialised"] = run.count(TrackState::NotInitialised);
  j["weak_frames"] = run.frames_where([](const TrackResult& r) { return r.state == TrackState::Weak; });
  j["lost_frames"] = run.frames_where([](const TrackResult& r) { return r.state == TrackState::Lost; });
  // where tracking, lost beyond relocalisation, started a new map anchored at a guessed pose
  j["new_map_frames"] = run.frames_where([](const TrackResult& r) { return r.new_map; });
  // steps beyond a vehicle's reach: taken on strong evidence, or rejected (the frame placed at the prediction)
  j["jump_frames"] = run.frames_where([](const TrackResult& r) { return r.jump; });
  j["rejected_step_frames"] = run.frames_where([](const TrackResult& r) { return r.step_rejected; });
  // ...of those, the ones placed by their scan's registration onto the last frame's
  j["registered_rejected_step_frames"] = run.frames_where([](const TrackResult& r) { return r.step_registered; });
  // steps refused although clearly more inliers agreed with them than with the pose kept (weak frames)
  j["contested_step_frames"] = run.frames_where([](const TrackResult& r) { return r.step_contested; });
  // frames placed by the speed before a slide faster than a vehicle brakes (TrackerOptions::speed_window_s)
  j["speed_corrected_frames"] = run.frames_where([](const TrackResult& r) { return r.speed_corrected; });
  // starts chosen by the keypoints without depth against the road and the inliers
  j["rays_start_frames"] = run.frames_where([](const TrackResult& r) { return r.start_by_rays; });
  // suspect poses kept, not lost, on their scan's registration onto the last frame's
  j["scan_confirmed_frames"] = run.frames_where([](const TrackResult& r) { return r.scan_confirmed; });
  // [frame, the first frame placed on the start it refuted]
  j["refuted_starts"] = Json::array();
  for (const auto& f : run.frames) {
    if (f.result.start_refuted_since) j["refuted_starts"].push_back({f.result.frame_index, *f.result.start_refuted_since});
  }
  // first frames after a gap in the timestamps whose scan was registered across it, and those where
  // the registration was accepted as the prediction
  j["gap_frames"] = run.frames_where([](const TrackResult& r) { return r.gap; });
  j["registered_gap_frames"] = run.frames_where([](const TrackResult& r) { return r.gap_registered; });
  // lost frames placed by their scan's registration onto the last frame's (else the constant-velocity guess)
  j["registered_lost_frames"] = run.frames_where([](const TrackResult& r) { return r.lost_registered; });
  j["min_inliers_ok"] = min_inliers ? Json(*min_inliers) : Json(nullptr);
  const auto scan_age = run.scan_age_median();
  j["scan_to_image_ms"] = scan_age ? json_number(*scan_age * 1000.0) : Json(nullptr);  // median; 0: simultaneous
  j["keyframes"] = run.keyframe_count();
  j["landmarks"] = run.landmarks.size();
  j["loop_closing"] = run.loop_closing;
  j["loop_closures"] = std::move(closures);
  j["loop_candidates"] = {{"keyframes", l.keyframes},     {"candidates", l.candidates}, {"verified", l.verified},
                          {"implausible", l.implausible}, {"consistent", l.consistent}, {"confirming", l.confirming},
                          {"closures", l.closures},       {"merges", l.merges},
                          {"bridge_attempts", l.bridge_attempts}, {"bridges", l.bridges},
                          {"scan_refined", l.scan_refined}, {"scan_kept", l.scan_kept},
                          {"time_ms", json_number(l.time_ms)}};
  j["threaded_mapping"] = run.threaded;
  j["threads"] = run.threads;
  j["playback_rate"] = run.playback_rate;
  j["wall_s"] = json_number(run.wall_s);
  j["stage_ms"] = {{"io_wait", stage(t.io_wait)},
                   {"depth", stage(t.depth)},
                   {"extraction", stage(t.extraction)},
                   {"tracking", stage(t.tracking)},
                   {"mapping", stage(t.mapping)},
                   {"loop", stage(t.loop)},
                   {"depth_extraction_tracking", stage(t.front)},
                   {"total", stage(t.total)}};
  j["metrics"] = run.metrics ? metrics_json(*run.metrics) : Json(nullptr);
  // a path that is not UTF-8 is written with replacement characters rather than failing the outputs
  return j.dump(2, ' ', false, Json::error_handler_t::replace) + "\n";
}

std::string summary_text(const RunResult& run) {
  const RunTimings t = run.timings();
  std::string s;
  const auto out = std::back_inserter(s);
  fmt::format_to(out, "{} ({}), camera {}, depth {}: {} frames in {:.1f} s\n", run.sequence_name,
                 to_string(run.format), run.camera, run.depth, run.frames.size(), run.wall_s);
  if (run.stopped) {
    fmt::format_to(out, "  PARTIAL: stopped after {} of {} frames; every output holds only these\n",
                   run.frames.size(), run.frames_planned);
  }
  fmt::format_to(out, "  ok {}, weak {}, lost {}, not initialised {}; {} keyframes, {} landmarks\n",
                 run.count(TrackState::Ok), run.count(TrackState::Weak), run.count(TrackState::Lost),
                 run.count(TrackState::NotInitialised), run.keyframe_count(), run.landmarks.size());
  const auto jumps = run.frames_where([](const TrackResult& r) { return r.jump; });
  const auto new_maps = run.frames_where([](const TrackResult& r) { return r.new_map; });
  if (!jumps.empty()) {
    fmt::format_to(out, "  steps beyond a vehicle's reach taken at frame(s) {}\n", fmt::join(jumps, ", "));
  }
  const auto gaps = run.frames_where([](const TrackResult& r) { return r.gap; });
  if (!gaps.empty()) {
    const auto registered = run.frames_where([](const TrackResult& r) { return r.gap_registered; });
    fmt::format_to(out, "  gaps in the frames before frame(s) {}; the scans registered across the gap at: {}\n",
                   fmt::join(gaps, ", "), registered.empty() ? "none" : fmt::format("{}", fmt::join(registered, ", ")));
  }
  const auto refused = run.frames_where([](const TrackResult& r) { return r.step_registered; });
  if (!refused.empty()) {
    fmt::format_to(out, "  refused step(s) placed by the scans (not the constant-velocity guess): {}\n",
                   fmt::join(refused, ", "));
  }
  const auto contested = run.frames_where([](const TrackResult& r) { return r.step_contested; });
  if (!contested.empty()) {
    fmt::format_to(out, "  frame(s) placed against clearly more support for another pose (weak): {}\n",
                   fmt::join(contested, ", "));
  }
  for (const auto& f : run.frames) {
    if (const TrackResult& r = f.result; r.start_refuted_since) {
      fmt::format_to(out, "  start refuted at frame {} (the keypoints without depth fit its contested step): frames {}-{} "
                     "stay where the wrong start put them\n", r.frame_index, *r.start_refuted_since, r.frame_index - 1);
    }
  }
  const auto by_rays = run.frames_where([](const TrackResult& r) { return r.start_by_rays; });
  if (!by_rays.empty()) {
    fmt::format_to(out, "  start(s) chosen by the keypoints without depth against the road and the inliers (the scale "
                   "unchecked until a contested step): {}\n", fmt::join(by_rays, ", "));
  }
  const auto corrected = run.frames_where([](const TrackResult& r) { return r.speed_corrected; });
  if (!corrected.empty()) {
    fmt::format_to(out, "  frame(s) where the speed had slid faster than a vehicle brakes, placed by the speed before it "
                   "(the keypoints without depth agreeing): {}\n", fmt::join(corrected, ", "));
  }
  const auto confirmed = run.frames_where([](const TrackResult& r) { return r.scan_confirmed; });
  if (!confirmed.empty()) {
    fmt::format_to(out, "  frame(s) the map could not confirm, kept where their scans register (not lost): {}\n",
                   fmt::join(confirmed, ", "));
  }
  const auto placed = run.frames_where([](const TrackResult& r) { return r.lost_registered; });
  if (!placed.empty()) {
    fmt::format_to(out, "  lost frame(s) placed by the scans (not the constant-velocity guess): {}\n", fmt::join(placed, ", "));
  }
  if (!new_maps.empty()) {
    fmt::format_to(out, "  lost beyond relocalisation: new map started at frame(s) {}\n", fmt::join(new_maps, ", "));
  }
  if (run.loop_statistics.implausible > 0) {
    fmt::format_to(out, "  loop closing refused {} verified loop(s) asking for more correction than odometry can "
                   "drift\n", run.loop_statistics.implausible);
  }
  for (const LoopClosure& c : run.loop_closures) {
    fmt::format_to(out, "  {} at frame {} with frame {}: map moved {:.2f} m / {:.2f} deg there, {} landmarks fused, "
                   "{:.0f} ms (global BA of {} keyframes {:.0f} ms)\n",
                   c.bridged ? "maps bridged" : c.merged ? "maps merged" : "loop closed", c.frame_index, c.matched_frame_index, c.correction_m,
                   c.correction_deg, c.fused_landmarks, c.time_ms, c.global_ba_keyframes, c.global_ba_ms);
  }
  if (const auto age = run.scan_age_median(); age && *age != 0.0) {
    fmt::format_to(out, "  LiDAR depth moved to the images' time: scans {:.1f} ms {} (median)\n", std::abs(*age) * 1000.0,
                   *age > 0.0 ? "earlier" : "later");
  }
  fmt::format_to(out, "  per frame (median / p95 ms): depth {:.2f} / {:.2f}, extraction {:.2f} / {:.2f}, tracking "
                 "{:.2f} / {:.2f}, mapping {:.2f} / {:.2f}\n",
                 t.depth.median, t.depth.p95, t.extraction.median, t.extraction.p95, t.tracking.median,
                 t.tracking.p95, t.mapping.median, t.mapping.p95);
  fmt::format_to(out, "  depth+extraction+tracking {:.2f} ms median; total {:.2f} ms median, {:.2f} ms mean\n",
                 t.front.median, t.total.median, t.total.mean);
  if (!run.metrics) {
    fmt::format_to(out, "  no ground truth: no accuracy figures\n");
    return s;
  }
  const RunMetrics& m = *run.metrics;
  const TrajectoryEvaluation& e = m.evaluation;
  if (m.frames_tracked < m.frames_with_ground_truth) {
    // untracked frames carry guesses: the tracked frames' own figure first, the whole run's beside it
    fmt::format_to(out, "  tracked {} of {} frames with ground truth: ATE RMSE {} over those; over all frames (the "
                   "untracked at their guessed pose):\n", m.frames_tracked, m.frames_with_ground_truth,
                   m.tracked_ate ? fmt::format("{:.3f} m", m.tracked_ate->translation.rmse) : "n/a");
  }
  fmt::format_to(out, "  ATE RMSE {:.3f} m, end-point drift {:.2f} %, KITTI metric ({}) {:.2f} % / {:.3f} deg/100m\n",
                 e.ate.translation.rmse, e.drift.percent, m.kitti_lengths, e.kitti.t_err_percent,
                 e.kitti.r_err_deg_per_100m);
  // a path far shorter than the truth's: tracking stood still on something moving with the car
  fmt::format_to(out, "  path {:.1f} m, the ground truth's {:.1f} m\n", e.estimated_path_length, e.path_length);
  return s;
}

void write_run_outputs(const RunResult& run, const std::filesystem::path& out_dir) {
  write_run_outputs(run, OutputFolder(out_dir));
}

void write_run_outputs(const RunResult& run, const OutputFolder& folder) {
  const std::filesystem::path& out_dir = folder.path();
  write_text(out_dir / "timing.csv", timing_csv(run));
  write_text(out_dir / "summary.json", summary_json(run));
  if (run.failed()) return;  // a trajectory of guesses would look like a result
  write_kitti_trajectory(out_dir / "trajectory_kitti.txt", run.trajectory.poses);
  write_tum_trajectory(out_dir / "trajectory_tum.txt", run.trajectory);
  // the ground truth of the frames run, row for row with trajectory_kitti.txt (for evo and plots; a
  // raw drive's comes from OXTS and has no file of its own)
  if (!run.ground_truth.empty()) write_kitti_trajectory(out_dir / "ground_truth_kitti.txt", run.ground_truth);
  write_plot(run, out_dir / "trajectory.svg");
  write_ply(out_dir / "map.ply", run.landmarks, {}, run.keyframes);
}

}  // namespace rgbl
