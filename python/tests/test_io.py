"""Sequences and frames: numpy views of the loaded data."""

import shutil

import numpy as np
import pytest

import rgbl


def test_synthetic_sequence_frames(short_street):
    seq = rgbl.open_sequence(short_street.sequence_dir)
    assert len(seq) == 4 and seq.format == rgbl.DatasetFormat.kitti
    assert seq.sensors.cameras == [True, True, True, True] and seq.sensors.lidar
    frame = seq.load(3)
    assert frame.index == 3 and frame.timestamp == pytest.approx(0.3)
    grey, colour = frame.images[0], frame.images[2]
    assert grey.shape == (185, 613) and grey.dtype == np.uint8
    assert colour.shape == (185, 613, 3)
    scan = frame.scan
    assert scan.dtype == np.float32 and scan.shape[1] == 4 and len(scan) > 10000
    # views of the frame's own buffers: no copy, and the frame stays alive through them
    for array in (grey, colour, scan):
        assert not array.flags.owndata and array.base is frame
    assert np.shares_memory(frame.images[0], grey)
    del frame
    assert grey.sum() > 0  # still valid
    # exact ground truth: KITTI's convention, the first pose is the identity
    assert np.allclose(seq.ground_truth.poses[0], np.eye(4))
    assert np.array_equal(seq.load(3).T_world_cam0, seq.ground_truth.poses[3])


def test_load_only_what_is_asked(short_street):
    seq = rgbl.open_sequence(short_street.sequence_dir)
    frame = seq.load(0, cameras=[False, False, False, False], lidar=True)
    assert frame.images == [None, None, None, None] and len(frame.scan) > 0
    with pytest.raises(IndexError):
        seq.load(4)


def test_scan_file_is_viewed_as_n_by_4(short_street):
    scan = rgbl.read_kitti_scan(short_street.sequence_dir / "velodyne" / "000000.bin")
    raw = np.fromfile(short_street.sequence_dir / "velodyne" / "000000.bin", np.float32).reshape(-1, 4)
    assert np.array_equal(scan, raw)
    assert not scan.flags.owndata


def test_check_sequence_lists_every_file_that_does_not_load(short_street, tmp_path):
    assert rgbl.check_sequence(rgbl.open_sequence(short_street.sequence_dir)) == []
    copy = tmp_path / "sequences" / "00"
    shutil.copytree(short_street.sequence_dir, copy)
    (copy / "image_0" / "000001.png").write_bytes(b"not a PNG")
    (copy / "velodyne" / "000002.bin").write_bytes(b"twenty bytes of junk")
    problems = rgbl.check_sequence(rgbl.open_sequence(copy))
    assert [frame for frame, _ in problems] == [1, 2]
    assert "image_0/000001.png" in problems[0][1] and "velodyne/000002.bin" in problems[1][1]


def test_describe_sequence_says_what_the_loader_sees(short_street):
    sequence = rgbl.open_sequence(short_street.sequence_dir)
    text = rgbl.describe_sequence(sequence)
    assert f"frames:        {len(sequence)} over" in text
    assert "camera 0:      grey left" in text and "lidar:         " in text and "ground truth:  " in text


def test_synthetic_street_options_are_checked_by_name(tmp_path):
    with pytest.raises(rgbl.ConfigError, match="'path'"):
        rgbl.write_synthetic_kitti(tmp_path / "a", path="spiral")
    with pytest.raises(rgbl.ConfigError, match="'laps'"):
        rgbl.write_synthetic_kitti(tmp_path / "b", path="curve", laps=2)
    with pytest.raises(rgbl.ConfigError, match="'scenario'"):
        rgbl.write_synthetic_kitti(tmp_path / "c", scenario="nope")
