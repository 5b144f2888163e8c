"""Scans of any size in bounded memory (issue #15 point 3): a scan is thinned before the SLAM sees it.

A radio scan holds tens to a few hundred points (188 beams, a few echoes each). A recording from
another sensor, or a damaged one, may hold millions, or points kilometres away; every matcher's
cost and every grid's extent grows with them. So, deterministically and without a random draw:
1. points beyond ``max_range_m`` are dropped;
2. above ``max_points``, each grid cell keeps its strongest point (two points in one cell score
   alike against any likelihood field);
3. still above, the ``max_points`` strongest are kept (radio points are peaks: the weak ones are
   sidelobes and diffuse echoes).

The points kept stay in their original order.
"""

from __future__ import annotations

import numpy as np

from radioslam.sensing.pointcloud import Scan


def thin_scan(scan: Scan, max_points: int, max_range_m: float, cell_m: float) -> tuple[Scan, str]:
    """The scan as the SLAM uses it, and a note saying what was left out ("" when nothing was)."""
    keep = np.flatnonzero(scan.range_m <= max_range_m)
    if len(keep) > max_points:
        cells = np.floor(scan.xy[keep] / cell_m).astype(np.int64)
        order = np.lexsort((-scan.power_db[keep], cells[:, 1], cells[:, 0]))  # each cell's strongest first
        first = np.ones(len(order), dtype=bool)
        first[1:] = np.any(np.diff(cells[order], axis=0) != 0, axis=1)
        keep = np.sort(keep[order[first]])
    if len(keep) > max_points:
        keep = np.sort(keep[np.argsort(-scan.power_db[keep], kind="stable")[:max_points]])
    if len(keep) == len(scan):
        return scan, ""
    far = int(np.sum(scan.range_m > max_range_m))
    note = f"{len(scan):,} points thinned to {len(keep):,}" + (f" ({far:,} beyond {max_range_m:g} m)" if far else "")
    return scan.select(keep), note
