"""What a SLAM run gives (issue #12): the trajectory with and without the pose graph, each scan's
status, the loop closures, the warnings a user must read, and the time each scan took."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radioslam.slam.loop_closer import LoopClosure
from radioslam.slam.plane_adjustment import PlaneAdjustmentResult
from radioslam.slam.status import ScanStatus


@dataclass
class SlamResult:
    poses: np.ndarray  # (P, 3) with loop closure and pose graph optimization
    odometry: np.ndarray  # (P, 3) front end only
    status: list[ScanStatus]  # how each scan's pose was found
    match_score: np.ndarray  # (P,) normalized front-end score, NaN where not matched
    loops: list[LoopClosure] = field(default_factory=list)  # relocalizations included
    warnings: list[str] = field(default_factory=list)
    seconds_per_scan: np.ndarray = field(default_factory=lambda: np.zeros(0))
    planes: PlaneAdjustmentResult | None = None  # the walls of the last solve (None: not run)
    adjustment_seconds: float = 0.0  # the last solve's time (not in seconds_per_scan)
    # the honest ending (issue #47, slam/ending.py): where the answer came from, the runner-up and its odds
    source: str = "pose graph"
    alternative: np.ndarray | None = None  # (P, 3) the runner-up when its odds are within the stated ones
    alternative_source: str | None = None
    alternative_odds: float = float("inf")  # p(answer) / p(runner-up)
    ambiguous_trajectory: bool = False  # ★ metrics.json: a runner-up within the stated odds
    ending_seconds: float = 0.0  # the comparison's time (not in seconds_per_scan)
    ending_lines: list[str] = field(default_factory=list)  # what the comparison tells a user, a line each
    lost_after: int = 2  # this many consecutive predicted scans are a lost stretch
    dead_reckoned_after: int = 10  # and this many consecutive scans none of which fixed one pose

    def scans_with(self, status: ScanStatus) -> list[int]:
        return [k for k, s in enumerate(self.status) if s is status]

    def status_counts(self) -> dict[str, int]:
        """How many scans have each status (every status named, zeros included)."""
        return {s.value: len(self.scans_with(s)) for s in ScanStatus}

    @property
    def lost_scans(self) -> list[int]:
        """Scans of the stretches of at least ``lost_after`` consecutive scans whose poses rest on
        the motion model alone (one predicted scan between matched ones is a new view, not lost),
        and of at least ``dead_reckoned_after`` consecutive scans of which none fixed one pose in
        every direction (predicted, skipped, degenerate or ambiguous: along a hall whose ends it never
        sees, the position along it is the motion model's for that many steps)."""
        lost = stretches([s.lost for s in self.status], self.lost_after)
        unfixed = stretches([not s.fixes_pose for s in self.status], self.dead_reckoned_after)
        return sorted(set(lost) | set(unfixed))

    @property
    def tracking_lost(self) -> bool:
        """★ ``metrics.json``: the run has lost stretches."""
        return bool(self.lost_scans)

    def summary_lines(self) -> list[str]:
        """What a user must know, one line each: every status other than matched with its scans,
        and last, if tracking was lost, the lost stretches."""
        lines = [f"{len(keys)} scan(s) {status.value}: {scan_ranges(keys)}" for status in ScanStatus
                 if status is not ScanStatus.MATCHED and (keys := self.scans_with(status))]
        lines += self.ending_lines
        if self.tracking_lost:
            lines.append(f"tracking lost: scans {scan_ranges(self.lost_scans)} matched nothing, or for many scans "
                         "in a row none fixed one pose (a direction nothing fixes, rival poses alike), and were "
                         "not relocalized; their poses are the motion model's")
        return lines

    @property
    def loop_closures(self) -> list[LoopClosure]:
        return [lc for lc in self.loops if not lc.relocalization]


def stretches(flags: list[bool], at_least: int) -> list[int]:
    """The indices of the runs of at least ``at_least`` consecutive True flags."""
    padded = np.array([0] + [int(f) for f in flags] + [0])
    runs = np.flatnonzero(np.diff(padded)).reshape(-1, 2)  # (start, end) of each run: 0 on both sides
    return [k for a, b in runs if b - a >= at_least for k in range(a, b)]


def scan_ranges(keys: list[int]) -> str:
    """'3–7, 12, 20–21' for [3, 4, 5, 6, 7, 12, 20, 21]."""
    if not keys:
        return ""
    keys = sorted(keys)
    starts = [keys[0]] + [b for a, b in zip(keys, keys[1:]) if b != a + 1]
    ends = [a for a, b in zip(keys, keys[1:]) if b != a + 1] + [keys[-1]]
    return ", ".join(str(a) if a == b else f"{a}–{b}" for a, b in zip(starts, ends))
