"""Fixtures: a synthetic street with exact ground truth (rendered once per session) and the real KITTI
excerpt, found as the C++ tests find it ($RGBL_DATA_DIR, else RGBL_DEFAULT_DATA_DIR set by CTest)."""

import os
import pathlib

import pytest

import rgbl


def data_root() -> pathlib.Path:
    env = os.environ.get("RGBL_DATA_DIR", "")
    if env:
        return pathlib.Path(env)
    return pathlib.Path(os.environ.get("RGBL_DEFAULT_DATA_DIR", pathlib.Path(__file__).parents[3] / "shared" / "data"))


def find_data(relative: str) -> pathlib.Path:
    """The path below the data root, or a skip saying why (a failure when RGBL_REQUIRE_DATA=1, as in CI)."""
    path = data_root() / relative
    if path.exists():
        return path
    if os.environ.get("RGBL_REQUIRE_DATA") == "1":
        pytest.fail(f"RGBL_REQUIRE_DATA=1 but {path} does not exist")
    pytest.skip(f"skipped: no data ({path} not found; set RGBL_DATA_DIR)")


@pytest.fixture(scope="session")
def seq04() -> pathlib.Path:
    return find_data("kitti/odometry/sequences/04")


@pytest.fixture(scope="session")
def raw0009() -> pathlib.Path:
    return find_data("kitti/raw/2011_09_26/2011_09_26_drive_0009_sync")


@pytest.fixture(scope="session")
def street(tmp_path_factory) -> rgbl.KittiLayout:
    """24 frames of a curved street at half KITTI resolution, cameras 0-3, LiDAR, exact poses."""
    root = tmp_path_factory.mktemp("street")
    return rgbl.write_synthetic_kitti(root, frames=24, path="curve", seed=1)


@pytest.fixture(scope="session")
def short_street(tmp_path_factory) -> rgbl.KittiLayout:
    """4 frames of the same street, for tests that only read frames."""
    root = tmp_path_factory.mktemp("short_street")
    return rgbl.write_synthetic_kitti(root, frames=4, path="curve", seed=1)


@pytest.fixture
def camera() -> rgbl.PinholeCamera:
    return rgbl.PinholeCamera(fx=100.0, fy=100.0, cx=50.0, cy=30.0, width=101, height=61)
