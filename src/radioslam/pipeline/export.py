"""``radioslam export DIR --mcap FILE`` (issue #17): a finished run as a ROS 2 bag (:mod:`radioslam.io.mcap_bag`)."""

from __future__ import annotations

from pathlib import Path

from radioslam.io.mcap_bag import BagContents, OccupancyImage, write_mcap
from radioslam.io.ros_map import read_ros_map
from radioslam.io.rundir import RunDir
from radioslam.io.slam_summary import read_slam_summary
from radioslam.io.tum import read_tum
from radioslam.pipeline.slam import read_scans


def export_mcap(out: Path, path: Path) -> dict[str, int]:
    """The run in ``out`` (after its slam stage) written to ``path``; the number of messages per topic."""
    run = RunDir(out)
    stamps, slam = read_tum(run.trajectory)
    _, front_end = read_tum(run.trajectory_odometry)
    truth = read_tum(run.ground_truth)[1] if run.ground_truth.exists() else None
    cells, meta = read_ros_map(run.map_yaml)
    summary = read_slam_summary(run.slam_summary)
    loops = [(int(lc["anchor"]), int(lc["pose"])) for lc in summary.get("loop_closures", [])]
    bag = BagContents(stamps, read_scans(run), slam, front_end,
                      OccupancyImage(cells, float(meta["resolution"]), tuple(meta["origin"][:2])), loops,
                      truth if truth is not None and len(truth) == len(slam) else None)
    return write_mcap(path, bag)
