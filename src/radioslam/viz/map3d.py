"""The 3D map of a run with elevation beams (issue #16): map.ply's points in 3D, coloured by height, with
the trajectory; and their heights against the true horizontal surfaces (floor, furniture tops, ceiling)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from radioslam.viz.figures import save_figure  # noqa: E402

MAX_DRAWN = 40_000  # points drawn in the 3D panel (every k-th beyond that): a readable, light figure


def map_3d_figure(path: str | Path, points: np.ndarray, trajectory: np.ndarray, terminal_height_m: float,
                  surface_heights_m: np.ndarray, title: str = "") -> None:
    """(a) points (P, 3) of the fused map, world frame, z above the floor, and the SLAM trajectory (N, 3) at
    the terminal's height; (b) the histogram of the points' heights with the true surfaces' heights."""
    fig = plt.figure(figsize=(12, 5.2), layout="constrained")
    ax = fig.add_subplot(1, 2, 1, projection="3d")
    shown = points[:: max(1, len(points) // MAX_DRAWN)]
    cloud = ax.scatter(shown[:, 0], shown[:, 1], shown[:, 2], c=shown[:, 2], s=1.5, cmap="viridis",
                       depthshade=False)
    ax.plot(trajectory[:, 0], trajectory[:, 1], np.full(len(trajectory), terminal_height_m), color="crimson",
            lw=1.5, label="SLAM trajectory")
    ax.set_xlabel("x (m)"), ax.set_ylabel("y (m)"), ax.set_zlabel("z (m)")
    ax.set_title("(a) radio point cloud map, 3D")
    ax.legend(loc="upper left", fontsize=8)
    fig.colorbar(cloud, ax=ax, shrink=0.6, label="height above the floor (m)")
    hist = fig.add_subplot(1, 2, 2)
    hist.hist(points[:, 2], bins=np.arange(np.floor(points[:, 2].min() * 10) / 10, points[:, 2].max() + 0.1, 0.05),
              color="steelblue", orientation="horizontal")
    for z in surface_heights_m:
        hist.axhline(z, color="crimson", lw=1, ls="--")
    hist.axhline(terminal_height_m, color="black", lw=1, ls=":", label=f"terminal ({terminal_height_m:g} m)")
    hist.plot([], [], color="crimson", ls="--", label="true horizontal surfaces")
    hist.set_xlabel("points"), hist.set_ylabel("height above the floor (m)")
    hist.set_title("(b) point heights")
    hist.legend(loc="lower right", fontsize=8)
    if title:
        fig.suptitle(title)
    save_figure(fig, path)
