"""File formats: SigMF captures, TUM trajectories, atomic writes. (Scene YAML lives in scene.)"""

from radioslam.io.atomic import atomic_path, atomic_write_text
from radioslam.io.errors import SigMFError, TumError
from radioslam.io.sigmf_io import read_capture, write_capture
from radioslam.io.tum import read_tum, write_tum

__all__ = ["SigMFError", "TumError", "atomic_path", "atomic_write_text", "read_capture", "read_tum",
           "write_capture", "write_tum"]
