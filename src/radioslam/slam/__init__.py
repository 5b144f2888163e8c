"""SLAM on radio point clouds (paper §IV-B): correlative scan matching with specular normals,
submaps, branch-and-bound loop closure, a robust pose graph (GTSAM) and maps."""

from radioslam.slam.config import SlamConfig
from radioslam.slam.driver import RadioSlam, SlamResult
from radioslam.slam.errors import SlamError

__all__ = ["RadioSlam", "SlamConfig", "SlamError", "SlamResult"]
