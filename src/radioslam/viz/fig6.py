"""Fig. 6 of the paper: (a) the reflection energy of the scans, (b) the map without PGO
(front end only), (c) the map with loop closure and PGO; true walls and both trajectories
overlaid. Estimates are drawn after their SE(2) alignment onto the ground truth."""

from __future__ import annotations

import numpy as np

from radioslam.eval.trajectory_metrics import align
from radioslam.sensing.pointcloud import Scan
from radioslam.slam.se2 import transform_points
from radioslam.viz.figures import plt, save_figure


def _world(poses: np.ndarray, scans: list[Scan]) -> np.ndarray:
    return np.concatenate([transform_points(p, s.xy) for p, s in zip(poses, scans)] + [np.zeros((0, 2))])


def fig6_figure(path, segments: np.ndarray, truth: np.ndarray, odometry: np.ndarray, optimized: np.ndarray,
                scans: list[Scan], title: str = "") -> None:
    odometry, _ = align(odometry, truth)
    optimized, _ = align(optimized, truth)
    power = np.concatenate([s.power_db for s in scans] + [np.zeros(0)])
    fig, axes = plt.subplots(1, 3, figsize=(16, 5.6))
    panels = [("(a) reflection energy (dB re. scan peak)", truth, True),
              ("(b) map without PGO", odometry, False), ("(c) map with PGO", optimized, False)]
    for ax, (name, poses, energy) in zip(axes, panels):
        for seg in segments:
            ax.plot(seg[:, 0], seg[:, 1], color="0.2", lw=1.2, zorder=1)
        pts = _world(poses, scans)
        if energy:
            art = ax.scatter(pts[:, 0], pts[:, 1], c=power, s=4, cmap="viridis", zorder=2)
            fig.colorbar(art, ax=ax, shrink=0.8)
        else:
            ax.scatter(pts[:, 0], pts[:, 1], s=3, color="tab:red", zorder=2, label="map points")
            ax.plot(truth[:, 0], truth[:, 1], "k--", lw=1, label="ground truth")
            ax.plot(poses[:, 0], poses[:, 1], "-", color="tab:blue", lw=1.2,
                    label="front end" if poses is odometry else "with PGO")
            ax.legend(loc="upper right", fontsize=7)
        ax.set_title(name)
        ax.set_aspect("equal")
        ax.set_xlabel("x (m)")
    axes[0].set_ylabel("y (m)")
    if title:
        fig.suptitle(title)
    save_figure(fig, path)
