"""Fig. 6 of the paper: (a) the reflection energy of the scans, (b) the map without PGO (front end only),
(c) the map with loop closure and PGO. Three equal panels on the same axes; the true walls drawn over the
points in black with a white edge; both trajectories, the start, and in (c) the loop closures' edges;
legends and the colour bar below the data. Estimates are drawn after their SE(2) alignment onto the ground
truth (the map frame is the terminal's at the first pose)."""

from __future__ import annotations

import matplotlib.patheffects as effects
import numpy as np

from radioslam.eval.trajectory_metrics import align
from radioslam.sensing.pointcloud import Scan
from radioslam.slam.se2 import transform_points
from radioslam.viz.figures import plt, save_figure

WALL_STYLE = dict(color="black", lw=1.3, zorder=4,
                  path_effects=[effects.Stroke(linewidth=3.2, foreground="white"), effects.Normal()])
TRUTH, FRONT_END, PGO, LOOPS, POINTS = "0.35", "tab:orange", "tab:blue", "tab:purple", "tab:red"


def _world(poses: np.ndarray, scans: list[Scan]) -> np.ndarray:
    return np.concatenate([transform_points(p, s.xy) for p, s in zip(poses, scans)] + [np.zeros((0, 2))])


def _limits(segments: np.ndarray, truth: np.ndarray, margin: float = 0.8) -> tuple[tuple, tuple]:
    xy = np.concatenate([segments.reshape(-1, 2), truth[:, :2]])
    lo, hi = xy.min(axis=0) - margin, xy.max(axis=0) + margin
    return (lo[0], hi[0]), (lo[1], hi[1])


def fig6_figure(path, segments: np.ndarray, truth: np.ndarray, odometry: np.ndarray, optimized: np.ndarray,
                scans: list[Scan], title: str = "", loop_closures: list[tuple[int, int]] = ()) -> None:
    odometry, _ = align(odometry, truth)
    optimized, _ = align(optimized, truth)
    power = np.concatenate([s.power_db for s in scans] + [np.zeros(0)])
    xlim, ylim = _limits(segments, truth)
    fig, axes = plt.subplots(1, 3, figsize=(16, 6.4), sharex=True, sharey=True, layout="constrained")
    panels = [("(a) reflection energy", truth, None), ("(b) map without PGO (front end)", odometry, FRONT_END),
              ("(c) map with loop closure and PGO", optimized, PGO)]
    for ax, (name, poses, colour) in zip(axes, panels):
        pts = _world(poses, scans)
        if colour is None:
            art = ax.scatter(pts[:, 0], pts[:, 1], c=power, s=4, cmap="viridis", vmin=-25, vmax=0, zorder=2,
                             rasterized=True)
        else:
            ax.scatter(pts[:, 0], pts[:, 1], s=3, color=POINTS, alpha=0.6, zorder=2, rasterized=True,
                       label="map points")
            ax.plot(truth[:, 0], truth[:, 1], "--", color=TRUTH, lw=1.0, zorder=3, label="ground truth")
            ax.plot(poses[:, 0], poses[:, 1], "-", color=colour, lw=1.6, zorder=5,
                    label="front end" if colour == FRONT_END else "with PGO")
        for seg in segments:
            ax.plot(seg[:, 0], seg[:, 1], **WALL_STYLE)
        ax.plot(*truth[0, :2], marker="*", ms=13, color="gold", mec="black", zorder=6, ls="none", label="start")
        ax.set_title(name)
        ax.set_aspect("equal")
        ax.set_xlim(*xlim)
        ax.set_ylim(*ylim)
        ax.set_xlabel("x (m)")
    for k, (anchor, pose) in enumerate(loop_closures):
        a, b = optimized[anchor], optimized[pose]
        axes[2].plot([a[0], b[0]], [a[1], b[1]], "-", color=LOOPS, lw=1.8, zorder=7,
                     label="loop closure" if k == 0 else None)
    axes[0].set_ylabel("y (m)")
    # panel (a)'s colour bar in a strip under all three (the panels stay equal), shrunk to sit under (a)
    fig.colorbar(art, ax=list(axes), location="bottom", shrink=0.3, anchor=(0.0, 1.0), aspect=30, pad=0.01,
                 label="(a): dB re. the scan's peak")
    axes[0].plot([], [], **WALL_STYLE, label="true walls")
    handles = {}
    for ax in axes:
        for handle, label in zip(*ax.get_legend_handles_labels()):
            handles.setdefault(label, handle)
    fig.legend(handles.values(), handles.keys(), loc="outside upper center", ncol=len(handles), frameon=False)
    if title:
        fig.suptitle(title, x=0.01, ha="left", fontweight="bold")
    save_figure(fig, path)
