"""SLAM one scan at a time (paper §IV-B; issue #14): a :class:`SlamSession` takes each radio scan as it
comes and gives its pose at once; :meth:`SlamSession.finish` ends the walk and gives the
:class:`~radioslam.slam.result.SlamResult`. An offline run is a session fed every scan, so a live
session and an offline run of the same scans end with the same trajectory.

The components each own one job (issue #12): the :class:`~radioslam.slam.keyframe_map.KeyframeMap` holds the
scans and their submaps, the :class:`~radioslam.slam.front_end.FrontEnd` registers a scan against its local map of
the latest of them, the :class:`~radioslam.slam.loop_closer.LoopCloser` closes loops against the submaps and
relocalizes, the :class:`~radioslam.slam.back_end.BackEnd` owns the pose graph. :meth:`SlamSession.add` is the story
of one scan, one step per comment.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from radioslam.sensing.pointcloud import Scan
from radioslam.slam.back_end import BackEnd
from radioslam.slam.config import Anchors, SlamConfig
from radioslam.slam.ending import Judge, Source, odometry_in_map_frame
from radioslam.slam.errors import SlamError
from radioslam.slam.forks import Decision, Forks
from radioslam.slam.front_end import FrontEnd, Step
from radioslam.slam.keyframe_map import KeyframeMap
from radioslam.slam.loop_closer import LoopCloser, LoopClosure
from radioslam.slam.lost_found import LostAndFound
from radioslam.slam.occupancy import OccupancyGrid
from radioslam.slam.plane_adjustment import PlaneAdjustment
from radioslam.slam.posterior import Posterior
from radioslam.slam.result import SlamResult
from radioslam.slam.rivals import Cause, Rivals
from radioslam.slam.scan_points import fused_points, prepare_points
from radioslam.slam.status import ScanStatus
from radioslam.slam.submap_map import SubmapMap
from radioslam.slam.thinning import thin_scan


@dataclass(frozen=True)
class ScanUpdate:
    """What one scan gave at once: its key, its pose (world frame, the latest solution) and status."""

    key: int
    pose: np.ndarray
    status: ScanStatus
    seconds: float


class SlamSession:
    """Built from plain settings; ``loop_hook`` lets a test replace accepted loop closures;
    ``odometry`` (P, 3) are external odometry poses of the scans to come (their steps become between
    factors)."""

    def __init__(self, cfg: SlamConfig | None = None,
                 loop_hook: Callable[[LoopClosure], LoopClosure] | None = None,
                 odometry: np.ndarray | None = None):
        self.cfg = cfg = cfg or SlamConfig()
        self.loop_hook = loop_hook or (lambda loop: loop)
        self.keyframes = KeyframeMap.from_config(cfg)  # the map's scans and submaps, shared by the components
        self.front_end = FrontEnd.from_config(cfg, odometry, self.keyframes)
        self.loop_closer = LoopCloser.from_config(cfg, self.keyframes)
        self.back_end = BackEnd.from_config(cfg)
        self.posterior = Posterior.from_config(cfg, self.front_end.motion)  # one scan's placement weighed
        self.rivals = Rivals()  # every decision's alternative, for the ending
        self.lost_and_found = LostAndFound.from_config(cfg, self.posterior, self.rivals)
        self.forks = Forks.from_config(cfg, self.rivals)
        self.steps: list[Step] = []
        self.sightings: list[np.ndarray] = []  # each scan's sightings of walls, for the last solve
        self.seconds: list[float] = []
        self.lost = 0  # consecutive scans nothing matched
        self.map = SubmapMap(cfg.map)  # the live map, scan by scan, in the loop closer's submaps
        self.enough_points = False  # any scan with the points to match

    @property
    def poses(self) -> np.ndarray:
        """(P, 3) the poses of the scans so far at the latest solution."""
        return np.array([self.back_end.estimates[k] for k in range(len(self.steps))]).reshape(-1, 3)

    def occupancy(self) -> OccupancyGrid | None:
        """The occupancy grid now: every submap's (fixed once full) at its first scan's latest pose."""
        return self.map.grid(self.back_end.estimates)

    def map_points(self) -> np.ndarray:
        """(N, 2) every scan's points in the world frame at the latest solution."""
        keys = self.keyframes.keys
        return fused_points(keys, self.back_end.estimates, self.keyframes.points, np.zeros(3))[0] if keys else \
            np.zeros((0, 2))

    def add(self, scan: Scan) -> ScanUpdate:
        """Scan k (the next one): its pose now."""
        k, tick, back_end, forks = len(self.steps), time.perf_counter(), self.back_end, self.forks
        # 1. the scan's points (its horizontal slice, thinned where there are too many, or too far) and the
        #    specular normal of the wall each came from
        scan, points, thinned = self._points(scan)
        # 2. register it against the local map: the motion's hypotheses and the scan's own rotation candidates
        step = self.front_end.register(k, points, back_end.estimates).noted(thinned)
        # 3. a lost scan (one of a stretch nothing matched, or one whose match puts points on space the map
        #    saw through) is searched for in the whole map: relocalized where its posterior there (what the map
        #    explains better, less the prior of a jump that far) beats the front end's pose's
        step, relocalizations = self._relocalized(k, step, points)
        # 4. a score drop opens a trial elsewhere in the map; once confirmed by the scans after it, the
        #    terminal was carried there (kidnapped): every scan of the trial is relocalized
        step, relocalizations = self._taken_elsewhere(k, step, points, relocalizations)
        # 5. the pose and the factors tying it to the previous one into the pose graph; the decision's
        #    alternatives kept for the ending (an ambiguous scan's turned rivals, the motion's expected step)
        back_end.add(k, step, self.front_end.motion.odometry_step(k))
        forks.remember(k, step, back_end.estimates, self.loop_closer)
        self._keep_expected(k, step)
        # 6. the scan joins the map of keyframes (and so the local map and the current submap); the motion model
        #    learns the step
        self._insert(k, step, points, scan)
        # 7. loop closures against older submaps near the pose (sampled while the walk is tied to the map)
        loops = self._loops(k, step)
        # 8. an ambiguous scan's rival branch that matches the map from before it far better than the chosen
        #    branch, which contradicts that map, is taken: every pose since carried by its jump
        self.steps.append(step)
        loops = self._decide(k, forks.observe(k, step.status, back_end.estimates, self.loop_closer), loops)
        # 9. the loops into the pose graph, and its new solution
        back_end.add_loops(loops + relocalizations)
        self.seconds.append(time.perf_counter() - tick)
        return ScanUpdate(k, np.array(back_end.estimates[k]), self.steps[k].status, self.seconds[-1])

    def _points(self, scan: Scan):
        """Step 1: the scan's horizontal slice as thinned, its matchable points (:class:`ScanPoints`) and the note
        on its thinning."""
        cfg = self.cfg
        scan, thinned = thin_scan(scan.horizontal(), cfg.scan.max_points, cfg.scan.max_range_m, cfg.grid.resolution_m)
        self.enough_points |= len(scan) >= cfg.scan.min_points
        points = prepare_points(scan, cfg.scan, cfg.grid)
        self.sightings.append(points.sightings)
        return scan, points, thinned

    def _keep_expected(self, k: int, step: Step) -> None:
        """Step 5: where the scan placed itself against the motion's odds (its step less probable under the motion
        prior than the expected one, by more than the ending's stated odds), the scan's fit at the expected step
        stays the decision's alternative; a step the motion expects about as well is the motion's own
        uncertainty, not a decision."""
        if step.expected is None:
            return
        last = self.back_end.estimates[k - 1]
        against = self.posterior.step_term(k, last, step.expected) - self.posterior.step_term(k, last, step.pose)
        if against > np.log(self.cfg.ending.odds):
            self.rivals.keep_poses(k, last, step.expected, Cause.EXPECTED)

    def _relocalized(self, k: int, step: Step, points) -> tuple[Step, list[LoopClosure]]:
        """Step 3: the step, relocalized where a lost scan's posterior in the whole map beats the front end's pose
        (the pose it replaced kept as its alternative); and the relocalization, if any."""
        cfg, back_end, loop_closer = self.cfg, self.back_end, self.loop_closer
        self.lost = self.lost + 1 if step.status is ScanStatus.PREDICTED else 0
        suspect = self.lost >= cfg.loop_closure.relocalize_after or (
            step.status is not ScanStatus.SKIPPED and step.contradicted >= cfg.loop_closure.contradicted_fraction)
        if suspect and step.status is not ScanStatus.PREDICTED and self.forks.contested(k, back_end.estimates,
                                                                                       loop_closer, step, points):
            suspect = False  # an open fork the map contradicts the choice of decides first (step 8)
        found = loop_closer.relocalize(k, points, back_end.estimates, k - self.lost) if suspect else None
        odds = -np.inf if found is None else self._relocation_log_odds(k, found, step, points)
        if odds <= 0.0:
            if odds > -np.log(cfg.ending.odds):  # not taken, but on odds the ending must weigh
                self.rivals.keep_poses(k, back_end.estimates[k - 1], back_end.relocalized_pose(found),
                                       Cause.PLACE_FOUND)
            return step, []
        self.rivals.keep_poses(k, back_end.estimates[k - 1], step.pose, Cause.RELOCALIZATION)
        return self.front_end.relocalized(back_end.relocalized_pose(found), found.score), [found]

    def _taken_elsewhere(self, k: int, step: Step, points,
                         relocalizations: list[LoopClosure]) -> tuple[Step, list[LoopClosure]]:
        """Step 4: the step and the relocalizations, those of a trial confirmed at scan k in place of step 3's:
        the jump into its first scan loosened, every earlier scan of it relocalized."""
        back_end, front_end = self.back_end, self.front_end
        confirmed = self.lost_and_found.observe(k, step.status, step.pose, step.score, points, back_end.estimates,
                                                self.loop_closer)
        if not confirmed:
            return step, relocalizations
        back_end.cut(confirmed[0].key)
        for loop in confirmed[:-1]:
            self.steps[loop.key] = front_end.relocalized(back_end.relocalized_pose(loop), loop.score, confirmed)
        return front_end.relocalized(back_end.relocalized_pose(confirmed[-1]), confirmed[-1].score,
                                     confirmed), confirmed

    def _insert(self, k: int, step: Step, points, scan: Scan) -> None:
        """Step 6: the scan (thinned) into the map of keyframes (its submap) and the live occupancy map; the step
        into the motion model."""
        self.front_end.update(step, self.back_end.estimates.get(k - 1))
        if step.status is not ScanStatus.SKIPPED:
            self.keyframes.insert(k, points)
            self.map.add(k, scan.xy, self.keyframes.submaps[-1].anchor, self.back_end.estimates)

    def _loops(self, k: int, step: Step) -> list[LoopClosure]:
        """Step 7: scan k's loop closures (none from a scan that fixed no pose), each through the loop hook."""
        back_end, loop_closer = self.back_end, self.loop_closer
        budget = 0 if step.status in (ScanStatus.SKIPPED, ScanStatus.DEGENERATE, ScanStatus.PREDICTED) else \
            loop_closer.budget(k, back_end.loops[-1].key if back_end.loops else None)
        return [self.loop_hook(lc) for lc in loop_closer.close(k, back_end.estimates, back_end.drift, budget)]

    def _relocation_log_odds(self, k: int, found: LoopClosure, step: Step, points) -> float:
        """Scan k's log posterior odds at the place relocalization ``found`` against the front end's pose, under
        the map before it (:meth:`Posterior.log_odds`)."""
        estimates = self.back_end.estimates
        return self.posterior.log_odds(k, points, self.back_end.relocalized_pose(found), step.pose[None],
                                       estimates[k - 1], self.keyframes.before(k, before=k), estimates,
                                       self.keyframes.points, found.searched_m2)

    def _decide(self, k: int, decided: Decision | None, loops: list[LoopClosure]) -> list[LoopClosure]:
        """A fork decided at scan k: its rival's poses taken; the loops of scan k that still hold."""
        if decided is None:
            return loops
        estimates = self.back_end.estimates
        for key, _ in decided.switches:  # the branch left
            self.rivals.keep_poses(key, estimates[key - 1], estimates[key], Cause.FORK)
        self.back_end.switch(decided.switches)
        self.lost_and_found.forget()
        why = ("it matches the map from before far better" if decided.loop is not None else
               "the chosen branch put walls where the map from before saw through, the rival did not")
        for key, _ in decided.switches:
            self.steps[key] = self.steps[key].noted(f"its rival taken at scan {k}: {why}")
        return [lc for lc in loops if lc.anchor >= decided.fork] + ([] if decided.loop is None else [decided.loop])

    def finish(self) -> SlamResult:
        """The walk ended: an open fork decided on the evidence there is, the last solve, the result."""
        cfg, back_end, steps = self.cfg, self.back_end, self.steps
        if not self.enough_points:
            raise SlamError(f"none of the {len(steps)} scans has {cfg.scan.min_points} points or more: "
                            "nothing to map", field="(points)")
        # the walk's last scan: no more evidence will come, so an open fork decides at the plain significance
        k = len(steps) - 1
        back_end.add_loops(self._decide(k, self.forks.observe(k, steps[k].status, back_end.estimates,
                                                              self.loop_closer, last=True), []))
        back_end.finish()
        # trials left undecided: another place explained their scans almost as well
        for keys in self.lost_and_found.undecided:
            for key in (key for key in keys if steps[key].status is not ScanStatus.RELOCALIZED):
                steps[key] = steps[key].noted(f"another place of the map explains scans {keys[0]}–{keys[-1]} "
                                              "almost as well (a trial left undecided)", ScanStatus.AMBIGUOUS)
        # every pose adjusted together with the walls its specular arcs face (a smooth last solve)
        tick = time.perf_counter()
        poses = self.poses
        adjuster = PlaneAdjustment.from_config(cfg.plane_adjustment) if cfg.plane_adjustment.enabled else None
        unplaced = np.array([s.status in (ScanStatus.PREDICTED, ScanStatus.SKIPPED) for s in steps])
        degenerate = np.array([s.status is ScanStatus.DEGENERATE for s in steps])
        # the first scan is matched to nothing: where the step out of it fixes no position (the second
        # scan unplaced or degenerate, a hall walked along from its start), neither is its own
        if len(steps) > 1:
            degenerate[0] |= (unplaced[1] or degenerate[1]) and not unplaced[0]
        marginal = cfg.plane_adjustment.anchors is Anchors.MARGINAL
        adjusted = adjuster.refine(poses, self.sightings, back_end.step_covariance, unplaced, degenerate,
                                   back_end.pose_sigmas(len(steps)) if marginal else None,
                                   back_end.odometry_covariance(self.front_end.motion)) if adjuster else None
        for k in [] if adjusted is None else adjusted.placed:
            steps[k] = steps[k].noted("placed on the walls the other scans sighted by the plane adjustment")
        result = self._result(poses if adjusted is None else adjusted.poses)
        result = replace(result, planes=adjusted, adjustment_seconds=time.perf_counter() - tick)
        # the honest ending: the trajectories held compared by their posteriors, the best the answer
        return self._ending(result) if cfg.ending.enabled else result

    def _ending(self, result: SlamResult) -> SlamResult:
        """The result with the best of the pose graph's trajectory, the odometry's and every decision's
        alternative, and the runner-up when its odds are within the stated ones (a warning naming the cause)."""
        tick = time.perf_counter()
        motion = self.front_end.motion
        candidates = [(Source.POSE_GRAPH, result.poses)]
        odometry = odometry_in_map_frame(motion.odometry, result.poses[0]) if motion.odometry is not None else None
        if odometry is not None:
            candidates.append((Source.ODOMETRY, odometry))
        judge, scans = Judge.from_config(self.cfg, self.posterior), self.keyframes.points
        answer = judge.scan_terms(result.poses, scans)
        branches = [(rival.key, judge.aligned(rival.key, poses, scans)) for rival, poses in
                    self.rivals.branches(result.poses)]
        branches += judge.excursions(branches, result.poses)
        candidates += [(Source.RIVAL_BRANCH, poses) for poses in
                       judge.shortlist(branches, answer, scans, self.cfg.ending.hypotheses)]
        ending = judge.judge(candidates, scans, [answer])
        best, runner_up = ending.best, ending.runner_up
        lines = []
        if best.source is not Source.POSE_GRAPH:
            lines.append(f"the {best.source.value}'s trajectory explains the scans and the motion better than the "
                         f"pose graph's (odds {ending.odds_over(Source.POSE_GRAPH):.3g} : 1): it is the answer")
        if ending.ambiguous:
            lines.append(judge.warning(best, runner_up, ending.runner_up_odds, result.status,
                                       motion.odometry is not None))
        return replace(result, poses=best.poses, source=best.source.value, warnings=result.warnings + lines,
                       ending_lines=lines,
                       ambiguous_trajectory=ending.ambiguous,
                       alternative=runner_up.poses if ending.ambiguous else None,
                       alternative_source=runner_up.source.value if ending.ambiguous else None,
                       alternative_odds=ending.runner_up_odds, ending_seconds=time.perf_counter() - tick)

    def _result(self, poses: np.ndarray) -> SlamResult:
        steps, back_end, cfg = self.steps, self.back_end, self.cfg
        carried = self.front_end.motion.dead_reckoning_scans()  # odometry keeps a stretch no scan fixed this long
        result = SlamResult(poses=poses, odometry=np.array([back_end.chain[k] for k in range(len(steps))]),
                            status=[s.status for s in steps], match_score=np.array([s.score for s in steps]),
                            loops=back_end.loops, seconds_per_scan=np.array(self.seconds),
                            lost_after=max(cfg.loop_closure.relocalize_after, carried),
                            dead_reckoned_after=max(cfg.motion.dead_reckoned_scans, carried))
        result.warnings = [f"scan {k}: {s.note}" for k, s in enumerate(steps) if s.note] + result.summary_lines()
        return result
