"""What the SLAM made of each scan (issue #12): one status per scan, recorded in ``slam.json``
and counted in ``metrics.json``."""

from __future__ import annotations

from enum import Enum


class ScanStatus(str, Enum):
    """How a scan's pose was found."""

    MATCHED = "matched"  # the scan matched the local map; one hypothesis clearly won
    AMBIGUOUS = "ambiguous"  # two hypotheses scored within the margin: weighted as such
    RELOCALIZED = "relocalized"  # tracking failed and a global search against every submap found it
    PREDICTED = "predicted"  # nothing matched: the pose is the motion model's (tracking lost)
    SKIPPED = "skipped"  # too few points to match: the pose is the motion model's
    DEGENERATE = "degenerate"  # matched, but a direction nothing fixes keeps the prediction

    @property
    def lost(self) -> bool:
        """The pose rests on the motion model alone, not on the scan."""
        return self is ScanStatus.PREDICTED

    @property
    def fixes_pose(self) -> bool:
        """The scan fixed one pose in every direction: not predicted or skipped (the motion model's),
        not degenerate (a direction nothing fixes) and not ambiguous (rival poses score alike)."""
        return self in (ScanStatus.MATCHED, ScanStatus.RELOCALIZED)
