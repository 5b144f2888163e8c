"""File formats: SigMF captures, TUM trajectories, PLY scans, calibration JSON, atomic writes.
(Scene YAML lives in scene.)"""

from radioslam.io.atomic import atomic_path, atomic_write_text
from radioslam.io.calibration_io import read_calibration, write_calibration
from radioslam.io.errors import CalibrationFileError, PlyError, SigMFError, TumError
from radioslam.io.ply import read_scan, write_scan
from radioslam.io.sigmf_io import read_capture, write_capture
from radioslam.io.tum import read_tum, write_tum

__all__ = ["CalibrationFileError", "PlyError", "SigMFError", "TumError", "atomic_path", "atomic_write_text",
           "read_calibration", "read_capture", "read_scan", "read_tum", "write_calibration", "write_capture",
           "write_scan", "write_tum"]
