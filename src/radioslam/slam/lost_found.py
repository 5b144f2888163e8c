"""Lost and found by trial (issues #12, #47): a scan whose match score drops well below the recent scans'
may have been taken elsewhere (a kidnapped terminal) or may be exploring (half its points where the map
knows nothing). One scan cannot tell the two apart, so a drop opens a trial, a second hypothesis followed
scan by scan and weighed by its posterior odds (:mod:`radioslam.slam.posterior`):

1. the suspect scan is searched for in the whole map before it (the loop closer's global search,
   Hess et al. 2016 §V); a place that explains it better than the front end's pose opens the trial,
   which starts with the jump's prior odds against it: the motion prior holds a jump to its unexpected
   share spread over the area searched (with odometry, one the odometry does not show costs tens of
   nats), and the scans must pay for it. Unless the room looks the same from both places (the map
   around the front end's pose, carried to the place found, lands on walls again: a symmetric room, a
   row of aisles: the place found is then kept as an alternative for the ending, :mod:`radioslam.slam.rivals`);
2. each following scan is searched for within one step of the latest place (every heading, as the front
   end searches its own local map), against the same map with the trial's scans added at their places (a
   front end led astray by them, a wrong turn, does not lead the trial astray);
3. each scan adds its log odds: its posterior at the trial's place (the trial's scans at the trial's
   places, the trial's own last step as its motion) less its posterior at the front end's pose (the same
   scans at the front end's poses, the walk's motion): each hypothesis explains its own scans alike, a
   fair comparison; the sum is the log posterior odds of the two trajectories since the drop, a sequential
   test (Wald's SPRT). Once ``confirm_scans`` scans are followed and the odds reach the ending's 1 : ``odds``,
   the trial is confirmed and all of them are relocalized (the walk without the jump kept as a rival,
   :mod:`radioslam.slam.rivals`). The scans' own evidence below evens (the front
   end explains them better together, before any jump), a place scoring below ``relocalize_min_score`` or
   ``max_trial_scans`` scans undecided end it.

A terminal found elsewhere may be brought back where it was taken (or a stretch of foreign scans
ends and the walk's own resume): for ``alert_scans`` scans after a confirmed trial, each scan is
also searched for within a step of the last pose before the jump, whatever its score (the front
end, searching within a step of the place it jumped to, can match a scan of a room that looks
alike there as well as the rest); a place there with the better posterior opens a trial.

An exploring walk leaves the wrong place's map behind within a step or two; a kidnapped terminal
keeps matching the place it was carried to.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from radioslam.slam.config import LoopClosureConfig
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.loop_closer import LoopCloser, LoopClosure
from radioslam.slam.posterior import Posterior
from radioslam.slam.rivals import Cause, Rivals
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
    step: np.ndarray | None = None  # the front end's step into the first scan (the no-jump branch's)
    log_odds: float = 0.0  # log p(trial's places | scans) − log p(front end's poses | scans) since the drop
    jump: float = 0.0  # of which the jump's prior odds (≤ 0: the motion expected no jump), paid once

    @property
    def evidence(self) -> float:
        """The log odds the scans themselves brought (the steps after the jump included)."""
        return self.log_odds - self.jump

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

    def velocity(self, estimates: dict[int, np.ndarray]) -> np.ndarray | None:
        """The trial's own last step (None after its first scan: the jump left no velocity)."""
        if len(self.found) < 2:
            return None
        places = [LoopCloser.placed_pose(loop, estimates) for loop in self.found[-2:]]
        return between(places[0], places[1])


class LostAndFound:
    """Opens, follows and decides trials; ``observe`` once per registered scan. A followed scan is
    searched for within ``max_step_m`` of the trial's latest place; ``posterior`` weighs the two
    hypotheses, and ``odds`` confirm one; a confirmed jump leaves the walk without it in ``rivals``."""

    def __init__(self, cfg: LoopClosureConfig, max_step_m: float, posterior: Posterior, odds: float, rivals: Rivals):
        self.cfg, self.max_step_m, self.posterior, self.odds, self.rivals = cfg, max_step_m, posterior, odds, rivals
        self.scores: list[float] = []  # the front end's scores of tracked scans
        self.trial: Trial | None = None
        self.alert = 0  # scans left after a confirmed jump during which each is also searched for where it was taken
        self.taken_from: int | None = None  # the last scan before that jump
        # the scans of each trial that ended undecided: followed for at least confirm_scans scans, its odds
        # within the stated ones of the front end's poses
        self.undecided: list[list[int]] = []

    @property
    def bound(self) -> float:
        """The log odds that confirm a trial: the ending's 1 : ``odds``, a probability ratio."""
        return float(np.log(self.odds))

    @classmethod
    def from_config(cls, cfg, posterior: Posterior, rivals: Rivals) -> "LostAndFound":
        return cls(cfg.loop_closure, cfg.motion.max_step_m, posterior, cfg.ending.odds, rivals)

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
            self._follow(k, pose, points, estimates, loop_closer)
        elif self.alert > 0 or self.suspect(score):
            self._open(k, pose, score, points, estimates, loop_closer)
        if followed:
            self.alert = max(0, self.alert - 1)
        if status in TRACKED and np.isfinite(score):
            self.scores.append(score)
        if self.decided():
            self.rivals.keep(self.trial.found[0].key, self.trial.step, Cause.JUMP)  # the walk without the jump
            found, self.trial = self.trial.found, None
            self.alert, self.taken_from = self.cfg.alert_scans, found[0].key - 1
            return found
        return []

    def decided(self) -> bool:
        """The open trial is confirmed: ``confirm_scans`` scans followed, its odds at least ``bound``."""
        return self.trial is not None and len(self.trial.found) >= self.cfg.confirm_scans and \
            self.trial.log_odds >= self.bound

    def log_odds(self, k: int, points: ScanPoints, place: np.ndarray, fronts: np.ndarray, keys: list[int],
                 places: dict[int, np.ndarray], estimates: dict[int, np.ndarray], scans: dict[int, ScanPoints],
                 velocity=None) -> float:
        """A followed scan k's log posterior at the trial's ``place`` (the map ``keys`` at the trial's ``places``,
        its step from its last place with its own ``velocity``) less that of the no-jump hypothesis: the better
        of its placements ``fronts`` (F, 3: the front end's pose, and its best fit within a step: a front end
        that slipped was not carried away), against the map at the front end's ``estimates`` with the walk's
        motion. Each hypothesis is judged by its own map (the chain rule)."""
        post = self.posterior
        last_place = LoopCloser.placed_pose(self.trial.found[-1], estimates)
        trial = post.placement(k, points, place, last_place, keys, places, scans, velocity=velocity)
        front = max(post.placement(k, points, pose, estimates[k - 1], keys, estimates, scans) for pose in fronts)
        return trial - front

    def _front_placements(self, pose: np.ndarray, points: ScanPoints, grid: LikelihoodGrid, normals: np.ndarray,
                          loop_closer: LoopCloser) -> np.ndarray:
        """The no-jump hypothesis' placements of a scan (2, 3): the front end's pose, and the scan's best fit
        within a step of it in the front end's whole map."""
        refit, _, _ = loop_closer.follow(grid, normals, points, pose[None], self.max_step_m)
        return np.array([pose, refit])

    def _open(self, k, pose, score, points, estimates, loop_closer: LoopCloser) -> None:
        """A trial for scan k: first where the terminal was taken (after a jump), then, if its score
        dropped, wherever in the whole map before it it fits best."""
        keys = loop_closer.keyframes.before(k, before=k)
        if not keys:
            return
        grid, normals = loop_closer.whole_map(keys, estimates)
        if self.alert > 0 and self._open_where_taken(k, pose, points, estimates, loop_closer, keys, grid, normals):
            return
        if not self.suspect(score):
            return
        found = loop_closer.relocalize(k, points, estimates, before=k, whole=(grid, normals))
        if found is None:
            return
        place = loop_closer.placed_pose(found, estimates)
        if loop_closer.looks_alike(compose(place, inverse(pose)), pose, keys, grid, estimates):
            # no scan can tell the two places apart: the front end's stays, and the place found is kept for the
            # ending to weigh with the whole walk (a terminal carried to a look-alike place is not silently lost)
            self.rivals.keep_poses(k, estimates[k - 1], place[None], Cause.LOOKALIKE)
            return
        self._start(k, keys, pose, found, place, points, estimates, loop_closer, found.searched_m2,
                    self._front_placements(pose, points, grid, normals, loop_closer))

    def _open_where_taken(self, k, pose, points, estimates, loop_closer: LoopCloser, keys: list[int],
                          grid: LikelihoodGrid, normals: np.ndarray) -> bool:
        """After a jump, the scan searched for within a step of the last pose before it (a terminal
        carried away is often brought back, foreign scans are followed by the walk's own): a place
        there with the better posterior opens a trial, with no self-similarity test (one place is
        tested, not the whole map's best)."""
        if self.taken_from is None or self.taken_from not in estimates:
            return False
        place, found_score, covariance = loop_closer.follow(grid, normals, points, estimates[self.taken_from][None],
                                                            self.max_step_m)
        if found_score < self.cfg.relocalize_min_score:
            return False
        found = loop_closer.placed(k, place, found_score, covariance, keys, estimates)
        return self._start(k, keys, pose, found, place, points, estimates, loop_closer, grid.area_m2,
                           self._front_placements(pose, points, grid, normals, loop_closer))

    def jump_log_odds(self, k: int, place: np.ndarray, pose: np.ndarray, estimates: dict[int, np.ndarray],
                      area_m2: float) -> float:
        """The prior odds of the step from pose k − 1 to the trial's ``place`` against the front end's ``pose``."""
        last = estimates[k - 1]
        return self.posterior.step_term(k, last, place, area_m2) - self.posterior.step_term(k, last, pose, area_m2)

    def _start(self, k: int, keys: list[int], pose: np.ndarray, found: LoopClosure, place: np.ndarray,
               points: ScanPoints, estimates: dict[int, np.ndarray], loop_closer: LoopCloser, area_m2: float,
               fronts: np.ndarray) -> bool:
        """A trial opened by ``found`` (at ``place``) if the scan itself is more probable there than at the front
        end's ``fronts``: the jump's prior is paid by the scans that follow, or the trial fails."""
        odds = self.posterior.log_odds(k, points, place, fronts, estimates[k - 1], keys, estimates,
                                       loop_closer.keyframes.points, area_m2)
        jump = self.jump_log_odds(k, place, pose, estimates, area_m2)
        if odds - jump <= 0.0:
            return False
        self.trial = Trial(keys, pose, [found], between(estimates[k - 1], pose), odds, jump)
        return True

    def _follow(self, k, pose, points, estimates, loop_closer: LoopCloser) -> None:
        trial = self.trial
        keys = trial.keys + [loop.key for loop in trial.found]
        places = trial.places(estimates)
        grid, normals = loop_closer.whole_map(keys, places)  # the trial's scans at its places
        place, found_score, covariance = loop_closer.follow(grid, normals, points, trial.guesses(pose, estimates),
                                                            self.max_step_m)
        front_grid, front_normals = loop_closer.whole_map(keys, estimates)  # the trial's scans at the front end's
        fronts = self._front_placements(pose, points, front_grid, front_normals, loop_closer)
        trial.log_odds += self.log_odds(k, points, place, fronts, keys, places, estimates, loop_closer.keyframes.points,
                                        velocity=trial.velocity(estimates))
        if found_score < self.cfg.relocalize_min_score or trial.evidence < 0.0 or \
                len(trial.found) >= self.cfg.max_trial_scans:
            # the front end explains the scans better (it was exploring), or the trial was left undecided: its
            # odds within the stated ones either way
            if len(trial.found) >= self.cfg.confirm_scans and trial.evidence >= 0.0 and trial.log_odds > -self.bound:
                self.undecided.append([loop.key for loop in trial.found])
                first = trial.found[0]  # the walk with the trial's jump: for the ending to weigh
                self.rivals.keep_poses(first.key, estimates[first.key - 1],
                                       LoopCloser.placed_pose(first, estimates)[None], Cause.PLACE_FOUND)
            self.trial = None
            return
        trial.found.append(loop_closer.placed(k, place, found_score, covariance, trial.keys, estimates))
        trial.tracked = pose
