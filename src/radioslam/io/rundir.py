"""The run directory ★ (DESIGN.md §5): file names every stage agrees on."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from radioslam.config import RadioConfig


@dataclass(frozen=True)
class RunDir:
    root: Path

    @property
    def scene(self) -> Path:
        return self.root / "scene.yaml"

    @property
    def ground_truth(self) -> Path:
        return self.root / "ground_truth.tum"

    @property
    def captures(self) -> Path:
        return self.root / "captures"

    @property
    def traces(self) -> Path:
        """A ray tracer's paths per pose (:mod:`radioslam.io.trace_cache`): no run's output, kept when a new
        run replaces the old one (each file is named by what its trace depends on)."""
        return self.root / "traces"

    def capture_base(self, pose_index: int) -> Path:
        """``captures/NNNN`` (add ``.sigmf-meta`` / ``.sigmf-data``)."""
        return self.captures / f"{pose_index:04d}"

    @property
    def odometry(self) -> Path:
        """The simulated drifting odometry (scenes with an ``odometry:`` block)."""
        return self.root / "odometry.tum"

    @property
    def calibration(self) -> Path:
        return self.root / "calibration.json"

    @property
    def scans(self) -> Path:
        return self.root / "scans"

    @property
    def trajectory(self) -> Path:
        return self.root / "trajectory.tum"

    @property
    def trajectory_odometry(self) -> Path:
        return self.root / "trajectory_odometry.tum"

    @property
    def trajectory_alternative(self) -> Path:
        """The runner-up trajectory, when its odds are within the stated ones (``ambiguous_trajectory``)."""
        return self.root / "trajectory_alternative.tum"

    @property
    def trajectory_scene(self) -> Path:
        """The SLAM trajectory in the scene's frame (slam --scene-frame, a simulated run's)."""
        return self.root / "trajectory_scene.tum"

    @property
    def map_yaml(self) -> Path:
        return self.root / "map.yaml"

    @property
    def map_cloud(self) -> Path:
        return self.root / "map.ply"

    @property
    def slam_summary(self) -> Path:
        return self.root / "slam.json"

    @property
    def metrics(self) -> Path:
        return self.root / "metrics.json"

    @property
    def report(self) -> Path:
        return self.root / "report.html"

    def relative(self, path: Path) -> str:
        """``path`` (in the run directory) relative to it, as run.json names files."""
        return Path(path).relative_to(self.root).as_posix()

    def terminal_height_m(self) -> tuple[float, str]:
        """The terminal's height above the floor (what lifts a scan's z to the map's) and where it came
        from: the run's scene.yaml (``radio.height_m``), else the radio's default."""
        try:
            height = yaml.safe_load(self.scene.read_text(encoding="utf-8"))["radio"]["height_m"]
            if isinstance(height, (int, float)) and np.isfinite(height) and height > 0:
                return float(height), "scene.yaml radio.height_m"
        except (OSError, yaml.YAMLError, KeyError, TypeError):
            pass
        return RadioConfig().height_m, "the radio's default (no scene.yaml with radio.height_m)"

    def scan_file(self, pose_index: int) -> Path:
        return self.scans / f"{pose_index:04d}.ply"

    def heatmap_file(self, pose_index: int) -> Path:
        """scans/NNNN.png: a pose's radar heatmap and point cloud (the sense stage's figure)."""
        return self.scans / f"{pose_index:04d}.png"

    @staticmethod
    def pose_timestamps(count: int) -> np.ndarray:
        """Poses are stamped 1 s apart, t = index."""
        return np.arange(count, dtype=np.float64)
