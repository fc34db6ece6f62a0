"""Type stubs of rgbl (the extension rgbl._rgbl re-exported). Shapes are noted as comments."""

import enum
import os
from typing import Callable, List, Optional, Sequence as _Seq, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

_Path = Union[str, os.PathLike[str]]
_Array = npt.ArrayLike
_F32 = npt.NDArray[np.float32]
_F64 = npt.NDArray[np.float64]
_U8 = npt.NDArray[np.uint8]

# --- errors -------------------------------------------------------------------------------------------

class Error(RuntimeError):
    """Base of the errors rgbl raises at its IO and configuration edges."""

class ConfigError(Error, ValueError):
    """An option or settings key with a value that cannot work."""
    key: str

class ParseError(Error, OSError):
    """A file that is missing, unreadable or not in the expected format."""
    file: str
    line: int

# --- geometry -----------------------------------------------------------------------------------------

class PinholeCamera:
    fx: float
    fy: float
    cx: float
    cy: float
    width: int
    height: int
    distortion: tuple[float, float, float, float, float]  # k1, k2, p1, p2, k3
    def __init__(self, fx: float, fy: float, cx: float, cy: float, width: int, height: int) -> None: ...
    @property
    def K(self) -> _F64: ...  # 3 x 3
    def project(self, points: _Array) -> _F64:
        """Pixels of points (3 or N x 3): N x 2 (or 2), NaN where not visible."""
    def unproject(self, pixel: tuple[float, float], z: float) -> tuple[float, float, float]: ...

class CameraCalibration:
    camera: PinholeCamera
    T_cam_cam0: _F64  # 4 x 4
    T_cam_lidar: _F64  # 4 x 4
    def __init__(self, camera: PinholeCamera, T_cam_cam0: Optional[_Array] = None,
                 T_cam_lidar: Optional[_Array] = None) -> None: ...
    @property
    def P_img_lidar(self) -> _F64: ...  # 3 x 4

class KittiCalibration:
    @property
    def P(self) -> list[_F64]: ...  # four 3 x 4
    @property
    def T_cam0_lidar(self) -> _F64: ...
    @property
    def width(self) -> list[int]: ...
    @property
    def height(self) -> list[int]: ...
    def camera(self, index: int) -> CameraCalibration: ...
    def baseline(self, a: int, b: int) -> float: ...

def read_kitti_calibration(calib_txt: _Path, width: int = 0, height: int = 0) -> KittiCalibration: ...
def project_to_depth(scan: _Array, calibration: Union[CameraCalibration, _Array], width: int = ..., height: int = ...,
                     min_depth: float = 5.0, max_depth: float = 200.0) -> _F32:
    """Sparse depth (H x W) of a float32 N x 4 scan: z-buffered, nearest point wins. Pass a
    CameraCalibration, or a 3 x 4 P_img_lidar with width and height."""

# --- io -----------------------------------------------------------------------------------------------

class Trajectory:
    def __init__(self, poses: _Array, timestamps: Optional[_Array] = None) -> None: ...
    @property
    def poses(self) -> _F64: ...  # N x 4 x 4, shares the object's memory
    @property
    def timestamps(self) -> _F64: ...  # N (or empty)
    def __len__(self) -> int: ...

def read_kitti_trajectory(file: _Path) -> _F64: ...  # N x 4 x 4
def write_kitti_trajectory(file: _Path, poses: _Array) -> None: ...
def read_tum_trajectory(file: _Path) -> Trajectory: ...
def write_tum_trajectory(file: _Path, trajectory: Trajectory) -> None: ...
def read_kitti_scan(file: _Path) -> _F32: ...  # N x 4

class DatasetFormat(enum.Enum):
    automatic = 0
    kitti = 1
    kitti_raw = 2
    tum = 3

class SensorSet:
    @property
    def cameras(self) -> list[bool]: ...
    @property
    def lidar(self) -> bool: ...
    @property
    def depth(self) -> bool: ...

class Frame:
    """One loaded frame; its arrays share the frame's memory."""
    @property
    def index(self) -> int: ...
    @property
    def timestamp(self) -> float: ...
    @property
    def scan_timestamp(self) -> Optional[float]: ...
    @property
    def images(self) -> list[Optional[_U8]]: ...  # 0/1 grey H x W, 2/3 BGR H x W x 3
    @property
    def scan(self) -> _F32: ...  # N x 4
    @property
    def depth(self) -> Optional[_F32]: ...  # H x W
    @property
    def T_world_cam0(self) -> Optional[_F64]: ...  # 4 x 4

class Sequence:
    @property
    def format(self) -> DatasetFormat: ...
    @property
    def name(self) -> str: ...
    @property
    def path(self) -> os.PathLike[str]: ...
    @property
    def sensors(self) -> SensorSet: ...
    @property
    def calibration(self) -> KittiCalibration: ...
    @property
    def notes(self) -> list[str]: ...
    @property
    def ground_truth(self) -> Optional[Trajectory]: ...
    def __len__(self) -> int: ...
    def timestamp(self, index: int) -> float: ...
    def load(self, index: int, cameras: Optional[_Seq[bool]] = None, lidar: bool = True, depth: bool = True) -> Frame: ...

def check_sequence(sequence: Sequence) -> List[Tuple[int, str]]:
    """A (frame, message) per file that does not load, one sensor at a time; empty when all load."""

def describe_sequence(sequence: Sequence) -> str:
    """What `rgbl info` prints: layout, frames, cameras, LiDAR, depth camera, ground truth, notes."""

def open_sequence(path: _Path, format: str = "auto", cameras: Optional[_Seq[bool]] = None, lidar: bool = True,
                  depth: bool = True) -> Sequence:
    """KITTI odometry sequences/NN, a KITTI raw drive or a TUM RGB-D folder ('auto', 'kitti', 'kitti-raw', 'tum')."""

# --- depth --------------------------------------------------------------------------------------------

def dilate_depth(sparse: _Array, kernel: str = "diamond", size: int = 5, max_depth: float = 200.0) -> _F32:
    """Inverse dilation; kernel 'diamond', 'rectangle' or 'cross' of odd size."""
def ip_basic(sparse: _Array, mode: str = "fast", max_depth: float = 100.0, extrapolate: bool = False,
             blur: str = "bilateral") -> _F32: ...
def remove_occluded_samples(sparse: _Array, radius: int, ratio: float = 1.25) -> _F32:
    """A copy without the samples with one nearer by more than `ratio` within `radius` px."""
def occlusion_radius_px(fx: float, window_deg: float = 0.3) -> int: ...
def depth_density(depth: _Array) -> float: ...

class DepthSourceNeeds:
    @property
    def scan(self) -> bool: ...
    @property
    def right_image(self) -> bool: ...
    @property
    def depth_image(self) -> bool: ...

def depth_source_names() -> list[str]: ...
def depth_source_usage() -> str: ...
def depth_source_needs(spec: str) -> DepthSourceNeeds: ...

class DepthSource:
    @property
    def name(self) -> str: ...
    def prepare(self, image: _Array, scan: Optional[_Array] = None, image_right: Optional[_Array] = None,
                depth_image: Optional[_Array] = None, index: int = 0, timestamp: float = 0.0) -> None: ...
    def sample(self, pixels: _Array) -> _F32:
        """N x 4: (z, distance in px to the measurement, spread, gradient in m/px, 0 = unknown); z = 0: no depth."""
    def dense_depth(self) -> _F32: ...

def make_depth_source(spec: str, calibration: CameraCalibration, stereo_baseline: float = 0.0) -> DepthSource: ...
def make_lidar_source(calibration: CameraCalibration, surface_fit_window_deg: float = 0.5,
                      occlusion_window_deg: float = 0.3, surface_tolerance: float = 0.05) -> DepthSource: ...
def read_depth_png(file: _Path) -> _F32: ...
def write_depth_png(file: _Path, depth: _Array) -> None: ...

class DepthErrors:
    count: int
    coverage: float
    mae: float
    rmse: float
    imae: float
    irmse: float

def evaluate_depth(prediction: _Array, ground_truth: _Array) -> DepthErrors: ...

class DepthErrorAccumulator:
    def __init__(self) -> None: ...
    def add(self, prediction: _Array, ground_truth: _Array) -> None: ...
    def result(self) -> DepthErrors: ...

# --- features -----------------------------------------------------------------------------------------

class OrbOptions:
    num_features: int
    num_levels: int
    scale_factor: float
    fast_threshold: int
    fast_min_threshold: int
    cell_size: int
    features_per_node: int
    spread_fraction: float
    edge_threshold: int
    patch_size: int
    orientation_radius: int
    blur_size: int
    blur_sigma: float
    def __init__(self) -> None: ...
    def validate(self) -> None: ...

class OrbExtractor:
    def __init__(self, options: Optional[OrbOptions] = None) -> None: ...
    @property
    def options(self) -> OrbOptions: ...
    def extract(self, image: _Array) -> tuple[np.ndarray, _U8]:
        """(keypoints: structured x, y, angle, response, size, level; descriptors: N x 32 uint8)."""

def hamming_distance(a: _Array, b: _Array) -> int: ...

# --- metrics ------------------------------------------------------------------------------------------

class ErrorStats:
    rmse: float
    mean: float
    median: float
    max: float

class AteResult:
    translation: ErrorStats
    @property
    def T_gt_est(self) -> _F64: ...
    @property
    def errors(self) -> _F64: ...

class RpeResult:
    translation: ErrorStats
    rotation_deg: ErrorStats
    @property
    def translation_errors(self) -> _F64: ...
    @property
    def rotation_errors_deg(self) -> _F64: ...

class DriftResult:
    path_length: float
    end_error: float
    percent: float

class KittiMetricOptions:
    lengths: list[float]
    step_size: int
    def __init__(self) -> None: ...

class KittiLengthError:
    length: float
    segments: int
    t_err_percent: float
    r_err_deg_per_100m: float

class KittiMetric:
    segments: int
    t_err_percent: float
    r_err_deg_per_100m: float
    per_length: list[KittiLengthError]

class TrajectoryEvaluation:
    poses: int
    path_length: float  # m, ground truth
    estimated_path_length: float  # m, the estimate's own
    kitti_options: KittiMetricOptions
    kitti: KittiMetric
    ate: AteResult
    rpe: RpeResult
    drift: DriftResult

def absolute_trajectory_error(estimate: _Array, ground_truth: _Array, align: bool = True) -> AteResult: ...
def relative_pose_error(estimate: _Array, ground_truth: _Array, delta: int = 1) -> RpeResult: ...
def end_point_drift(estimate: _Array, ground_truth: _Array) -> DriftResult: ...
def kitti_metric(estimate: _Array, ground_truth: _Array, lengths: Optional[_Seq[float]] = None,
                 step_size: int = 10) -> KittiMetric: ...
def evaluate_trajectory(estimate: _Array, ground_truth: _Array) -> TrajectoryEvaluation: ...
def trajectory_distances(poses: _Array) -> _F64: ...

# --- tracking -----------------------------------------------------------------------------------------

class TrackState(enum.Enum):
    NotInitialised = 0
    Ok = 1
    Weak = 2
    Lost = 3

class StageTiming:
    depth_ms: float
    extraction_ms: float
    tracking_ms: float
    mapping_ms: float
    loop_ms: float
    front_ms: float
    total_ms: float

class LoopClosure:
    frame_index: int
    matched_frame_index: int
    merged: bool
    bridged: bool
    place_source: str
    place_similarity: float
    inliers: int
    correction_m: float
    correction_deg: float

class TrackResult:
    frame_index: int
    timestamp: float
    state: TrackState
    keyframe: bool
    relocalised: bool
    new_map: bool
    jump: bool
    step_rejected: bool
    step_registered: bool  # a rejected step's frame placed by its scan's registration onto the last frame's
    step_contested: bool  # a step refused although clearly more inliers agreed with it than with the pose kept (weak)
    start_refuted_since: Optional[int]  # a start given up here: the first frame placed on it (Tracking.StartDoubt)
    speed_corrected: bool  # the speed had slid faster than a car brakes; placed by the speed before it (Tracking.SpeedWindow)
    start_by_rays: bool  # a start chosen by the keypoints without depth against the road and the inliers (Tracking.StartByRays)
    scan_confirmed: bool  # a suspect pose kept, not lost, where its scan registers (Tracking.ConfirmSuspectByScan)
    gap: bool  # the first frame after a gap in the timestamps, its scan registered onto the last one's
    gap_registered: bool  # ...and the registration was accepted as the prediction
    lost_registered: bool  # a lost frame placed by its scan's registration onto the last frame's
    inliers: int
    keypoints: int
    keypoints_with_depth: int
    scan_age: float
    map_keyframes: int
    map_landmarks: int
    loop_closure: Optional[LoopClosure]
    timing: StageTiming
    @property
    def T_world_cam(self) -> _F64: ...  # 4 x 4

class SystemTrajectory:
    frame_indices: list[int]
    states: list[TrackState]
    @property
    def timestamps(self) -> _F64: ...
    @property
    def poses(self) -> _F64: ...  # N x 4 x 4
    def __len__(self) -> int: ...

class System:
    def __init__(self, calibration: CameraCalibration, depth: str = "lidar", orb: Optional[OrbOptions] = None,
                 threaded: bool = False, loop_closing: bool = True, stereo_baseline: float = 0.0) -> None: ...
    def track(self, image: _Array, scan: Optional[_Array] = None, *, index: Optional[int] = None,
              timestamp: Optional[float] = None, image_right: Optional[_Array] = None,
              depth_image: Optional[_Array] = None, scan_timestamp: Optional[float] = None) -> TrackResult:
        """Tracks one frame (arrays read in place, the GIL released while C++ runs)."""
    def finish(self) -> None: ...
    def trajectory(self) -> SystemTrajectory: ...
    @property
    def calibration(self) -> CameraCalibration: ...
    @property
    def loop_closing(self) -> bool: ...
    def loop_closures(self) -> list[LoopClosure]: ...
    @property
    def keyframe_count(self) -> int: ...
    @property
    def landmark_count(self) -> int: ...
    @property
    def frames_tracked(self) -> int: ...

# --- pipeline -----------------------------------------------------------------------------------------

class PipelineOptions:
    dataset: os.PathLike[str]
    format: DatasetFormat
    camera: int
    first: int
    frames: int
    step: int
    depth: str
    settings: os.PathLike[str]
    threaded: bool
    threads: int
    playback_rate: float
    loop_closing: bool
    def __init__(self) -> None: ...

class FrameRecord:
    result: TrackResult
    io_wait_ms: float

class StageStats:
    median: float
    p95: float
    mean: float
    max: float

class RunTimings:
    io_wait: StageStats
    depth: StageStats
    extraction: StageStats
    tracking: StageStats
    mapping: StageStats
    loop: StageStats
    front: StageStats
    total: StageStats

class RunMetrics:
    frames_with_ground_truth: int
    frames_tracked: int
    evaluation: TrajectoryEvaluation
    tracked_ate: Optional[AteResult]
    kitti_lengths: str

class RunResult:
    sequence_name: str
    sequence_path: os.PathLike[str]
    format: DatasetFormat
    camera: int
    depth: str
    first: int
    step: int
    threaded: bool
    threads: int
    playback_rate: float
    loop_closing: bool
    frames: list[FrameRecord]
    loop_closures: list[LoopClosure]
    wall_s: float
    metrics: Optional[RunMetrics]
    @property
    def trajectory(self) -> Trajectory: ...
    @property
    def ground_truth(self) -> _F64: ...  # N x 4 x 4
    @property
    def landmarks(self) -> _F64: ...  # N x 3
    @property
    def keyframes(self) -> _F64: ...  # N x 4 x 4
    frames_planned: int
    stopped: bool
    def count(self, state: TrackState) -> int: ...
    def tracked_count(self) -> int: ...
    def failed(self) -> bool: ...
    def keyframe_count(self) -> int: ...
    def timings(self) -> RunTimings: ...
    def summary_json(self) -> str: ...
    def summary_text(self) -> str:
        """The run in a few lines, as `rgbl run` prints it (also str(result))."""
    def write_outputs(self, out_dir: _Path) -> None: ...

def write_run_outputs(result: RunResult, out_dir: _Path) -> None: ...
def run_output_files() -> list[str]: ...

class Pipeline:
    """What `rgbl run` does: Pipeline(dataset, ...).run(progress) -> RunResult."""
    def __init__(self, dataset: Union[_Path, PipelineOptions], *, format: str = "auto", camera: int = -1,
                 first: int = 0, frames: int = 0, step: int = 1, depth: str = "lidar",
                 settings: Optional[_Path] = None, threaded: bool = False, loop_closing: bool = True,
                 threads: int = 0, playback_rate: float = 0.0) -> None: ...
    @property
    def options(self) -> PipelineOptions: ...
    @property
    def sequence(self) -> Sequence: ...
    @property
    def camera(self) -> int: ...
    @property
    def calibration(self) -> CameraCalibration: ...
    @property
    def depth_name(self) -> str: ...
    @property
    def frame_count(self) -> int: ...
    def frame_index(self, i: int) -> int: ...
    @property
    def orb_options(self) -> OrbOptions: ...
    @property
    def notes(self) -> list[str]: ...
    def make_system(self) -> System: ...
    def run(self, progress: Optional[Callable[[FrameRecord, int, int], object]] = None) -> RunResult: ...
    def collect(self, system: System, results: list[TrackResult], wall_s: float = 0.0) -> RunResult: ...

# --- simulator ----------------------------------------------------------------------------------------

class KittiLayout:
    @property
    def root(self) -> os.PathLike[str]: ...
    @property
    def sequence_dir(self) -> os.PathLike[str]: ...
    @property
    def poses_file(self) -> os.PathLike[str]: ...

def write_synthetic_kitti(root: _Path, *, frames: int = 20, seed: int = 1, path: str = "straight", width: int = 613,
                          height: int = 185, scenario: str = "", sequence: int = 0, laps: int = 1) -> KittiLayout: ...
