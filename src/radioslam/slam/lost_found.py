"""Lost and found by trial (issue #12, point 3): a scan whose match score drops well below the
recent scans' may have been taken elsewhere (a kidnapped terminal) or may be exploring (half its
points where the map knows nothing). One scan cannot tell the two apart: an exploring scan can
score higher at a wrong place of the mapped room than at its own. So a drop opens a trial
instead of a decision:

1. the suspect scan is searched for in the whole map before it (the loop closer's global search,
   Hess et al. 2016 §V); a place that explains it ``gain`` better than the front end's local map
   does opens the trial, unless the room looks the same from both places (the map around the
   front end's pose, carried to the place found, lands on walls again: a symmetric room, a row of
   aisles);
2. each following scan is carried there by the front end's own relative motion and refined
   against the same map;
3. when ``confirm_scans`` scans in a row are each explained ``gain`` better there than by the
   front end, the trial is confirmed and all of them are relocalized; one that is not ends it.

An exploring walk leaves the wrong place's map behind within a step or two; a kidnapped terminal
keeps matching the place it was carried to.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radioslam.slam.config import LoopClosureConfig
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.loop_closer import LoopCloser, LoopClosure
from radioslam.slam.scan_points import ScanPoints
from radioslam.slam.se2 import between, compose, inverse
from radioslam.slam.status import ScanStatus

TRACKED = (ScanStatus.MATCHED, ScanStatus.AMBIGUOUS, ScanStatus.DEGENERATE)  # their scores set the median


@dataclass
class Trial:
    """A place the suspect scans may have been taken at, followed scan by scan."""

    grid: LikelihoodGrid  # the whole map before the first suspect scan
    keys: list[int]  # the map's scans
    tracked: np.ndarray  # the front end's pose of the latest scan followed
    found: list[LoopClosure] = field(default_factory=list)  # one relocalization per scan followed

    def guess(self, tracked: np.ndarray, estimates: dict[int, np.ndarray]) -> np.ndarray:
        """Where the next scan lies if the trial is right: the latest place plus the front end's step."""
        return compose(LoopCloser.placed_pose(self.found[-1], estimates), between(self.tracked, tracked))


class LostAndFound:
    """Opens, follows and decides trials; ``observe`` once per registered scan."""

    def __init__(self, cfg: LoopClosureConfig):
        self.cfg = cfg
        self.scores: list[float] = []  # the front end's scores of tracked scans
        self.trial: Trial | None = None

    def forget(self) -> None:
        """Drop the open trial (the poses it was followed from have moved)."""
        self.trial = None

    def suspect(self, score: float) -> bool:
        """A score below ``suspect_drop`` times the median of the latest ``suspect_window`` scores
        (once at least half that many are known)."""
        recent = self.scores[-self.cfg.suspect_window:]
        return len(recent) >= self.cfg.suspect_window // 2 and score < self.cfg.suspect_drop * float(np.median(recent))

    def observe(self, k: int, status: ScanStatus, pose: np.ndarray, score: float, points: ScanPoints,
                estimates: dict[int, np.ndarray], loop_closer: LoopCloser) -> list[LoopClosure]:
        """Scan k as the front end placed it; the relocalizations of a confirmed trial (else [])."""
        tracked = status in TRACKED and np.isfinite(score)
        if not tracked:
            self.trial = None
        elif self.trial is not None:
            self._follow(k, pose, score, points, estimates, loop_closer)
        elif self.suspect(score):
            self._open(k, pose, score, points, estimates, loop_closer)
        if tracked:
            self.scores.append(score)
        if self.trial is not None and len(self.trial.found) >= self.cfg.confirm_scans:
            found, self.trial = self.trial.found, None
            return found
        return []

    def _open(self, k, pose, score, points, estimates, loop_closer: LoopCloser) -> None:
        keys = loop_closer.map_keys(k, before=k)
        if not keys:
            return
        grid, normals = loop_closer.whole_map(keys, estimates)
        found = loop_closer.relocalize(k, points, estimates, before=k, whole=(grid, normals))
        if found is None or found.score < (1.0 + self.cfg.relocalize_gain) * score:
            return
        jump = compose(loop_closer.placed_pose(found, estimates), inverse(pose))  # carries F onto the place found
        if loop_closer.looks_alike(jump, pose, keys, grid, estimates):
            return
        self.trial = Trial(grid, keys, pose, [found])

    def _follow(self, k, pose, score, points, estimates, loop_closer: LoopCloser) -> None:
        trial = self.trial
        place, found_score, covariance = loop_closer.follow(trial.grid, points, trial.guess(pose, estimates))
        if found_score < max(self.cfg.relocalize_min_score, (1.0 + self.cfg.relocalize_gain) * score):
            self.trial = None  # the front end explains this scan as well: it was exploring
            return
        trial.found.append(loop_closer.placed(k, place, found_score, covariance, trial.keys, estimates))
        trial.tracked = pose
