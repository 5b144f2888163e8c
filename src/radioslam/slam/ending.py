"""The honest ending (issue #47, point 4): at the walk's end, the trajectories the SLAM holds are compared
by their log posteriors, the best is the answer, and a runner-up within stated odds is reported with it.

The hypotheses: the pose graph's solution (with the plane adjustment), the external odometry when given
(placed at the first pose), and every decision's alternative (:mod:`radioslam.slam.rivals`: an ambiguous
scan's turned rival, the motion's expected step where the scan overrode it, the branch a fork's decision
left, the pose a relocalization replaced, the walk without a confirmed jump; each the answer with that one step
replaced, every later pose carried with it, the step aligned by the scans after it, :meth:`Judge.aligned`; and
each one's excursions, returning to the answer where the answer's own step of return is a surprise,
:meth:`Judge.excursions`; the ``ending.hypotheses`` of highest odds over the answer screened on a sample of
the scans each changes, :meth:`Judge.shortlist`). The front end's own
chain is no hypothesis here: it is greedy in exactly this likelihood (each scan placed on its predecessors), and beat
the loop-corrected trajectory on it where the latter was ten times closer to the truth (docs/notes.md,
session 28). Two that agree (every pose within ``same_m`` and ``same_deg``) are one. Each trajectory T scores

    log p(T | scans, u) = Σ_k log p(scan k | T_k, map of the scans before k near T_k)
                        + Σ_k log p(step k | motion, odometry)

with the front end's measurement model (:mod:`radioslam.slam.measurement`: each specular arc one
observation, unseen space at the prior of a surface, seen-through space contradicting, and so a scan's
own clear lines across mapped walls) against the
scans before k whose poses lie within scan k's reach of T_k (revisits included: a folded trajectory lays
a corridor's scans over another's, where their echoes contradict each other), and the motion prior
(:mod:`radioslam.slam.motion_prior`) of each step given the one before it and the odometry.

A trajectory the scans cannot support better than the odometry (a corridor nothing fixes) then loses to
the odometry; and when the runner-up's odds are better than 1 : ``odds`` (a rival branch: it is never the
answer, see :class:`Ending`), the run says so (``ambiguous_trajectory``) and keeps the alternative.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

import numpy as np

from radioslam.slam.posterior import Posterior, extent_m2
from radioslam.slam.refine import refine_poses
from radioslam.slam.result import scan_ranges
from radioslam.slam.scan_points import ScanPoints, fused_points, map_grid
from radioslam.slam.se2 import between, compose, inverse, wrap_angle
from radioslam.slam.status import ScanStatus


class Source(str, Enum):
    """Where a trajectory hypothesis comes from."""

    POSE_GRAPH = "pose graph"
    ODOMETRY = "odometry"
    RIVAL_BRANCH = "rival branch"  # an open fork's rival: the walk after an ambiguous scan taken the other way


@dataclass(frozen=True)
class Hypothesis:
    source: Source
    poses: np.ndarray  # (P, 3) map frame
    log_likelihood: float  # the scans' term
    log_prior: float  # the motion's term

    @property
    def log_posterior(self) -> float:
        return self.log_likelihood + self.log_prior


@dataclass(frozen=True)
class Ending:
    """The hypotheses, best first; the answer and its runner-up, and whether the runner-up is within the
    stated odds of the answer.

    The answer is the best of the pose graph's and the odometry's trajectories. A rival branch is never the
    answer, only a runner-up: these odds are not calibrated well enough to carry a walk onto a turned twin
    (on the look-alike rooms the best-scoring rival was the wrong one in 3 of 6 runs, docs/notes.md,
    session 28), but they are evidence enough that the answer may be wrong: a rival that scores better than
    the answer, or within the odds, makes the trajectory ambiguous."""

    hypotheses: list[Hypothesis]
    odds: float  # the ambiguity threshold: 1 : odds

    @property
    def best(self) -> Hypothesis:
        """The answer."""
        return next(h for h in self.hypotheses if h.source is not Source.RIVAL_BRANCH)

    @property
    def runner_up(self) -> Hypothesis | None:
        """The best hypothesis other than the answer."""
        return next((h for h in self.hypotheses if h is not self.best), None)

    @property
    def runner_up_odds(self) -> float:
        """p(answer) / p(runner-up) (inf: none; below 1 where a rival branch scores better)."""
        if self.runner_up is None:
            return float("inf")
        return float(np.exp(np.clip(self.best.log_posterior - self.runner_up.log_posterior, -700.0, 700.0)))

    @property
    def ambiguous(self) -> bool:
        return self.runner_up_odds < self.odds

    def odds_over(self, source: Source) -> float:
        """p(answer) / p(the hypothesis from ``source``) (1 where it was merged into the answer)."""
        other = next((h for h in self.hypotheses if h.source is source), self.best)
        return float(np.exp(np.clip(self.best.log_posterior - other.log_posterior, -700.0, 700.0)))


class Judge:
    """Built from the posterior that weighs each scan's placement and plain values: when two trajectories are
    one, and the stated odds."""

    def __init__(self, posterior: Posterior, same_m: float, same_rad: float, odds: float, align_m: float,
                 align_rad: float, align_radius_m: float, screened_scans: int):
        self.posterior, self.same_m, self.same_rad, self.odds = posterior, same_m, same_rad, odds
        self.align_m, self.align_rad, self.align_radius_m = align_m, align_rad, align_radius_m
        self.screened_scans = screened_scans

    @classmethod
    def from_config(cls, cfg, posterior: Posterior) -> "Judge":
        """An alternative's step is aligned within the front end's distinct radius: the resolution at which its
        fit was told from the pose taken; on the scans before it within ``posterior.radius_m`` of those after."""
        e, f = cfg.ending, cfg.front_end
        return cls(posterior, e.same_m, np.radians(e.same_deg), e.odds, f.distinct_m, np.radians(f.distinct_deg),
                   cfg.posterior.radius_m, e.screened_scans)

    def judge(self, candidates: list[tuple[Source, np.ndarray]], scans: dict[int, ScanPoints],
              known: list["Scored"] = ()) -> Ending:
        """The candidates (source, (P, 3) poses), those alike merged (the first kept), scored (or taken from
        ``known``, the same poses scored already) and ranked."""
        kept: list[tuple[Source, np.ndarray]] = []
        for source, poses in candidates:
            if not any(self._alike(poses, other) for _, other in kept):
                kept.append((source, poses))
        scored: list[Scored] = []
        for _, poses in kept:
            scored.append(next((s for s in known if s.poses is poses), None) or self.scan_terms(poses, scans, scored))
        hypotheses = [Hypothesis(source, poses, sum(s.terms, 0.0), self.posterior.trajectory_prior(poses))
                      for (source, poses), s in zip(kept, scored)]
        return Ending(sorted(hypotheses, key=lambda h: -h.log_posterior), self.odds)

    def shortlist(self, branches: list[tuple[int, np.ndarray]], answer: "Scored", scans: dict[int, ScanPoints],
                  count: int) -> list[np.ndarray]:
        """The ``count`` branches (fork scan, (P, 3) poses) of highest screened odds over the ``answer``
        (:meth:`screened`); each kept alternative then costs a scoring of every scan whose map it changes."""
        if len(branches) <= count:
            return [poses for _, poses in branches]
        answer_prior = self.posterior.trajectory_prior(answer.poses)
        odds = [self.screened(poses, answer, scans, answer_prior) for _, poses in branches]
        best = np.argsort(-np.array(odds), kind="stable")[:count]
        return [branches[i][1] for i in sorted(best)]

    def screened(self, poses: np.ndarray, answer: "Scored", scans: dict[int, ScanPoints],
                 answer_prior: float | None = None) -> float:
        """An estimate of a trajectory's log odds over the scored ``answer`` (its motion term ``answer_prior``,
        where known): the whole motion term's difference, and the scan terms' (:meth:`scan_terms`) on at most
        ``screened_scans`` of the scans it judges against another map than the answer does, evenly spread over
        them and scaled to their number (on the others the two score alike). The odds of a branch lie where the
        walk comes back to the places it saw before its fork, which the fork scan alone does not show."""
        if answer_prior is None:
            answer_prior = self.posterior.trajectory_prior(answer.poses)
        motion = self.posterior.trajectory_prior(poses) - answer_prior
        keys = sorted(scans)
        changed = [(i, k, around) for i, k, around, alike in self._judged(poses, keys, answer, scans) if not alike]
        if not changed:
            return motion
        picked = np.unique(np.linspace(0, len(changed) - 1, min(self.screened_scans, len(changed))).astype(int))
        gain = sum(self.posterior.scan_term(scans[k], poses[k], keys[:i], poses, scans, around) - answer.terms[i - 1]
                   for i, k, around in (changed[j] for j in picked))
        return len(changed) / len(picked) * gain + motion

    def excursions(self, branches: list[tuple[int, np.ndarray]], answer: np.ndarray) -> list[tuple[int, np.ndarray]]:
        """The branches (fork scan, (P, 3) poses) that return to the ``answer``: for each branch and each later scan
        k whose step from the branch into the answer's pose k is more probable under the motion prior than the
        answer's own step into it, by more than the stated odds, the branch up to k − 1 and the answer from k on
        (fork scan, poses). A decision the walk undid later (a wrong turn taken back by another, a kidnap that
        returns) is no branch that carries every later pose; there, the answer's step of return is a surprise
        that the excursion does not need."""
        area, own = extent_m2(answer), self.posterior.step_terms(answer)  # own[k − 1]: the answer's step k
        out = []
        for key, poses in branches:
            for k in range(max(key + 1, 2), len(answer)):
                back = self.posterior.step_term(k, poses[k - 1], answer[k], area, between(poses[k - 2], poses[k - 1]))
                if back > own[k - 1] + np.log(self.odds):
                    excursion = poses.copy()
                    excursion[k:] = answer[k:]
                    out.append((key, excursion))
        return out

    def aligned(self, key: int, poses: np.ndarray, scans: dict[int, ScanPoints]) -> np.ndarray:
        """A branch from scan ``key`` on with its jump refined: the scans from ``key`` on, one rigid body at the
        branch's poses, fitted onto the map of the scans before ``key`` within ``align_radius_m`` of them, within
        ``align_m`` and ``align_rad`` (least squares on the likelihood field,
        :func:`radioslam.slam.refine.refine_poses`). A decision's alternative step was fitted on the local map of
        its moment, a few degrees off at worst; carried to the walk's end, such an error lays every later scan
        beside the walls it comes back to, and the branch loses for its fit, not for its decision."""
        keys = sorted(scans)
        before, after = [m for m in keys if m < key], [m for m in keys if m >= key]
        if not before or not after:
            return poses
        gap = np.linalg.norm(poses[before][:, None, :2] - poses[after][None, :, :2], axis=2).min(axis=1)
        near = [m for m, d in zip(before, gap) if d <= self.align_radius_m]
        if not near:
            return poses
        grid, _ = map_grid(near, {m: poses[m] for m in near}, scans, self.posterior.grid)
        xy, normals = fused_points(after, {m: poses[m] for m in after}, scans, poses[key])
        fitted = refine_poses(grid, xy, normals, poses[key][None], self.align_m, self.align_rad)[0]
        out = poses.copy()
        out[key:] = compose(compose(fitted, inverse(poses[key])), poses[key:])
        return out

    def apart(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """(P,) the poses where two trajectories differ by more than ``same_m`` or ``same_rad``."""
        return (np.linalg.norm(a[:, :2] - b[:, :2], axis=1) > self.same_m) | \
            (np.abs(wrap_angle(a[:, 2] - b[:, 2])) > self.same_rad)

    def _alike(self, a: np.ndarray, b: np.ndarray) -> bool:
        return not self.apart(a, b).any()

    def scan_terms(self, poses: np.ndarray, scans: dict[int, ScanPoints], scored: list["Scored"] = ()) -> "Scored":
        """log p(scan k | T_k, the scans before k near T_k) (:meth:`Posterior.scan_term`) for each scan but the
        first (0 where none is near): each scan judged by the map from before it, never by the scans that
        follow it on its own branch (a wrong branch agrees with itself).

        A term is the same number on two trajectories wherever it is judged alike, and then taken from the one
        ``scored`` already: a scan's term depends on the poses up to its own alone, so where ``poses`` begin as
        a scored trajectory does, those scans' terms are its; and the likelihood of a scan against its map is
        unchanged by a rigid motion of both, so where ``poses`` go on as that trajectory carried rigidly (a
        rival branch: the answer with one step replaced), a scan judged against the same scans, all of them
        carried too, scores that trajectory's term. Only the scans whose map the branch changes are judged
        again: the fork's and those that come back near the scans before it."""
        keys = sorted(scans)
        other, shared = None, 0
        for candidate in scored:
            differ = np.flatnonzero(np.any(candidate.poses != poses, axis=1))
            if (same := int(differ[0]) if len(differ) else len(poses)) > shared:
                other, shared = candidate, same
        terms, near = [], []
        for i, k, around, alike in self._judged(poses, keys, other, scans):
            terms.append(other.terms[i - 1] if alike else
                         self.posterior.scan_term(scans[k], poses[k], keys[:i], poses, scans, around))
            near.append(around)
        return Scored(poses, terms, near)

    def _judged(self, poses: np.ndarray, keys: list[int], other: "Scored | None", scans: dict[int, ScanPoints]):
        """Per scan but the first: (its index i in ``keys``, its key, the scans before it near it, whether it
        scores as on ``other``, a scored trajectory). A scan's term depends on its own pose and those of the
        scans it is judged against alone, and not on one rigid motion of them all: it is ``other``'s wherever
        the same scans are near and the scan and each of them moved from ``other``'s poses by one rigid motion
        (none before the first pose where the two differ; a carried branch's jump after it; an excursion's,
        and none again from its return on)."""
        differ = np.flatnonzero(np.any(other.poses != poses, axis=1)) if other is not None else np.zeros(1, int)
        shared = int(differ[0]) if len(differ) else len(poses)
        moves = compose(poses, inverse(other.poses)) if other is not None else None  # each pose's move from other's
        for i, k in enumerate(keys[1:], start=1):
            if k < shared:
                yield i, k, other.near[i - 1], True
                continue
            around = self.posterior.nearby(poses[k], keys[:i], poses, scans[k].reach)
            yield i, k, around, other is not None and around == other.near[i - 1] and _one_motion(moves[[k] + around])

    def warning(self, best: Hypothesis, runner_up: Hypothesis, odds: float, status: list, odometry: bool) -> str:
        """One line: the two trajectories, their odds, where they part (the scans beyond ``same_m`` or
        ``same_rad`` of each other: there are some, or they would be one), why the scans cannot decide, and
        what would help."""
        apart = np.flatnonzero(self.apart(best.poses, runner_up.poses))
        there = [status[k] for k in apart]
        causes = []
        if ScanStatus.DEGENERATE in there:
            causes.append("nothing fixes the position along a corridor or wall")
        if ScanStatus.AMBIGUOUS in there:
            causes.append("places that look alike under a turn or a shift")
        if ScanStatus.RELOCALIZED in there:
            causes.append("a jump to another place of the map that the motion did not show")
        if ScanStatus.PREDICTED in there or ScanStatus.SKIPPED in there:
            causes.append("scans with too few echoes (open space, or nothing within range)")
        why = "; ".join(causes) or "the scans explain both about as well"
        helps = "a slower walk past the places where they part" if odometry else "odometry or a gyro (--odometry)"
        standing = (f"is within odds of 1 : {odds:.3g} of" if odds >= 1 else
                    f"scores {1 / odds:.3g} : 1 over")
        return (f"ambiguous trajectory: the {runner_up.source.value}'s {standing} the {best.source.value}'s "
                f"answer (scans {scan_ranges(apart.tolist())} differ): {why}; it is written as "
                f"trajectory_alternative.tum; what would help: {helps}")


@dataclass(frozen=True)
class Scored:
    """A trajectory's scan terms (one per scan but the first) and the scans each was judged against."""

    poses: np.ndarray
    terms: list[float]
    near: list[list[int]]


def _one_motion(moves: np.ndarray, tolerance: float = 1e-9) -> bool:
    """Whether rigid motions (M, 3) are one."""
    d = moves - moves[0]
    d[:, 2] = wrap_angle(d[:, 2])
    return bool(np.abs(d).max() <= tolerance)


def odometry_in_map_frame(odometry: np.ndarray, first_pose: np.ndarray) -> np.ndarray | None:
    """Full odometry poses (P, 3) carried rigidly so that the first lies at ``first_pose`` (None: a gyro's)."""
    if odometry is None or np.isnan(odometry[:, :2]).any():
        return None
    carry = compose(first_pose, inverse(odometry[0]))
    return compose(carry, odometry)
