"""A strip of the scans' statuses (issue #12): one coloured cell per scan along the run, with the
match score above it, so that where the SLAM was unsure is seen at a glance."""

from __future__ import annotations

import numpy as np

from radioslam.slam.status import ScanStatus
from radioslam.viz.figures import plt, save_figure

COLOURS = {ScanStatus.MATCHED: "#4caf50", ScanStatus.AMBIGUOUS: "#ffb300", ScanStatus.DEGENERATE: "#29b6f6",
           ScanStatus.RELOCALIZED: "#ab47bc", ScanStatus.PREDICTED: "#e53935", ScanStatus.SKIPPED: "#9e9e9e"}


def status_strip(path, statuses: list[ScanStatus], scores: np.ndarray) -> None:
    fig, (top, strip) = plt.subplots(2, 1, figsize=(12, 2.6), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    k = np.arange(len(statuses))
    top.plot(k, scores, "k.-", lw=0.8, ms=3)
    top.set_ylabel("match score")
    top.set_ylim(0, 1)
    strip.bar(k, np.ones(len(k)), width=1.0, color=[COLOURS[s] for s in statuses])
    strip.set_yticks([])
    strip.set_xlabel("scan")
    for status, colour in COLOURS.items():
        strip.bar([0], [0], color=colour, label=f"{status.value} ({sum(s is status for s in statuses)})")
    strip.legend(ncol=6, fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.9), frameon=False)
    save_figure(fig, path)
