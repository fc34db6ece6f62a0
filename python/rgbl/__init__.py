"""rgbl: LiDAR-enhanced indirect visual SLAM, from Python.

The C++ library's pipeline with numpy in and out: images are uint8 H x W (grey) or H x W x 3 (BGR),
scans float32 N x 4 (x, y, z, reflectance), depth maps float32 H x W (metres, 0 = none), poses
float64 4 x 4 and trajectories N x 4 x 4. Arrays are shared with C++ without copies where the layout
allows.

    import rgbl
    result = rgbl.Pipeline("sequences/04").run()
    print(result.metrics.evaluation.ate.translation.rmse)
    result.write_outputs("out")   # what `rgbl run --out out` writes

Errors arrive as rgbl.ConfigError (a ValueError: a bad option, `key` names it) and rgbl.ParseError
(an OSError: a missing or malformed file, `file` and `line` say where), both rgbl.Error.
"""

try:
    import numpy  # noqa: F401  (the extension needs it; say so plainly rather than "initialization failed")
except ImportError as error:
    raise ImportError(f"rgbl needs numpy, which this interpreter lacks (Debian: python3-numpy): {error}") from error

from . import _rgbl
from ._rgbl import *  # noqa: F401,F403  (the extension is the API)
from ._rgbl import __version__  # noqa: F401

__all__ = [name for name in dir(_rgbl) if not name.startswith("_")]
