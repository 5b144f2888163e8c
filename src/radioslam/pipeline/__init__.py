"""The stages over a run directory (DESIGN.md §5 ★): simulate → sense → slam → evaluate, and the report.

Each stage reads what the one before wrote, so the command line can run them one by one
(``simulate``, ``sense``, ``slam``, ``evaluate``, ``report``) or all at once (``run``, ``demo``). One
module per stage; this package is the application layer (nothing below it imports it).
"""

from radioslam.pipeline.calibration import calibrate_simulated, calibrated_receiver, simulated_calibration
from radioslam.pipeline.evaluate import evaluate_stage, map_3d_metrics, map_point_cells
from radioslam.pipeline.run import SIMULATED_ODOMETRY, RunOptions, report_stage, run_scene
from radioslam.pipeline.sense import capture_files, sense_stage, sensing_settings, simulate_and_sense
from radioslam.pipeline.simulate import capture_writer, scene_simulator, simulate_stage, write_json
from radioslam.pipeline.slam import read_odometry, read_scans, slam_stage, write_slam_outputs

__all__ = ["SIMULATED_ODOMETRY", "RunOptions", "calibrate_simulated", "calibrated_receiver", "capture_files",
           "capture_writer", "evaluate_stage", "map_3d_metrics", "map_point_cells", "read_odometry",
           "read_scans", "report_stage", "run_scene", "scene_simulator", "sense_stage", "sensing_settings",
           "simulate_and_sense", "simulate_stage", "simulated_calibration", "slam_stage", "write_json",
           "write_slam_outputs"]
