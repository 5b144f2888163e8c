"""SLAM on radio point clouds (paper §IV-B): a front end that registers each scan against a local
map whatever the motion (global rotation search from specular normals, branch and bound,
correlative refinement), submaps, loop closure and relocalization, a robust pose graph (GTSAM)
and maps."""

from radioslam.slam.config import SlamConfig, load_slam_config
from radioslam.slam.driver import RadioSlam
from radioslam.slam.errors import SlamError
from radioslam.slam.result import SlamResult
from radioslam.slam.session import ScanUpdate, SlamSession
from radioslam.slam.status import ScanStatus

__all__ = ["RadioSlam", "ScanStatus", "ScanUpdate", "SlamConfig", "SlamError", "SlamResult", "SlamSession",
           "load_slam_config"]
