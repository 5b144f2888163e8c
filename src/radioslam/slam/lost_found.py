"""Lost and found by trial (issue #12, point 3): a scan whose match score drops well below the
recent scans' may have been taken elsewhere (a kidnapped terminal) or may be exploring (half its
points where the map knows nothing). One scan cannot tell the two apart: an exploring scan can
score higher at a wrong place of the mapped room than at its own. So a drop opens a trial
instead of a decision:

1. the suspect scan is searched for in the whole map before it (the loop closer's global search,
   Hess et al. 2016 §V); a place that explains it ``gain`` better than the front end's pose does
   (against its local map, and against the whole map) opens the trial, unless the room looks the
   same from both places (the map around the front end's pose, carried to the place found, lands
   on walls again: a symmetric room, a row of aisles);
2. each following scan is searched for within one step of the latest place (every heading, as
   the front end searches its own local map), against the same map with the trial's scans added
   at their places (a front end led astray by them, a wrong turn, does not lead the trial astray);
3. each scan adds its evidence, log(score at the trial's place / score at the front end's pose),
   both against the whole map before the trial with the trial's scans at that hypothesis' poses
   (each hypothesis explains its own scans alike: a fair comparison), a sequential test of the
   two hypotheses (Wald's SPRT): once ``confirm_scans`` scans together are explained as well as
   if each had been ``gain`` better there, the trial is confirmed and all of them are
   relocalized. One scan brings at most that much (one the front end's place contradicts
   outright), so it decides only if the scans after it, followed at its place, do not speak
   against it. Evidence below zero (the front end explains them better together), a place
   scoring below ``relocalize_min_score`` or ``max_trial_scans`` scans undecided end it.

A terminal found elsewhere may be brought back where it was taken (or a stretch of foreign scans
ends and the walk's own resume): for ``alert_scans`` scans after a confirmed trial, each scan is
also searched for within a step of the last pose before the jump, whatever its score (the front
end, searching within a step of the place it jumped to, can match a scan of a room that looks
alike there as well as the rest); a place there explaining it better opens a trial.

An exploring walk leaves the wrong place's map behind within a step or two; a kidnapped terminal
keeps matching the place it was carried to.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radioslam.slam.config import LoopClosureConfig
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.loop_closer import LoopCloser, LoopClosure
from radioslam.slam.refine import fit_score
from radioslam.slam.scan_points import ScanPoints
from radioslam.slam.se2 import between, compose, inverse
from radioslam.slam.status import ScanStatus

TRACKED = (ScanStatus.MATCHED, ScanStatus.AMBIGUOUS, ScanStatus.DEGENERATE)  # their scores set the median
FOLLOWED = TRACKED + (ScanStatus.PREDICTED,)  # a trial opens or goes on at these (the local map failed them)


@dataclass
class Trial:
    """A place the suspect scans may have been taken at, followed scan by scan."""

    keys: list[int]  # the map's scans before the first suspect one
    tracked: np.ndarray  # the front end's pose of the latest scan followed
    found: list[LoopClosure] = field(default_factory=list)  # one relocalization per scan followed
    evidence: float = 0.0  # Σ log(trial's score / front end's score), each term bounded (:func:`evidence`)

    def places(self, estimates: dict[int, np.ndarray]) -> dict[int, np.ndarray]:
        """The latest poses with the trial's scans at the places the trial found them."""
        return {**estimates, **{loop.key: LoopCloser.placed_pose(loop, estimates) for loop in self.found}}

    def guesses(self, tracked: np.ndarray, estimates: dict[int, np.ndarray]) -> np.ndarray:
        """Where the next scan may lie if the trial is right (G, 3): the latest place itself (the
        centre of the search: no step is longer), it plus the front end's step, and it plus the
        trial's own last step."""
        places = [LoopCloser.placed_pose(loop, estimates) for loop in self.found[-2:]]
        guesses = [places[-1], compose(places[-1], between(self.tracked, tracked))]
        if len(places) == 2:
            guesses.append(compose(places[-1], between(places[0], places[1])))
        return np.array(guesses)


def hypothesis_scores(grid: LikelihoodGrid, place: np.ndarray, other_grid: LikelihoodGrid, other: np.ndarray,
                      points: ScanPoints) -> tuple[float, float]:
    """The scan's scores at ``place`` in ``grid`` (the trial's) and at ``other`` in ``other_grid``
    (the front end's): the same map but for the trial's own scans, each at its hypothesis' poses."""
    return fit_score(grid, points.xy, points.normals, place), fit_score(other_grid, points.xy, points.normals, other)


def evidence(found_score: float, score: float, bound: float) -> float:
    """One scan's evidence for a trial: log(trial's score / front end's score) within ±``bound``
    (a score at or below zero, a place the map contradicts, counts as the bound)."""
    if found_score <= 0 or score <= 0:  # the bound against the one at or below zero (both: no evidence)
        return float(bound * (int(found_score > 0) - int(score > 0)))
    return float(np.clip(np.log(found_score) - np.log(score), -bound, bound))


class LostAndFound:
    """Opens, follows and decides trials; ``observe`` once per registered scan. A followed scan is
    searched for within ``max_step_m`` of the trial's latest place."""

    def __init__(self, cfg: LoopClosureConfig, max_step_m: float):
        self.cfg, self.max_step_m = cfg, max_step_m
        self.scores: list[float] = []  # the front end's scores of tracked scans
        self.trial: Trial | None = None
        self.alert = 0  # scans left after a confirmed jump during which each is also searched for where it was taken
        self.taken_from: int | None = None  # the last scan before that jump
        # the scans of each trial that ended undecided: followed for at least confirm_scans scans, with at least
        # one scan's worth of evidence for the other place (log(1 + gain)), but never enough
        self.undecided: list[list[int]] = []

    @property
    def bound(self) -> float:
        """The evidence that confirms a trial, ``confirm_scans`` × log(1 + ``relocalize_gain``): as if each
        scan had been explained that much better. One scan brings at most this much: it may decide,
        but only once the scans after it, followed at its place, do not speak against it."""
        return self.cfg.confirm_scans * float(np.log1p(self.cfg.relocalize_gain))

    @classmethod
    def from_config(cls, cfg) -> "LostAndFound":
        return cls(cfg.loop_closure, cfg.motion.max_step_m)

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
        followed = status in FOLLOWED and np.isfinite(score)
        if not followed:
            self.trial = None
        elif self.trial is not None:
            self._follow(k, pose, score, points, estimates, loop_closer)
        elif self.alert > 0 or self.suspect(score):
            self._open(k, pose, score, points, estimates, loop_closer)
        if followed:
            self.alert = max(0, self.alert - 1)
        if status in TRACKED and np.isfinite(score):
            self.scores.append(score)
        if self.decided():
            found, self.trial = self.trial.found, None
            self.alert, self.taken_from = self.cfg.alert_scans, found[0].key - 1
            return found
        return []

    def decided(self) -> bool:
        """The open trial is confirmed: ``confirm_scans`` scans followed, with evidence ``bound``."""
        return self.trial is not None and len(self.trial.found) >= self.cfg.confirm_scans and \
            self.trial.evidence >= self.bound

    def _open(self, k, pose, score, points, estimates, loop_closer: LoopCloser) -> None:
        """A trial for scan k: first where the terminal was taken (after a jump), then, if its score
        dropped, wherever in the whole map before it it fits best."""
        keys = loop_closer.map_keys(k, before=k)
        if not keys:
            return
        grid, normals = loop_closer.whole_map(keys, estimates)
        if self.alert > 0 and self._open_where_taken(k, pose, points, estimates, loop_closer, keys, grid, normals):
            return
        if not self.suspect(score):
            return
        found = loop_closer.relocalize(k, points, estimates, before=k, whole=(grid, normals))
        if found is None or found.score < (1.0 + self.cfg.relocalize_gain) * score:
            return
        place = loop_closer.placed_pose(found, estimates)
        if loop_closer.looks_alike(compose(place, inverse(pose)), pose, keys, grid, estimates):
            return
        self._start(keys, pose, found, hypothesis_scores(grid, place, grid, pose, points))

    def _open_where_taken(self, k, pose, points, estimates, loop_closer: LoopCloser, keys: list[int],
                          grid: LikelihoodGrid, normals: np.ndarray) -> bool:
        """After a jump, the scan searched for within a step of the last pose before it (a terminal
        carried away is often brought back, foreign scans are followed by the walk's own): a place
        there explaining it ``gain`` better than the front end opens a trial, with no self-similarity
        test (one place is tested, not the whole map's best)."""
        if self.taken_from is None or self.taken_from not in estimates:
            return False
        place, found_score, covariance = loop_closer.follow(grid, normals, points, estimates[self.taken_from][None],
                                                            self.max_step_m)
        if found_score < self.cfg.relocalize_min_score:
            return False
        return self._start(keys, pose, loop_closer.placed(k, place, found_score, covariance, keys, estimates),
                           hypothesis_scores(grid, place, grid, pose, points))

    def _start(self, keys: list[int], pose: np.ndarray, found: LoopClosure, pair: tuple[float, float]) -> bool:
        """A trial opened by ``found`` if the map explains the scan ``relocalize_gain`` better at its
        place than at the front end's pose (``pair``: the two scores)."""
        if pair[0] < (1.0 + self.cfg.relocalize_gain) * pair[1]:
            return False
        self.trial = Trial(keys, pose, [found], evidence(*pair, self.bound))
        return True

    def _follow(self, k, pose, score, points, estimates, loop_closer: LoopCloser) -> None:
        trial = self.trial
        keys = trial.keys + [loop.key for loop in trial.found]
        grid, normals = loop_closer.whole_map(keys, trial.places(estimates))  # the trial's scans at its places
        place, found_score, covariance = loop_closer.follow(grid, normals, points, trial.guesses(pose, estimates),
                                                            self.max_step_m)
        front_grid, _ = loop_closer.whole_map(keys, estimates)  # and at the front end's
        trial.evidence += evidence(*hypothesis_scores(grid, place, front_grid, pose, points), self.bound)
        if found_score < self.cfg.relocalize_min_score or trial.evidence < 0.0 or \
                len(trial.found) >= self.cfg.max_trial_scans:
            # the front end explains the scans as well (it was exploring), or the trial was left undecided
            if len(trial.found) >= self.cfg.confirm_scans and trial.evidence >= self.bound / self.cfg.confirm_scans:
                self.undecided.append([loop.key for loop in trial.found])
            self.trial = None
            return
        trial.found.append(loop_closer.placed(k, place, found_score, covariance, trial.keys, estimates))
        trial.tracked = pose
