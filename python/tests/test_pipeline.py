"""System.track and the Pipeline on a synthetic street with exact ground truth."""

import _thread
import sys
import threading
import time

import numpy as np
import pytest

import rgbl


def test_pipeline_runs_with_progress(street):
    pipeline = rgbl.Pipeline(street.sequence_dir, first=2, step=2)
    assert pipeline.frame_count == 11 and pipeline.camera == 0 and pipeline.depth_name == "lidar"
    calls = []
    result = pipeline.run(progress=lambda record, done, total: calls.append((record.result.frame_index, done, total)))
    assert calls == [(2 + 2 * i, i + 1, 11) for i in range(11)]
    assert result.count(rgbl.TrackState.Ok) == 11
    assert result.trajectory.poses.shape == (11, 4, 4) and result.ground_truth.shape == (11, 4, 4)
    # the world is the ground truth's: the first pose is the ground truth's at frame 2
    assert np.abs(result.trajectory.poses[0] - result.ground_truth[0]).max() < 1e-9
    ate = result.metrics.evaluation.ate.translation.rmse
    assert ate < 0.1
    same = rgbl.absolute_trajectory_error(result.trajectory.poses, result.ground_truth)
    assert same.translation.rmse == ate
    assert result.landmarks.shape[1] == 3 and len(result.landmarks) > 100
    assert len(result.keyframes) == result.keyframe_count() >= 2
    assert result.timings().total.median > 0
    # the summary `rgbl run` prints, with this run's figures
    text = str(result)
    assert text == result.summary_text() and "ok 11, weak 0, lost 0" in text
    assert f"ATE RMSE {ate:.3f} m" in text
    # views of the result's buffers
    assert np.shares_memory(result.trajectory.poses, result.trajectory.poses)


def test_progress_errors_stop_the_run(street):
    pipeline = rgbl.Pipeline(street.sequence_dir, frames=6)

    def progress(record, done, total):
        if done == 3:
            raise KeyError("stop here")

    with pytest.raises(KeyError, match="stop here"):
        pipeline.run(progress)


def test_ctrl_c_stops_a_run_between_frames(street):
    # no progress callback: the run still checks for signals. Dense stereo (SGBM) makes the run long
    # enough (~1 s) that the interrupt lands well inside it on a loaded machine too.
    pipeline = rgbl.Pipeline(street.sequence_dir, depth="stereo")
    timer = threading.Timer(0.05, _thread.interrupt_main)  # what SIGINT does
    timer.start()
    start = time.perf_counter()
    with pytest.raises(KeyboardInterrupt):
        pipeline.run()
    stopped = time.perf_counter() - start
    timer.join()
    # stopped at the frames after the interrupt, not after the whole run
    assert stopped < 0.5 * pipeline.run().wall_s


def test_bad_options_name_the_option(street):
    with pytest.raises(rgbl.ConfigError) as info:
        rgbl.Pipeline(street.sequence_dir, step=0)
    assert info.value.key == "step"
    with pytest.raises(rgbl.ConfigError, match="sonar"):
        rgbl.Pipeline(street.sequence_dir, depth="sonar")
    with pytest.raises(rgbl.ConfigError) as info:
        rgbl.Pipeline(street.sequence_dir, playback_rate=-1.0)
    assert info.value.key == "playback_rate"


def track_from_python(pipeline):
    """The frames pipeline.run() tracks, fed through System.track from numpy arrays."""
    system = pipeline.make_system()
    cam = pipeline.camera
    results = []
    for i in range(pipeline.frame_count):
        frame = pipeline.sequence.load(pipeline.frame_index(i))
        results.append(system.track(frame.images[cam], frame.scan, index=frame.index, timestamp=frame.timestamp,
                                    image_right=frame.images[cam + 1]))
    return system, results


def test_python_loop_gives_the_pipelines_trajectory_to_the_bit(street, tmp_path):
    pipeline = rgbl.Pipeline(street.sequence_dir, frames=16)
    system, results = track_from_python(pipeline)
    assert system.frames_tracked == 16
    assert [r.state for r in results] == [rgbl.TrackState.Ok] * 16
    from_python = pipeline.collect(system, results)
    from_cpp = pipeline.run()
    assert np.array_equal(from_python.trajectory.poses, from_cpp.trajectory.poses)
    from_python.write_outputs(tmp_path / "py")
    rgbl.write_run_outputs(from_cpp, tmp_path / "cpp")
    for name in ("trajectory_kitti.txt", "trajectory_tum.txt", "ground_truth_kitti.txt"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cpp" / name).read_bytes()
    raw = system.trajectory()
    assert len(raw) == 16 and raw.frame_indices == list(range(16))
    assert np.allclose(raw.poses[0], np.eye(4))  # the tracker's world is its first camera


def test_system_from_a_calibration_tracks_colour_images(street):
    seq = rgbl.open_sequence(street.sequence_dir)
    system = rgbl.System(seq.calibration.camera(2), depth="lidar")
    for i in range(8):
        frame = seq.load(i)
        result = system.track(frame.images[2], frame.scan)  # BGR, converted to grey inside
        assert result.frame_index == i and result.timestamp == pytest.approx(0.1 * i)
    assert result.state == rgbl.TrackState.Ok and result.inliers >= 30
    assert result.keypoints_with_depth > 100
    # 8 frames at 1 m each along the ground truth: the tracked camera moved the same distance
    truth = seq.ground_truth.poses
    assert np.linalg.norm(result.T_world_cam[:3, 3]) == pytest.approx(np.linalg.norm(truth[7][:3, 3]), rel=0.02)
    assert system.keyframe_count >= 1 and system.landmark_count > 100


def test_stereo_without_a_right_image_raises(street):
    seq = rgbl.open_sequence(street.sequence_dir)
    system = rgbl.System(seq.calibration.camera(0), depth="stereo", stereo_baseline=seq.calibration.baseline(0, 1))
    with pytest.raises(rgbl.ConfigError, match="image_right"):
        system.track(seq.load(0).images[0])


def test_track_releases_the_gil(street):
    seq = rgbl.open_sequence(street.sequence_dir)
    system = rgbl.System(seq.calibration.camera(0))
    frame = seq.load(0)
    system.track(frame.images[0], frame.scan)
    frame = seq.load(1)
    stamps, stop = [], threading.Event()

    def spin():
        while not stop.is_set():
            stamps.append(time.perf_counter())

    interval = sys.getswitchinterval()
    sys.setswitchinterval(10.0)  # the spinning thread only runs when this one lets go of the GIL
    try:
        spinner = threading.Thread(target=spin)
        spinner.start()
        start = time.perf_counter()
        system.track(frame.images[0], frame.scan)
        end = time.perf_counter()
        inside = sum(start < t < end for t in list(stamps))
    finally:
        stop.set()
        sys.setswitchinterval(interval)
        spinner.join()
    assert inside > 0, "no Python thread ran while System.track ran"
