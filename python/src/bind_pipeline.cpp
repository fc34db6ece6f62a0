// rgbl::Pipeline: what `rgbl run` does, with a progress callback, and its RunResult.

#include "common.hpp"

#include "rgbl/pipeline/describe.hpp"
#include "rgbl/pipeline/pipeline.hpp"

#include <optional>
#include <string>

namespace rgbl::python {

void bind_pipeline(py::module_& m) {
  py::class_<PipelineOptions>(m, "PipelineOptions", "What a Pipeline runs (the options of `rgbl run`).")
      .def(py::init<>())
      .def_readwrite("dataset", &PipelineOptions::dataset)
      .def_readwrite("format", &PipelineOptions::format)
      .def_readwrite("camera", &PipelineOptions::camera, "0 or 2; -1: 0 when the dataset has it, else 2.")
      .def_readwrite("first", &PipelineOptions::first)
      .def_readwrite("frames", &PipelineOptions::frames, "0 = all.")
      .def_readwrite("step", &PipelineOptions::step)
      .def_readwrite("depth", &PipelineOptions::depth)
      .def_readwrite("settings", &PipelineOptions::settings)
      .def_readwrite("threaded", &PipelineOptions::threaded)
      .def_readwrite("threads", &PipelineOptions::threads, "Frame threads; 0 = the machine's hardware threads.")
      .def_readwrite("playback_rate", &PipelineOptions::playback_rate,
                     "Frames fed at this multiple of the recording's pace (1: as recorded); 0 = as fast as tracked.")
      .def_readwrite("loop_closing", &PipelineOptions::loop_closing);

  py::class_<FrameRecord>(m, "FrameRecord", "One tracked frame of a run and how long it waited to be loaded.")
      .def_readonly("result", &FrameRecord::result)
      .def_readonly("io_wait_ms", &FrameRecord::io_wait_ms);

  py::class_<StageStats>(m, "StageStats", "Milliseconds over the frames of a run.")
      .def_readonly("median", &StageStats::median)
      .def_readonly("p95", &StageStats::p95)
      .def_readonly("mean", &StageStats::mean)
      .def_readonly("max", &StageStats::max);
  py::class_<RunTimings>(m, "RunTimings", "Per-stage timing over a run.")
      .def_readonly("io_wait", &RunTimings::io_wait)
      .def_readonly("depth", &RunTimings::depth)
      .def_readonly("extraction", &RunTimings::extraction)
      .def_readonly("tracking", &RunTimings::tracking)
      .def_readonly("mapping", &RunTimings::mapping)
      .def_readonly("loop", &RunTimings::loop)
      .def_readonly("front", &RunTimings::front, "depth + extraction + tracking")
      .def_readonly("total", &RunTimings::total);

  py::class_<RunMetrics>(m, "RunMetrics", "Accuracy against the ground truth over the frames it covers.")
      .def_readonly("frames_with_ground_truth", &RunMetrics::frames_with_ground_truth)
      .def_readonly("frames_tracked", &RunMetrics::frames_tracked, "Of those, frames tracked (ok or weak).")
      .def_readonly("evaluation", &RunMetrics::evaluation, "Over every frame (untracked ones at their guessed pose).")
      .def_readonly("tracked_ate", &RunMetrics::tracked_ate,
                    "AteResult over the tracked frames alone, or None with fewer than 2.")
      .def_readonly("kitti_lengths", &RunMetrics::kitti_lengths);

  py::class_<RunResult>(m, "RunResult",
                        "Everything a run produced, in the ground truth's world (T_world_cam0 of KITTI's reference "
                        "camera). Arrays share the result's memory.")
      .def_readonly("sequence_name", &RunResult::sequence_name)
      .def_readonly("sequence_path", &RunResult::sequence_path)
      .def_readonly("format", &RunResult::format)
      .def_readonly("camera", &RunResult::camera)
      .def_readonly("depth", &RunResult::depth)
      .def_readonly("first", &RunResult::first)
      .def_readonly("step", &RunResult::step)
      .def_readonly("threaded", &RunResult::threaded)
      .def_readonly("threads", &RunResult::threads)
      .def_readonly("playback_rate", &RunResult::playback_rate)
      .def_readonly("loop_closing", &RunResult::loop_closing)
      .def_readonly("frames", &RunResult::frames, "A FrameRecord per tracked frame (a list copied on each access).")
      .def_property_readonly("trajectory", [](const py::object& self) {
        return py::cast(&self.cast<const RunResult&>().trajectory, py::return_value_policy::reference_internal, self);
      }, "A pose per frame (Trajectory), corrected by every loop closure.")
      .def_property_readonly("ground_truth", [](const py::object& self) {
        return poses_array(self.cast<const RunResult&>().ground_truth, self);
      }, "float64 N x 4 x 4: the ground truth of the first N frames of `trajectory` (N may be 0).")
      .def_readonly("loop_closures", &RunResult::loop_closures)
      .def_property_readonly("landmarks", [](const py::object& self) {
        return points_array(self.cast<const RunResult&>().landmarks, self);
      }, "float64 N x 3: the final map's points.")
      .def_property_readonly("keyframes", [](const py::object& self) {
        return poses_array(self.cast<const RunResult&>().keyframes, self);
      }, "float64 N x 4 x 4: T_world_cam0 of every keyframe.")
      .def_readonly("wall_s", &RunResult::wall_s)
      .def_readonly("metrics", &RunResult::metrics, "RunMetrics, or None without >= 2 frames of ground truth.")
      .def_readonly("frames_planned", &RunResult::frames_planned)
      .def_readonly("stopped", &RunResult::stopped, "Stopped on request before the last frame: every output is partial.")
      .def("count", &RunResult::count, py::arg("state"), "Frames in a TrackState.")
      .def("tracked_count", &RunResult::tracked_count, "Frames with a tracked pose (ok or weak).")
      .def("failed", &RunResult::failed,
           "No frame tracked in a whole run: the trajectory is guesses (write_outputs writes timing.csv and "
           "summary.json alone).")
      .def("keyframe_count", &RunResult::keyframe_count)
      .def("timings", &RunResult::timings)
      .def("summary_json", &summary_json, "summary.json's content.")
      .def("summary_text", &summary_text, "The run in a few lines, as `rgbl run` prints it.")
      .def("__str__", &summary_text)
      .def("write_outputs",
           [](const RunResult& r, const std::filesystem::path& out_dir) { write_run_outputs(r, out_dir); },
           py::arg("out_dir"),
           "Writes what `rgbl run` writes: trajectory_kitti.txt, trajectory_tum.txt, ground_truth_kitti.txt, "
           "timing.csv, summary.json, trajectory.svg, map.ply (a failed() run: timing.csv and summary.json).");

  m.def(
      "describe_sequence",
      [](const Sequence& sequence) {
        const py::gil_scoped_release release;  // reads frame 0's scan
        return describe_sequence(sequence);
      },
      py::arg("sequence"),
      "What `rgbl info` prints: layout, frames, cameras, LiDAR, depth camera, ground truth and the loader's notes.");

  m.def("write_run_outputs",
        [](const RunResult& r, const std::filesystem::path& out_dir) { write_run_outputs(r, out_dir); },
        py::arg("result"), py::arg("out_dir"),
        "The same as RunResult.write_outputs(out_dir).");
  m.def("run_output_files", &run_output_files, "The files write_run_outputs() writes.");

  py::class_<Pipeline>(m, "Pipeline",
                       "What `rgbl run` does, as a library: open a dataset, resolve the depth source and settings, "
                       "track every frame, re-express the poses in the ground truth's world and evaluate. "
                       "Construction checks everything and raises ConfigError / ParseError naming what is wrong.\n\n"
                       "    pipeline = rgbl.Pipeline('sequences/04', depth='lidar')\n"
                       "    result = pipeline.run(progress=lambda record, done, total: print(done, total))\n"
                       "    result.write_outputs('out')  # the files `rgbl run --out out` writes")
      .def(py::init([](const PipelineOptions& options) {
             const py::gil_scoped_release release;
             return std::make_unique<Pipeline>(options);
           }),
           py::arg("options"))
      .def(py::init([](const std::filesystem::path& dataset, const std::string& format, int camera, std::size_t first,
                       std::size_t frames, std::size_t step, const std::string& depth,
                       const std::optional<std::filesystem::path>& settings, bool threaded, bool loop_closing,
                       int threads, double playback_rate) {
             PipelineOptions o;
             o.dataset = dataset;
             o.format = parse_dataset_format(format);
             o.camera = camera;
             o.first = first;
             o.frames = frames;
             o.step = step;
             o.depth = depth;
             o.settings = settings.value_or(std::filesystem::path());  // pathlib makes '' into '.'
             o.threaded = threaded;
             o.loop_closing = loop_closing;
             o.threads = threads;
             o.playback_rate = playback_rate;
             const py::gil_scoped_release release;
             return std::make_unique<Pipeline>(o);
           }),
           py::arg("dataset"), py::kw_only(), py::arg("format") = "auto", py::arg("camera") = -1, py::arg("first") = 0,
           py::arg("frames") = 0, py::arg("step") = 1, py::arg("depth") = "lidar",
           py::arg("settings") = py::none(), py::arg("threaded") = false, py::arg("loop_closing") = true,
           py::arg("threads") = 0, py::arg("playback_rate") = 0.0,
           "The options of `rgbl run <dataset>`: format auto|kitti|kitti-raw|tum, camera 0|2 (-1: 0 when present), "
           "first frame, frames (0 = all), step, depth source spec, settings YAML, threaded, loop_closing, threads (0: the machine's), "
           "playback_rate (1: the recording's pace, `--realtime`; 0: as fast as tracked).")
      .def_property_readonly("options", &Pipeline::options)
      .def_property_readonly("sequence", &Pipeline::sequence, py::return_value_policy::reference_internal)
      .def_property_readonly("camera", &Pipeline::camera)
      .def_property_readonly("calibration", &Pipeline::calibration)
      .def_property_readonly("depth_name", &Pipeline::depth_name)
      .def_property_readonly("frame_count", &Pipeline::frame_count, "Frames run() tracks.")
      .def("frame_index", &Pipeline::frame_index, py::arg("i"), "Dataset index of the i-th frame run() tracks.")
      .def_property_readonly("orb_options", &Pipeline::orb_options)
      .def_property_readonly("notes", &Pipeline::notes, "Decisions taken on the user's behalf, to show once.")
      .def("make_system", [](const Pipeline& p) { return wrap_system(p.make_system(), p.system_options().frame_period); },
           "A System exactly as run() tracks with.")
      .def(
          "run",
          [](const Pipeline& p, const py::object& progress) {
            // The callback runs with the GIL; without one the loop still checks for Ctrl-C each frame.
            const Pipeline::Progress callback = [&progress](const FrameRecord& record, std::size_t done,
                                                            std::size_t total) {
              const py::gil_scoped_acquire acquire;
              if (PyErr_CheckSignals() != 0) throw py::error_already_set();
              if (!progress.is_none()) progress(record, done, total);
            };
            const py::gil_scoped_release release;
            return p.run(callback);
          },
          py::arg("progress") = py::none(),
          "Tracks every frame (the next loaded on a second thread; the GIL released), waits for threaded mapping "
          "and evaluates. progress(record: FrameRecord, done, total) is called after every frame.")
      .def(
          "collect",
          [](const Pipeline& p, const py::object& system, const std::vector<TrackResult>& results, double wall_s) {
            std::vector<FrameRecord> records(results.size());
            for (std::size_t i = 0; i < results.size(); ++i) records[i].result = results[i];
            System& s = unwrap_system(system);
            const py::gil_scoped_release release;
            return p.collect(s, std::move(records), wall_s);
          },
          py::arg("system"), py::arg("results"), py::arg("wall_s") = 0.0,
          "The RunResult of frames a caller tracked itself with make_system(): results are the TrackResults of "
          "frames frame_index(0), frame_index(1), ... in order. Finishes the system, re-expresses and evaluates "
          "exactly as run() does.");
}

}  // namespace rgbl::python
