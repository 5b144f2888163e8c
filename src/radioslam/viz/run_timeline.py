"""A run along its scans (issues #5, #17): each pose's position error after the SE(2) alignment, for the
front end and after PGO (where they differ, which the maps' scale hides), each scan's match score, and
its status as a coloured strip, on one time axis."""

from __future__ import annotations

import numpy as np

from radioslam.eval.trajectory_metrics import pose_errors
from radioslam.slam.status import ScanStatus
from radioslam.viz.fig6 import FRONT_END, PGO
from radioslam.viz.figures import plt, save_figure

COLOURS = {ScanStatus.MATCHED: "#4caf50", ScanStatus.AMBIGUOUS: "#ffb300", ScanStatus.DEGENERATE: "#29b6f6",
           ScanStatus.RELOCALIZED: "#ab47bc", ScanStatus.PREDICTED: "#e53935", ScanStatus.SKIPPED: "#9e9e9e"}


def run_timeline(path, truth: np.ndarray, front_end: np.ndarray, optimized: np.ndarray,
                 statuses: list[ScanStatus], scores: np.ndarray) -> None:
    fig, (error, score, strip) = plt.subplots(3, 1, figsize=(12, 5.2), sharex=True, layout="constrained",
                                              gridspec_kw={"height_ratios": [3, 2, 0.8]})
    k = np.arange(len(truth))
    for poses, colour, label in ((front_end, FRONT_END, "front end"), (optimized, PGO, "with PGO")):
        e = pose_errors(poses, truth) * 100
        error.plot(k, e, ".-", color=colour, lw=1.2, ms=4, label=f"{label} (RMSE {np.sqrt(np.mean(e**2)):.2f} cm)")
    error.set_ylabel("position error (cm)")
    error.set_ylim(bottom=0)
    error.legend(loc="upper left", fontsize=8, frameon=False)
    error.set_title("per pose, after the SE(2) alignment onto the ground truth", fontsize=9, loc="left")
    score.plot(k[: len(scores)], scores, "k.-", lw=0.8, ms=3)
    score.set_ylabel("match score")
    score.set_ylim(0, 1)
    strip.bar(k[: len(statuses)], np.ones(len(statuses)), width=1.0, color=[COLOURS[s] for s in statuses])
    strip.set_yticks([])
    strip.set_xlabel("scan")
    for status, colour in COLOURS.items():
        strip.bar([0], [0], color=colour, label=f"{status.value} ({sum(s is status for s in statuses)})")
    fig.legend(*strip.get_legend_handles_labels(), loc="outside lower center", ncol=6, fontsize=8, frameon=False)
    save_figure(fig, path)
