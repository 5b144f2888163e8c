"""The SLAM driver (paper §IV-B): radio scans in, trajectory, statuses and loop closures out.

The components each own one job (issue #12): the :class:`~radioslam.slam.front_end.FrontEnd`
registers a scan against its local map, the :class:`~radioslam.slam.loop_closer.LoopCloser`
owns the submaps, loop closures and relocalization, the
:class:`~radioslam.slam.back_end.BackEnd` owns the pose graph. ``RadioSlam.run`` is the story
of one scan, one step per comment.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np

from radioslam.sensing.pointcloud import Scan
from radioslam.slam.back_end import BackEnd
from radioslam.slam.config import Anchors, SlamConfig
from radioslam.slam.errors import SlamError
from radioslam.slam.forks import Forks
from radioslam.slam.front_end import FrontEnd, Step
from radioslam.slam.loop_closer import LoopCloser, LoopClosure
from radioslam.slam.lost_found import LostAndFound
from radioslam.slam.plane_adjustment import PlaneAdjustment, PlaneAdjustmentResult
from radioslam.slam.scan_points import prepare_points
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
        if self.tracking_lost:
            lines.append(f"tracking lost: scans {scan_ranges(self.lost_scans)} matched nothing, or for many scans "
                         "in a row none fixed one pose (a direction nothing fixes, rival poses alike), and were "
                         "not relocalized; their poses are the motion model's")
        return lines

    @property
    def loop_closures(self) -> list[LoopClosure]:
        return [lc for lc in self.loops if not lc.relocalization]


class RadioSlam:
    """Built from plain settings; ``loop_hook`` lets a test replace accepted loop closures;
    ``odometry`` (P, 3) are external odometry poses (their steps become between factors)."""

    def __init__(self, cfg: SlamConfig | None = None,
                 loop_hook: Callable[[LoopClosure], LoopClosure] | None = None):
        self.cfg = cfg or SlamConfig()
        self.loop_hook = loop_hook or (lambda loop: loop)

    def run(self, scans: list[Scan], odometry: np.ndarray | None = None) -> SlamResult:
        cfg = self.cfg
        if not any(len(s) >= cfg.scan.min_points for s in scans):
            raise SlamError(f"none of the {len(scans)} scans has {cfg.scan.min_points} points or more: "
                            "nothing to map", field="(points)")
        if odometry is not None and len(odometry) != len(scans):
            raise SlamError(f"{len(odometry)} odometry poses for {len(scans)} scans", field="(odometry)")
        front_end, loop_closer, back_end = FrontEnd.from_config(cfg, odometry), LoopCloser.from_config(cfg), \
            BackEnd.from_config(cfg)
        lost_and_found, forks = LostAndFound.from_config(cfg), Forks.from_config(cfg)
        steps: list[Step] = []
        sightings: list[np.ndarray] = []  # each scan's sightings of walls, for the last solve
        seconds, lost = [], 0  # lost: consecutive scans nothing matched
        contradiction = Contradiction(cfg.loop_closure.contradicted_fraction, cfg.loop_closure.relocalize_gain)
        for k, scan in enumerate(scans):
            tick = time.perf_counter()
            # 1. the scan's points and the specular normal of the wall each came from
            points = prepare_points(scan, cfg.scan, cfg.grid)
            sightings.append(points.sightings)
            # 2. register it against the local map: the motion's hypotheses and the scan's own rotation candidates
            step = front_end.register(k, points, back_end.estimates)
            # 3. a lost scan (one of a stretch nothing matched, or one whose match puts points on space the map
            #    saw through) is searched for in the whole map: relocalized where the map explains it far better
            lost = lost + 1 if step.status is ScanStatus.PREDICTED else 0
            suspect = lost >= cfg.loop_closure.relocalize_after or contradiction.suspicious(step)
            if suspect and step.status is not ScanStatus.PREDICTED and forks.contested(k, back_end.estimates,
                                                                                      loop_closer, step, points):
                suspect = False  # an open fork the map contradicts the choice of decides first (step 8)
            found = loop_closer.relocalize(k, points, back_end.estimates, k - lost) if suspect else None
            if found is not None and (step.status is ScanStatus.PREDICTED or contradiction.better(found.score, step)):
                step = front_end.relocalized(back_end.relocalized_pose(found), found.score)
            relocalizations = [] if found is None else [found]
            # 4. a score drop opens a trial elsewhere in the map; once confirmed by the scans after it, the
            #    terminal was carried there (kidnapped): every scan of the trial is relocalized
            confirmed = lost_and_found.observe(k, step.status, step.pose, step.score, points, back_end.estimates,
                                               loop_closer)
            if confirmed:
                back_end.cut(confirmed[0].key)
                for loop in confirmed[:-1]:
                    steps[loop.key] = front_end.relocalized(back_end.relocalized_pose(loop), loop.score, confirmed)
                step = front_end.relocalized(back_end.relocalized_pose(confirmed[-1]), confirmed[-1].score, confirmed)
                relocalizations = confirmed
            # 5. the pose and the factors tying it to the previous one into the pose graph
            back_end.add(k, step, front_end.motion.odometry_step(k))
            forks.remember(k, step, back_end.estimates, loop_closer)  # an ambiguous scan's turned rivals
            # 6. the scan joins the local map and the current submap; the motion model learns the step
            front_end.update(k, step, points, back_end.estimates.get(k - 1))
            if step.status is not ScanStatus.SKIPPED:
                loop_closer.add(k, points)
            # 7. loop closures against older submaps near the pose (or the relocalizations), then optimize
            loops = [] if step.status in (ScanStatus.SKIPPED, ScanStatus.DEGENERATE, ScanStatus.PREDICTED) else \
                [self.loop_hook(lc) for lc in loop_closer.close(k, back_end.estimates, back_end.drift)]
            # 8. an ambiguous scan's rival branch that matches the map from before it far better than the chosen
            #    branch, which contradicts that map, is taken: every pose since carried by its jump
            decided = forks.observe(k, step.status, back_end.estimates, loop_closer, last=k == len(scans) - 1)
            if decided is not None:
                back_end.switch(decided.switches)
                loops = [lc for lc in loops if lc.anchor >= decided.fork] + ([] if decided.loop is None else
                                                                            [decided.loop])
                lost_and_found.forget()
                why = ("it matches the map from before far better" if decided.loop is not None else
                       "the chosen branch put walls where the map from before saw through, the rival did not")
                for key, _ in decided.switches:
                    steps[key] = steps[key].noted(f"its rival taken at scan {k}: {why}")
            back_end.add_loops(loops + relocalizations)
            steps.append(step)
            seconds.append(time.perf_counter() - tick)
        back_end.finish()
        # trials left undecided: another place explained their scans almost as well
        for keys in lost_and_found.undecided:
            for key in (key for key in keys if steps[key].status is not ScanStatus.RELOCALIZED):
                steps[key] = steps[key].noted(f"another place of the map explains scans {keys[0]}–{keys[-1]} "
                                              "almost as well (a trial left undecided)", ScanStatus.AMBIGUOUS)
        # 9. every pose adjusted together with the walls its specular arcs face (a smooth last solve)
        tick = time.perf_counter()
        poses = np.array([back_end.estimates[k] for k in range(len(steps))])
        adjuster = PlaneAdjustment.from_config(cfg.plane_adjustment) if cfg.plane_adjustment.enabled else None
        unplaced = np.array([s.status in (ScanStatus.PREDICTED, ScanStatus.SKIPPED) for s in steps])
        degenerate = np.array([s.status is ScanStatus.DEGENERATE for s in steps])
        # the first scan is matched to nothing: where the step out of it fixes no position (the second
        # scan unplaced or degenerate, a hall walked along from its start), neither is its own
        degenerate[:1] |= (unplaced | degenerate)[1:2] & ~unplaced[:1]
        marginal = cfg.plane_adjustment.anchors is Anchors.MARGINAL
        adjusted = adjuster.refine(poses, sightings, back_end.step_covariance, unplaced, degenerate,
                                   back_end.pose_sigmas(len(steps)) if marginal else None) if adjuster else None
        for k in [] if adjusted is None else adjusted.placed:
            steps[k] = steps[k].noted("placed on the walls the other scans sighted by the plane adjustment")
        result = self._result(steps, poses if adjusted is None else adjusted.poses, back_end, seconds,
                              cfg.loop_closure.relocalize_after, cfg.motion.dead_reckoned_scans)
        return replace(result, planes=adjusted, adjustment_seconds=time.perf_counter() - tick)

    @staticmethod
    def _result(steps: list[Step], poses: np.ndarray, back_end: BackEnd, seconds: list[float], lost_after: int,
                dead_reckoned_after: int) -> SlamResult:
        n = len(steps)
        result = SlamResult(poses=poses,
                            odometry=np.array([back_end.chain[k] for k in range(n)]),
                            status=[s.status for s in steps], match_score=np.array([s.score for s in steps]),
                            loops=back_end.loops, seconds_per_scan=np.array(seconds), lost_after=lost_after,
                            dead_reckoned_after=dead_reckoned_after)
        result.warnings = [f"scan {k}: {s.note}" for k, s in enumerate(steps) if s.note] + result.summary_lines()
        return result


@dataclass
class Contradiction:
    """A matched scan that puts at least ``fraction`` of its points on space the map saw through is
    suspect: exploring puts points where the map knows nothing, but a wrong place (a kidnapped
    terminal still half-matches the room's long walls within a step of where it was) puts them
    across free space. It is relocalized only where the map explains it ``gain`` better."""

    fraction: float
    gain: float

    def suspicious(self, step: Step) -> bool:
        return step.status is not ScanStatus.SKIPPED and step.contradicted >= self.fraction

    def better(self, score: float, step: Step) -> bool:
        return self.suspicious(step) and score >= (1.0 + self.gain) * step.score


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
