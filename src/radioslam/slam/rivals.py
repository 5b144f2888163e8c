"""The walks not taken (issue #47, point 4): every decision the SLAM took on odds short of the ending's keeps
its alternative, and the ending weighs each as a whole trajectory.

A decision places one scan: the front end's choice among turned poses the scan alone cannot tell apart (an
ambiguous scan's turned rivals), its choice of a pose the motion did not expect (taken against the motion
prior's odds beyond the ending's, the scan's own fit at the expected step left), a fork's decision for its
rival (the branch it left), a relocalization (taken at odds above 1 : 1, the front end's own pose left), a
lost-and-found trial's jump (confirmed at the ending's odds, the walk without the jump left); and the decisions
not taken on such odds: a relocalization whose posterior falls short of the front end's pose by less than the
ending's odds, a trial that ends undecided, and a trial not opened because the room looks the same from the
place found (no scan can weigh the two; the place each found left). Each alternative is kept as its step into
that scan from the pose before it; at the walk's end it is the answer's trajectory
with that step replaced and every later pose carried with it (a rigid branch, as in max-mixtures: Olson &
Agarwal, RSS 2012, keep the alternatives and let the whole data weigh them), its step aligned by the scans
after it (:meth:`radioslam.slam.ending.Judge.aligned`). The ending (:mod:`radioslam.slam.ending`) scores each
by its posterior; one within the stated odds of the answer, or better, makes the trajectory ambiguous. A
branch carried rigidly is rescored only where its map changes (:meth:`radioslam.slam.ending.Judge.scan_terms`),
so keeping every alternative costs the scans near each decision, not the walk.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from radioslam.slam.se2 import between, compose, inverse


class Cause(str, Enum):
    """The decision an alternative was left by."""

    TURNED = "a turned pose the scan could not tell apart"
    FORK = "the branch a fork's decision left"
    RELOCALIZATION = "the front end's pose a relocalization replaced"
    JUMP = "the walk without a confirmed jump"
    LOOKALIKE = "a place the room looks the same from, which a score drop's search of the whole map found"
    PLACE_FOUND = "a place the whole map's search found for the scan, not taken at odds within the ending's"
    EXPECTED = "the step the motion expected, where the scan placed itself against the motion's odds"


@dataclass(frozen=True)
class Rival:
    key: int  # the scan placed
    step: np.ndarray  # (3,) the alternative's step into it, in the frame of pose key − 1
    cause: Cause


class Rivals:
    """The alternatives kept, in the order the decisions were taken."""

    def __init__(self):
        self.kept: list[Rival] = []

    def keep(self, key: int, steps: np.ndarray, cause: Cause) -> None:
        """Scan ``key``'s alternative steps (A, 3) into it, each in the frame of pose key − 1."""
        self.kept += [Rival(key, step, cause) for step in np.atleast_2d(steps)]

    def keep_poses(self, key: int, last: np.ndarray, poses: np.ndarray, cause: Cause) -> None:
        """Scan ``key``'s alternative poses (A, 3) (world frame, with pose key − 1 at ``last``)."""
        self.keep(key, between(last, np.atleast_2d(poses)).reshape(-1, 3), cause)

    def branches(self, poses: np.ndarray) -> list[tuple[Rival, np.ndarray]]:
        """Each alternative's trajectory (P, 3): ``poses`` with its step into its scan, every later pose carried
        with it."""
        out = []
        for rival in self.kept:
            jump = compose(compose(poses[rival.key - 1], rival.step), inverse(poses[rival.key]))
            branch = poses.copy()
            branch[rival.key:] = compose(jump, poses[rival.key:])
            out.append((rival, branch))
        return out
