"""Sensing: IQ or resource grid → T1, T2 → calibrated detections → point cloud (paper §III, §IV-A)."""

from radioslam.sensing.calibration import Calibration, CalibrationTarget, estimate_hardware_delay
from radioslam.sensing.config import CfarKind, Detector, PointFilter, Refinement, SensingConfig, Taper
from radioslam.sensing.errors import SensingError
from radioslam.sensing.pointcloud import Scan
from radioslam.sensing.receiver import Receiver, SensingResult

__all__ = ["Calibration", "CalibrationTarget", "CfarKind", "Detector", "PointFilter", "Receiver", "Refinement", "Scan",
           "SensingConfig", "SensingError", "SensingResult", "Taper", "estimate_hardware_delay"]
