"""The front end (paper §IV-B; issue #12): each scan registered against a local map of the
latest scans, whatever the motion since the last one.

Like PRBonn/kiss-icp's ``KissICP.register_frame`` and Cartographer's
``LocalTrajectoryBuilder2D``, it owns the motion model and the local map. What it adds is
that the rotation comes from the scan itself: the candidates of the global rotation search
(:mod:`radioslam.slam.rotation_search`) and the motion model's hypotheses (standing still,
constant velocity, the last turn repeated, odometry) are all searched, each over every
translation within ``max_step_m`` of the last pose, by one branch-and-bound search
(Hess et al. 2016 §V); with full odometry, only the Gaussian core of its step (±3σ of its
stated noise). Distinct candidates within ``ambiguity_margin`` of the best make
the scan ambiguous: the one nearest the motion is taken, its covariance widened over the others,
unless the scan shows a turned one clearly better (:func:`choose`). The winner's response
surface gives the covariance (Olson 2009 §IV) and a least-squares fit refines it. A direction
no wall fixes keeps the paced prediction (Zhang et al. 2016). A weak match is weighed against
the prediction smoothly; one the map does not support at all is lost, for the loop closer to
relocalize.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from functools import cache, partial

import numpy as np

from radioslam.slam.branch_bound import distinct
from radioslam.slam.config import FrontEndConfig, GridConfig, MotionConfig, ScanConfig
from radioslam.slam.correlative import candidate_likelihoods
from radioslam.slam.degeneracy import remap
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.keyframe_map import KeyframeMap
from radioslam.slam.motion import Hypothesis, MotionHypothesis, MotionModel, jump_covariance
from radioslam.slam.scan_matcher import ScanMatcher, front_end_matcher
from radioslam.slam.scan_points import ScanPoints
from radioslam.slam.se2 import between, pose_covariance, wrap_angle
from radioslam.slam.status import ScanStatus

# with full odometry the front end searches its step's Gaussian core: ±3σ in each axis holds 99.7 % of it
ODOMETRY_CORE_SIGMAS = 3.0


@dataclass(frozen=True)
class Step:
    """What the front end made of one scan: the world pose, its covariance, how it was found."""

    pose: np.ndarray
    covariance: np.ndarray  # (3, 3) world frame
    status: ScanStatus
    score: float = float("nan")  # normalized match score; NaN where nothing was matched
    rivals: np.ndarray = field(default_factory=lambda: np.zeros((0, 3)))  # other hypotheses within the margin
    note: str = ""  # why the status is not MATCHED, for the warnings
    contradicted: float = 0.0  # fraction of the points on space the map saw through (a wrong place)
    expected: np.ndarray | None = None  # the scan's fit at the motion's prediction, where the pose is another

    def noted(self, text: str, status: ScanStatus | None = None) -> "Step":
        """This step with ``text`` added to its note (and its status replaced, when given)."""
        note = "; ".join(filter(None, [self.note, text]))
        return replace(self, note=note, status=self.status if status is None else status)


def fuse(pose: np.ndarray, covariance: np.ndarray, weight: float, prior: np.ndarray,
         prior_covariance: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The match (covariance / weight) fused with a prior: the prior alone at weight 0, the
    match alone as the prior's covariance grows; continuous in the weight."""
    inner = np.linalg.inv(covariance + weight * prior_covariance)
    gain = covariance @ inner  # K = (C/w)(C/w + C_p)⁻¹
    d = prior - pose
    d[2] = wrap_angle(d[2])
    fused = pose + gain @ d
    fused[2] = wrap_angle(fused[2])
    fused_cov = prior_covariance @ inner @ covariance  # (I − K)·C/w, without dividing by w
    return fused, 0.5 * (fused_cov + fused_cov.T)


def choose(candidates: np.ndarray, scores: np.ndarray, discount: np.ndarray, margin: float, turn_rad: float,
           trusted: float) -> tuple[int, np.ndarray]:
    """The candidate (C, 3) a scan is registered at, from its scores (C,) and motion-prior discounts (C,),
    and the indices of those within ``margin`` of the best discounted score (the scan cannot tell them
    apart): among those the motion decides (the smallest discount), unless the scan itself explains a
    candidate turned ≥ ``turn_rad`` from that choice clearly better (its own score beyond the margin of
    the choice's, and ``trusted`` at least): then the turn is seen in the scan, and its discount already
    holds the motion (not counted twice), so the best discounted of those is taken."""
    adjusted = scores * (1.0 - discount)
    best = adjusted.max()
    close = np.flatnonzero(adjusted >= best - margin * abs(best))  # the best is always among them, whatever its sign
    chosen = int(close[np.argmin(discount[close])])
    turned = close[np.abs(wrap_angle(candidates[close, 2] - candidates[chosen, 2])) >= turn_rad]
    seen = turned[(scores[turned] * (1.0 - margin) > scores[chosen]) & (scores[turned] >= trusted)]
    return (int(seen[np.argmax(adjusted[seen])]) if len(seen) else chosen), close


class FrontEnd:
    """Built from plain settings by :meth:`from_config`; ``register`` then ``update`` per scan."""

    def __init__(self, grid: GridConfig, scan: ScanConfig, cfg: FrontEndConfig, motion_cfg: MotionConfig,
                 motion: MotionModel, matcher: ScanMatcher, keyframes: KeyframeMap):
        self.grid_cfg, self.scan_cfg, self.cfg, self.motion_cfg, self.motion = grid, scan, cfg, motion_cfg, motion
        self.matcher, self.degeneracy = matcher, matcher.degeneracy
        self.keyframes = keyframes  # the map's scans (the session inserts them); the local map is the latest
        self.step_rad = matcher.options.angle_step_rad
        self.predicted = pose_covariance(motion_cfg.predicted_sigma_m, motion_cfg.predicted_sigma_deg)
        self.jump = jump_covariance(motion_cfg)  # a relocalized scan's step: the relocalization fixes the pose

    @classmethod
    def from_config(cls, cfg, odometry: np.ndarray | None = None, keyframes: KeyframeMap | None = None) -> "FrontEnd":
        motion = MotionModel.from_config(cfg.motion, odometry)
        return cls(cfg.grid, cfg.scan, cfg.front_end, cfg.motion, motion, front_end_matcher(cfg),
                   KeyframeMap.from_config(cfg) if keyframes is None else keyframes)

    def register(self, k: int, points: ScanPoints, estimates: dict[int, np.ndarray]) -> Step:
        """Scan k's pose; ``estimates`` holds every earlier pose (the latest solution)."""
        last = estimates.get(k - 1)
        if len(points) < self.scan_cfg.min_points:
            pose = np.zeros(3) if last is None else self.motion.predict(k, last)
            return Step(pose, self.predicted, ScanStatus.SKIPPED,
                        note=f"{len(points)} points (< {self.scan_cfg.min_points}), skipped")
        if not len(self.keyframes):  # the first scan defines the map frame
            pose = np.zeros(3) if last is None else self.motion.predict(k, last)
            return Step(pose, self.predicted, ScanStatus.MATCHED)
        return self._match(k, points, estimates, last)

    def _match(self, k: int, points: ScanPoints, estimates: dict[int, np.ndarray], last: np.ndarray) -> Step:
        cfg, xy, phi = self.cfg, points.xy, points.normals
        grid, map_normals = self._local_grid(estimates)
        hypotheses = self.motion.hypotheses(k, last)
        primary = hypotheses[0].pose
        prediction_fit = cache(lambda: self._prediction_fit(grid, xy, phi, primary))  # fitted once, if asked
        # every heading the scan's normals or the motion suggest over every translation within a step, or with
        # full odometry its step's Gaussian core
        centre, window, headings = self._search_region(phi, map_normals, hypotheses, last)
        found = self.matcher.search(
            grid, xy, phi, centre, headings, window, 0.0,
            self.matcher.keep_ratio, lambda poses: self._prior_discount(poses, hypotheses),
            np.array([h.pose for h in hypotheses]))
        if found.pose is None:
            return Step(primary, self.predicted, ScanStatus.PREDICTED, 0.0, note="nothing in the local map matches")
        candidates = self._contenders(found.candidates, found.scores, found.judged)
        # each candidate refined off the lattice and scored on the interpolated field: a pose between
        # cells must not lose to one that happens to sit on the lattice
        candidates = self.matcher.refine(grid, xy, phi, candidates)
        scores = self.matcher.scores(grid, xy, phi, candidates)
        discount = self._prior_discount(candidates, hypotheses)
        # the motion decides what the scan cannot tell apart, and no more
        chosen, close = choose(candidates, scores, discount, cfg.ambiguity_margin, np.radians(cfg.distinct_deg),
                               cfg.min_match_score + cfg.trust_ramp)
        # the motion's own choice among the candidates the scan supports (trusted scores)
        supported = np.flatnonzero(scores >= cfg.min_match_score + cfg.trust_ramp)
        by_motion = int(supported[np.argmin(discount[supported])]) if len(supported) else chosen
        turned = abs(wrap_angle(candidates[chosen, 2] - candidates[by_motion, 2])) >= np.radians(cfg.distinct_deg)
        # rivals: what the scan alone cannot tell from the choice (within the margin of its score, or above);
        # those the motion could not tell apart either (``close``) widen the covariance
        alike = np.setdiff1d(np.flatnonzero(scores >= (1.0 - cfg.ambiguity_margin) * scores[chosen]), [chosen])
        rivals, undecided = candidates[alike], candidates[np.intersect1d(alike, close)]
        pose, score = candidates[chosen], float(scores[chosen])
        contradicted = float(np.mean(candidate_likelihoods(grid, xy, phi, pose, np.zeros(1), np.zeros(1, int)) < 0))
        # the response surface around it gives the covariance (Olson 2009 §IV)
        cov = self.matcher.response(grid, xy, phi, pose).covariance + self.matcher.floor
        weight = float(np.clip((score - cfg.min_match_score) / cfg.trust_ramp, 0.0, 1.0))
        if weight == 0.0:
            return Step(primary, self.predicted, ScanStatus.PREDICTED, score,
                        note=f"match score {score:.2f} < {cfg.min_match_score:.2f}", contradicted=contradicted)
        weak = self.matcher.weak(grid, pose, xy, phi, cov)
        if weak is not None:  # candidates that only slide along the weak direction are not rivals
            rivals, undecided = (self._across(r, pose, weak) for r in (rivals, undecided))
        status, note = ScanStatus.MATCHED, ""
        if weak is not None:
            # a direction the match made weak itself: the walls facing along it agree elsewhere on it
            pose, cov, weak, note = self._settle(k, last, grid, pose, cov, points, weak)
        # a slide the walls facing along it tell apart is no rival (the others' points land alike)
        rivals, undecided = (r[~self.degeneracy.told_apart(grid, pose, xy, phi, r, cfg.ambiguity_margin,
                                                           np.radians(cfg.distinct_deg))] for r in (rivals, undecided))
        if weak is not None:
            # a direction the walls cannot fix keeps the paced prediction there (Zhang et al. 2016)
            pose, cov = remap(pose, cov, self.motion.paced(primary, last), weak, self.motion_cfg.predicted_sigma_m)
            status = ScanStatus.DEGENERATE
            note = (f"degenerate match, nothing fixes the position along "
                    f"{np.degrees(np.arctan2(weak[1], weak[0])):.0f}° (predicted instead)")
        if len(rivals):
            status = ScanStatus.AMBIGUOUS
            note = "; ".join(filter(None, [note, f"ambiguous: {len(rivals)} other pose(s) score within "
                                                 f"{cfg.ambiguity_margin:.0%}"]))
        if len(undecided):
            # neither the scan nor the motion can decide: widen the covariance over the poses left
            spread = undecided - pose
            spread[:, 2] = wrap_angle(spread[:, 2])
            cov = cov + spread.T @ spread / len(undecided)
        if turned and not np.any(np.all(np.isclose(rivals, candidates[by_motion]), axis=1)):
            # the scan took a pose turned from the motion's choice: that stays a rival for the map to decide
            # (a corridor folded back onto itself explains a corner's scan better than the corner does,
            # whose new walls the map has not seen yet), and so does the prediction's own fit, where the
            # candidates, ranked against the turned one, missed it (a corner's clutter)
            rivals = self._with_prediction_fit(np.vstack([rivals, candidates[by_motion]]), prediction_fit())
            status = ScanStatus.AMBIGUOUS
            turn = np.degrees(wrap_angle(pose[2] - candidates[by_motion, 2]))
            note = "; ".join(filter(None, [note, f"turned {turn:.0f}° from the motion's choice, which stays a rival"]))
        elif (jump := float(np.linalg.norm(pose[:2] - last[:2]))) > self.motion_cfg.max_step_m:
            # a pose no step reaches (the search window's corners lie beyond max_step_m), with no candidate near
            # the motion left to compare (each scored below trust, or none kept): the prediction's own fit stays
            # a rival where it is turned from the pose taken (a fork's rival: where the motion's candidate fell
            # out of branch and bound's list, a fold taken beyond a step would otherwise open no fork)
            widened = self._with_prediction_fit(rivals, prediction_fit())
            if len(widened) > len(rivals) and abs(wrap_angle(widened[-1, 2] - pose[2])) >= np.radians(cfg.distinct_deg):
                rivals, status = widened, ScanStatus.AMBIGUOUS
                note = "; ".join(filter(None, [note, f"{jump:.2f} m from the last pose, beyond a step: the "
                                                     "prediction's fit stays a rival"]))
        if weight < 1.0:
            pose, cov = fuse(pose, cov, weight, primary, self.predicted)
            if abs(wrap_angle(primary[2] - pose[2])) >= np.radians(cfg.distinct_deg):
                # a weak match turned from the motion's prediction: the prediction stays a rival
                rivals = np.vstack([rivals, primary])
                status = ScanStatus.AMBIGUOUS
                note = "; ".join(filter(None, [note, f"weak match (score {score:.2f}) turned "
                                                     f"{np.degrees(wrap_angle(pose[2] - primary[2])):.0f}° from the "
                                                     "motion's prediction, which stays a rival"]))
        # the scan's own fit where the motion expected it, where it placed itself elsewhere: the decision's
        # alternative, for the ending to weigh (:class:`radioslam.slam.rivals.Cause`)
        expected = prediction_fit() if self._apart(pose, primary) else None
        return Step(pose, cov, status, score, rivals, note, contradicted, expected)

    def _apart(self, a: np.ndarray, b: np.ndarray) -> bool:
        """Whether two poses are distinct (beyond ``distinct_m`` or ``distinct_deg``)."""
        return bool(np.linalg.norm(a[:2] - b[:2]) > self.cfg.distinct_m or
                    abs(wrap_angle(a[2] - b[2])) > np.radians(self.cfg.distinct_deg))

    def _search_region(self, phi: np.ndarray, map_normals: np.ndarray, hypotheses: list[Hypothesis],
                       last: np.ndarray) -> tuple[np.ndarray, float, np.ndarray]:
        """Where the scan is searched: the centre (2,), the half width of the square window and the headings (A,).
        With full odometry, its step's Gaussian core: ``ODOMETRY_CORE_SIGMAS`` of its per-step σ around it in
        each axis (the motion prior's mass lies there; a step beyond it is the prior's unexpected share, left to
        relocalization when the scan then matches nothing). Otherwise every translation within ``max_step_m`` of
        the last pose, at every heading the scan's normals or the motion's hypotheses suggest."""
        primary = hypotheses[0]
        if primary.kind is MotionHypothesis.ODOMETRY and not self.motion.gyro_only:
            reach = ODOMETRY_CORE_SIGMAS * self.motion.odometry_sigmas
            turns = np.arange(-reach[2], reach[2] + 1e-12, self.step_rad)
            return primary.pose[:2], float(reach[0]), wrap_angle(primary.pose[2] + turns)
        headings = self.matcher.headings(phi, map_normals, [h.pose[2] for h in hypotheses])
        return last[:2], self.motion_cfg.max_step_m, headings

    def _settle(self, k: int, last: np.ndarray, grid: LikelihoodGrid, pose: np.ndarray, cov: np.ndarray,
                points: ScanPoints, weak: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, str]:
        """A degenerate match slid along its weak direction to the slide the walls facing along it and the
        motion's prior of scan k's step from ``last`` make most probable (:meth:`DegeneracyTest.settled`),
        with the covariance there, when it is no longer degenerate there; else the match as it was."""
        xy, phi = points.xy, points.normals
        settled = self.degeneracy.settled(grid, pose, xy, phi, points.observation_weights, weak,
                                          self.motion_cfg.max_step_m, partial(self.motion.log_prob, k, last))
        if settled is None:
            return pose, cov, weak, ""
        settled = self.matcher.refine(grid, xy, phi, settled)[0]
        settled_cov = self.matcher.response(grid, xy, phi, settled).covariance + self.matcher.floor
        if self.matcher.weak(grid, settled, xy, phi, settled_cov) is not None:
            return pose, cov, weak, ""
        dx, dy = settled[:2] - pose[:2]
        note = (f"moved {np.hypot(dx, dy):.2f} m toward {np.degrees(np.arctan2(dy, dx)):.0f}° by the walls facing "
                "that way (the match had slid along the others)")
        return settled, settled_cov, None, note

    def _contenders(self, candidates: np.ndarray, scores: np.ndarray, adjusted: np.ndarray) -> np.ndarray:
        """The distinct candidates (C, 3; lattice ``scores`` (C,) and the motion prior's ``adjusted`` ones) that
        :func:`choose` may pick, to be refined: the best ``refined_candidates`` by discounted score (branch
        and bound's order: the motion's picks), and those the scan itself explains clearly better than all
        of them (their own score beyond the ambiguity margin of theirs) whose discounted score is within
        the margin of the best: a turn seen in the scan, which ``choose`` takes whatever its discount. By
        discounted score alone, a U-turn the scan shows clearly ranks below the walk-on candidates and is
        never refined."""
        cfg, o = self.cfg, self.matcher.options
        by_motion, motion_scores = self.matcher.distinct(candidates, scores)
        seen = (scores * (1.0 - cfg.ambiguity_margin) > motion_scores.max()) & \
            (adjusted >= (1.0 - cfg.ambiguity_margin) * adjusted.max())
        order = np.flatnonzero(seen)[np.argsort(-scores[seen], kind="stable")]
        by_scan, _ = self.matcher.distinct(candidates[order], scores[order])
        both = np.concatenate([by_motion, by_scan])
        merged, _ = distinct(both, np.zeros(len(both)), o.distinct_m, o.distinct_rad, 2 * o.refined)
        return merged

    def _with_prediction_fit(self, rivals: np.ndarray, fitted: np.ndarray) -> np.ndarray:
        """``rivals`` (R, 3) and the scan's own fit near the motion's prediction (:meth:`_prediction_fit`),
        unless a rival is that hypothesis already (within ``distinct_m`` and ``distinct_deg`` of it: a rival
        at the same place turned the other way is another hypothesis)."""
        if any(not self._apart(rival, fitted) for rival in rivals):
            return rivals
        return np.vstack([rivals, fitted])

    def _prediction_fit(self, grid: LikelihoodGrid, xy: np.ndarray, phi: np.ndarray, primary: np.ndarray) -> np.ndarray:
        """The scan's best fit (3,) within ``distinct_m`` of the motion's prediction ``primary``."""
        return self.matcher.response(grid, xy, phi, primary, self.cfg.distinct_m).pose

    def _across(self, rivals: np.ndarray, pose: np.ndarray, weak: np.ndarray) -> np.ndarray:
        """The rivals that differ from ``pose`` other than by sliding along the weak direction."""
        d = rivals[:, :2] - pose[:2]
        across = d - np.outer(d @ weak, weak)
        return rivals[(np.linalg.norm(across, axis=1) > self.cfg.distinct_m)
                      | (np.abs(wrap_angle(rivals[:, 2] - pose[2])) > np.radians(self.cfg.distinct_deg))]

    def _prior_discount(self, candidates: np.ndarray, hypotheses: list[Hypothesis]) -> np.ndarray:
        """The motion prior as a fraction (C,) of each candidate's score: ``motion_prior`` times its
        turn from the nearest hypothesis' heading in half turns, plus, once the motion is known,
        ``translation_prior`` times its distance from the primary hypothesis per ``max_step_m``."""
        cfg = self.cfg
        turn = np.min(np.abs(wrap_angle(candidates[:, 2][:, None] - [h.pose[2] for h in hypotheses])), axis=1)
        discount = cfg.motion_prior * turn / np.pi
        primary = hypotheses[0]
        if primary.kind is not MotionHypothesis.STILL:  # a step is predicted: deviations from it cost
            shift = np.linalg.norm(candidates[:, :2] - primary.pose[:2], axis=1) / self.motion_cfg.max_step_m
            discount = discount + cfg.translation_prior * np.minimum(shift, 1.0)
        return discount

    def _local_grid(self, estimates: dict[int, np.ndarray]) -> tuple[LikelihoodGrid, np.ndarray]:
        """The likelihood field of the local map's scans at their latest poses (world frame), and the
        map points' world normals."""
        return self.keyframes.grid(self.local_map_keys(estimates), estimates, self.grid_cfg)

    def local_map_keys(self, estimates: dict[int, np.ndarray]) -> list[int]:
        """The front end's local map now (:func:`local_map_keys`)."""
        return local_map_keys(self.keyframes.keys, estimates, self.cfg)

    def update(self, step: Step, previous: np.ndarray | None) -> None:
        """The motion model learns the step just taken (from the pose before it, ``previous``)."""
        jumped = previous is None or step.status is ScanStatus.RELOCALIZED
        self.motion.update(None if jumped else between(previous, step.pose),
                           observed=step.status is ScanStatus.MATCHED)

    def relocalized(self, pose: np.ndarray, score: float, trial: list | None = None) -> Step:
        """The step of a lost scan that the loop closer found again at ``pose``; ``trial``: the
        relocalizations of a confirmed trial it belongs to (:mod:`radioslam.slam.lost_found`)."""
        note = "lost, relocalized against the whole map" if not trial else \
            (f"taken elsewhere: scans {trial[0].key}–{trial[-1].key} match another place of the map far better "
             "than the local map, relocalized there")
        return Step(pose, self.jump, ScanStatus.RELOCALIZED, score, note=note)


def local_map_keys(keys: list[int], estimates, cfg: FrontEndConfig) -> list[int]:
    """The latest ``local_map_scans`` of ``keys`` (the scans matched so far, oldest first), and up to
    ``nearby_scans`` older ones taken within ``nearby_radius_m`` of the last one's pose (nearest first): what
    saw the walls around the terminal, as kiss-icp keeps every point within range of the current pose."""
    recent, older = keys[-cfg.local_map_scans:], np.array(keys[:-cfg.local_map_scans], int)
    if not len(older) or not cfg.nearby_scans:
        return recent
    here = estimates[keys[-1]][:2]
    distance = np.linalg.norm(np.array([estimates[m][:2] for m in older]) - here, axis=1)
    near = np.argsort(distance, kind="stable")[: cfg.nearby_scans]
    near = near[distance[near] <= cfg.nearby_radius_m]
    return sorted(older[near].tolist()) + recent
