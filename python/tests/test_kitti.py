"""The real KITTI excerpt (sequence 04, 51 frames): accuracy, bit-identity with `rgbl run`, depth on a real scan."""

import os
import subprocess

import numpy as np
import pytest

import rgbl


def test_python_tracking_matches_rgbl_run_byte_for_byte(seq04, tmp_path):
    cli = os.environ.get("RGBL_CLI")
    if not cli:
        pytest.fail("RGBL_CLI (the rgbl command) is not set; CTest sets it")
    subprocess.run([cli, "-q", "run", str(seq04), "--out", str(tmp_path / "cli")], check=True,
                   stdout=subprocess.DEVNULL)
    pipeline = rgbl.Pipeline(seq04)
    system = pipeline.make_system()
    results = []
    for i in range(pipeline.frame_count):
        frame = pipeline.sequence.load(pipeline.frame_index(i))
        results.append(system.track(frame.images[0], frame.scan, index=frame.index, timestamp=frame.timestamp,
                                    image_right=frame.images[1]))
    result = pipeline.collect(system, results)
    result.write_outputs(tmp_path / "py")
    for name in ("trajectory_kitti.txt", "trajectory_tum.txt", "ground_truth_kitti.txt"):
        assert (tmp_path / "py" / name).read_bytes() == (tmp_path / "cli" / name).read_bytes(), name
    # the accuracy `rgbl run` reports for this excerpt (0.077 m when written), with room for tuning
    assert result.count(rgbl.TrackState.Ok) == 51
    assert result.metrics.evaluation.ate.translation.rmse < 0.12
    assert result.metrics.evaluation.drift.percent < 1.5


def test_lidar_source_is_projection_plus_dilation_on_a_real_scan(seq04):
    seq = rgbl.open_sequence(seq04)
    frame = seq.load(10)
    calibration = seq.calibration.camera(0)
    sparse = rgbl.project_to_depth(frame.scan, calibration)
    assert sparse.shape == (370, 1226)
    assert 15000 < np.count_nonzero(sparse) < 30000  # ~20k of 124k points fall into the image
    # the source drops the samples behind foreground edges in the camera's view (0.3 deg, 25 % nearer)
    radius = rgbl.occlusion_radius_px(calibration.camera.fx, 0.3)
    assert radius == 4  # 707 px * tan(0.3 deg) = 3.7 px
    visible = rgbl.remove_occluded_samples(sparse, radius, 1.25)
    dropped = np.count_nonzero(sparse) - np.count_nonzero(visible)
    assert 0 < dropped < 0.1 * np.count_nonzero(sparse)
    assert np.all((visible == 0) | (visible == sparse))
    dense = rgbl.dilate_depth(visible)
    assert rgbl.depth_density(dense) > 3 * rgbl.depth_density(sparse)
    source = rgbl.make_depth_source("lidar", calibration)
    source.prepare(frame.images[0], frame.scan)
    assert np.array_equal(source.dense_depth(), dense)
    # keypoints read the same depths as the dense map where they fall on a sample
    v, u = np.nonzero(visible)
    pixels = np.column_stack([u[:50], v[:50]]).astype(np.float32)
    assert np.all(source.sample(pixels)[:, 0] > 0)


def test_ate_of_the_ground_truth_against_itself_is_zero(seq04):
    truth = rgbl.open_sequence(seq04).ground_truth.poses
    assert len(truth) == 51
    assert rgbl.absolute_trajectory_error(truth, truth).translation.rmse == pytest.approx(0.0, abs=1e-9)
    assert rgbl.trajectory_distances(truth)[-1] == pytest.approx(69, abs=2)  # the excerpt's ~69 m


def test_raw_drive_from_python_with_its_scan_times_is_the_pipelines_run(raw0009):
    """KITTI raw gives each scan's time: passed to System.track, the LiDAR depth moves as in Pipeline.run()."""
    pipeline = rgbl.Pipeline(raw0009)
    system = pipeline.make_system()
    results = []
    for i in range(pipeline.frame_count):
        frame = pipeline.sequence.load(pipeline.frame_index(i))
        assert 0.0166 < frame.timestamp - frame.scan_timestamp < 0.0171
        results.append(system.track(frame.images[0], frame.scan, index=frame.index, timestamp=frame.timestamp,
                                    scan_timestamp=frame.scan_timestamp))
    assert results[-1].scan_age == pytest.approx(frame.timestamp - frame.scan_timestamp)
    from_python = pipeline.collect(system, results)
    assert np.array_equal(from_python.trajectory.poses, pipeline.run().trajectory.poses)
