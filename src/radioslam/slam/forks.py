"""Ambiguous scans decided by the scans after them against the map from before (issue #12, point 2).

In a room of right angles a scan turned by 90° or 180° still matches its local map, and in a
long hall a U-turn looks like walking on: the front end then finds rival poses, turned from
its choice, that score within the ambiguity margin (:mod:`radioslam.slam.front_end`), and
takes the one the motion prefers. When that choice is wrong every later scan agrees with the
wrong map, because the local map follows the chosen branch. So an ambiguous scan is
remembered as a *fork* for ``fork_memory`` scans, with the map from before it frozen, in the
spirit of max-mixture factors (Olson & Agarwal, "Inference on networks of mixtures for robust
robot mapping", IJRR 2013: keep the alternatives, let the data pick one):

1. each rival is the chosen branch carried by a rigid ``jump`` (recomputed from the latest
   estimates at every scan: the step into the fork scan replaced by the rival's);
2. at each later scan, the scan carried by each jump (and by each pair of open forks' jumps
   together: a second ambiguous turn inside the first's memory) is matched against the frozen
   map from before the fork (all of its scans, the latest ones too: one grid, branch and bound
   within the loop window, the loop closer's score and degeneracy tests,
   :meth:`radioslam.slam.loop_closer.LoopCloser.matched_in`), and so is the chosen branch's
   scan; each branch's best match since the fork is remembered (a rival branch walking back into
   that map matches it at once, while the evidence against the chosen branch piles up only over
   the scans after);
3. the fork is decided for the rival when all of these hold:
   - the rival's best match, a *rival loop*, has weight ≥ ``fork_weight`` and scores
     ``fork_gain`` better than the chosen branch's best match with that map (none: 0);
   - the chosen branch is *contradicted*: ≥ ``fork_contradicted`` of its points since the fork
     lie on space the frozen map saw through, significantly more of them than the rival branch's
     (a sign test at ``fork_significance``: radio ghosts land there on either branch, the true one
     too). An exploring branch closes no loop with the old map while a
     rival in its mapped part may (a square room's 90° twin): a missing loop is no evidence
     against the choice, a wall where the terminal once looked through is. Where the room looks
     alike under the jump (a rectangle turned by 180°) both branches put their points on walls
     alike and the test keeps the choice; where it looks alike only near the turn (a straight
     hall turned about its centre line) the scans after it, walking on, tell the branches apart.

   Or, without a rival loop that decides (none, or none ``fork_gain`` better), when the
   contradiction is overwhelming: the chosen branch's points on that free space against the
   rival's pass the sign test at ``fork_significance``². An exploring rival closes no loop with
   the old map: a corner taken for its corridor folded back onto itself matches the old map as well
   as the corner does (whose new walls the map has not seen), and puts the next scans' points where
   the terminal walked.

   Each branch's points are counted where that map places the branch: its scans since the fork
   together, as one rigid scan, matched against it (:meth:`Forks._placed`): a rival from where
   its fork scan's candidate put it, which may be decimetres off, the chosen branch from where
   its estimates drifted (only once they are contradicted there).

   Then the step into the fork scan is replaced by the rival's, which carries every later pose
   by the placed jump (:meth:`radioslam.slam.back_end.BackEnd.switch`), and the rival loop, if
   any, joins the graph.

Both branches are judged by the map from before the fork, never by their own scans: a wrong
branch builds a local map that agrees with itself.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.special import betainc

from radioslam.slam.branch_bound import BranchAndBound
from radioslam.slam.config import LoopClosureConfig
from radioslam.slam.correlative import candidate_likelihoods
from radioslam.slam.front_end import Step
from radioslam.slam.grid import LikelihoodGrid
from radioslam.slam.loop_closer import LoopCloser, LoopClosure
from radioslam.slam.rivals import Cause, Rivals
from radioslam.slam.scan_matcher import ScanMatcher, loop_matcher
from radioslam.slam.scan_points import ScanPoints, fused_points
from radioslam.slam.se2 import between, compose, inverse, wrap_angle
from radioslam.slam.status import ScanStatus


@dataclass(frozen=True)
class Fork:
    """An ambiguous scan and its turned rivals, each as its step from the pose before it, with the
    map from before it, as it stood then (what both branches are judged by)."""

    key: int
    rivals: np.ndarray  # (R, 3) each rival's pose in the frame of pose key − 1
    grid: LikelihoodGrid  # the map of the scans before it
    keys: tuple[int, ...]  # those scans
    levels: int  # the levels of its branch-and-bound pyramid

    @cached_property
    def pyramid(self) -> BranchAndBound:
        """Branch and bound over the map from before the fork (built once, at its first use)."""
        return BranchAndBound(self.grid, self.levels)

    def scans_since(self, k: int, scans: dict[int, ScanPoints]) -> list[int]:
        """The scans of ``scans`` from the fork's to k (a skipped scan has none)."""
        return [m for m in range(self.key, k + 1) if m in scans]

    def jumps(self, estimates: dict[int, np.ndarray]) -> np.ndarray:
        """(R, 3) world transforms carrying the chosen branch (latest estimates) onto each rival's."""
        return np.array([compose(compose(estimates[self.key - 1], rival), inverse(estimates[self.key]))
                         for rival in self.rivals])


def placed_switches(switches: list[tuple[int, np.ndarray]], placed: np.ndarray) -> list[tuple[int, np.ndarray]]:
    """``switches`` (latest first) with the latest jump replaced so that all of them together carry the
    chosen branch by the jump ``placed``."""
    earlier = np.zeros(3)
    for _, jump in reversed(switches[1:]):  # the earlier forks' jumps, applied after the latest one's
        earlier = compose(earlier, jump)
    return [(switches[0][0], compose(inverse(earlier), placed))] + switches[1:]


@dataclass(frozen=True)
class Decision:
    switches: list[tuple[int, np.ndarray]]  # (ambiguous scan, jump onto its rival), latest first
    loop: LoopClosure | None  # the rival loop that decided it (relative to the rival branch); None: contradiction alone

    @property
    def fork(self) -> int:
        """The earliest ambiguous scan whose rival is taken."""
        return min(key for key, _ in self.switches)


class Forks:
    """Remembers forks and tests their rivals; ``observe`` once per scan, after its loops."""

    def __init__(self, cfg: LoopClosureConfig, matcher: ScanMatcher, rivals: Rivals):
        self.cfg, self.matcher = cfg, matcher  # the loop closer's: a branch is placed and matched as a loop is
        self.turn_rad = matcher.options.distinct_rad  # rivals turned at least this much from the choice fork
        self.rivals = rivals  # where every turned rival is kept for the ending, whether a fork opens or not
        self.open: list[Fork] = []
        self.chosen_scores: dict[int, float] = {}  # per fork: the chosen branch's best match score since it
        self.rival_loops: dict[tuple, LoopClosure] = {}  # per rival branch: its best loop since the fork

    @classmethod
    def from_config(cls, cfg, rivals: Rivals) -> "Forks":
        return cls(cfg.loop_closure, loop_matcher(cfg), rivals)

    def turned(self, step: Step) -> np.ndarray:
        """(R, 3) the rivals of ``step`` turned at least ``turn_rad`` from its pose: those a fork remembers."""
        return step.rivals[np.abs(wrap_angle(step.rivals[:, 2] - step.pose[2])) >= self.turn_rad]

    def remember(self, k: int, step: Step, estimates: dict[int, np.ndarray], loop_closer: LoopCloser) -> None:
        """Scan k's turned rivals, if any (once pose k − 1 and k are in ``estimates``), with the map before
        scan k."""
        self.open = [f for f in self.open if k - f.key <= self.cfg.fork_memory]
        if k - 1 not in estimates or not len(step.rivals):
            return
        turned = self.turned(step)
        self.rivals.keep_poses(k, estimates[k - 1], turned, Cause.TURNED)
        if not self.cfg.fork_limit:
            return
        keys = loop_closer.keyframes.before(k, before=k)
        if not len(turned) or not keys:
            return
        while len(self.open) >= self.cfg.fork_limit:
            # room for the new fork: the oldest one goes, unless the map from before it already contradicts its
            # chosen branch (a wrong branch's trouble opens forks of its own, which must not push out the fork
            # that can undo it); then the oldest uncontradicted one, and when every one is contradicted, the
            # latest: the later ones inherit an earlier one's wrong branch (their chosen branches are
            # contradicted by it alone)
            contested = [self._contradicted(*self._chosen_on_free(f, k - 1, estimates, loop_closer.keyframes.points))
                         for f in self.open]
            del self.open[contested.index(False) if False in contested else -1]
        self.open.append(Fork(k, np.array([between(estimates[k - 1], r) for r in turned]),
                              loop_closer.whole_map(keys, estimates)[0], tuple(keys), self.matcher.options.levels))

    @staticmethod
    def _on_free(fork: Fork, k: int, estimates: dict[int, np.ndarray], scans: dict[int, ScanPoints],
                 jump: np.ndarray | None = None) -> tuple[int, int]:
        """How many of the points of scans fork … k (at their latest poses, carried by ``jump`` if given:
        a rival's branch) lie on space the map from before the fork saw through, and of how many."""
        keys = fork.scans_since(k, scans)
        on_free = [candidate_likelihoods(fork.grid, scans[m].xy, scans[m].normals,
                                         estimates[m] if jump is None else compose(jump, estimates[m]),
                                         np.zeros(1), np.zeros(1, int)).ravel() < 0 for m in keys]
        return (int(np.count_nonzero(np.concatenate(on_free))), sum(map(len, on_free))) if on_free else (0, 0)

    def _contradicted(self, on_free: int, points: int) -> bool:
        """Whether the chosen branch put at least ``fork_contradicted`` of its ``points`` since the fork
        (``on_free`` of them, :meth:`_on_free`) on space the map from before the fork saw through:
        evidence against the branch, not only for a rival. An exploring branch closes no loop with that
        map, and a rival in the mapped part of a symmetric room does; only a wrong branch puts walls where
        the terminal once walked or looked through. Counted over the whole stretch, not per scan."""
        return points > 0 and on_free >= self.cfg.fork_contradicted * points

    def _contradicted_more(self, chosen: int, rival: int, significance: float | None = None) -> bool:
        """Whether the chosen branch has significantly more points on that free space (``chosen``) than the
        rival's (``rival``; a sign test): radio ghosts land on free space on either branch alike, a wrong
        branch's walls add to its own count. If the choice is right, the chosen branch's share of the
        T points on free space of both is at most Binomial(T, ½); the rival is evidenced when
        P(share ≥ observed) ≤ ``fork_significance`` (15 against 0: 3·10⁻⁵; a ghost a scan, 6 against 2:
        0.14)."""
        level = self.cfg.fork_significance if significance is None else significance
        # P(share ≥ chosen) = I_½(chosen, rival + 1), the regularized incomplete beta function: bit for bit
        # scipy.stats.binom.sf (whose import costs 0.3-0.5 s a command), in constant time
        return chosen > 0 and float(betainc(chosen, rival + 1, 0.5)) <= level

    def _placed(self, fork: Fork, k: int, estimates: dict[int, np.ndarray], scans: dict[int, ScanPoints],
                jump: np.ndarray) -> np.ndarray:
        """The jump that carries a branch (the chosen one carried by ``jump``) to where the map from before
        ``fork`` places it: the branch's scans fork … k together, as one rigid scan, matched against that
        map within ± ``fork_place_m``, ``fork_place_deg`` (Olson 2009's correlative search). A branch is a
        rigid hypothesis whose place is not known to the centimetre: a rival is where its fork scan's
        candidate put it, the chosen branch where its estimates drifted, either of them decimetres off
        along or across a corridor, where unplaced it puts many points on the map's free space and placed
        none."""
        keys = fork.scans_since(k, scans)
        if not keys:
            return jump
        carried = {m: compose(jump, estimates[m]) for m in keys}
        xy, normals = fused_points(keys, carried, scans, carried[k])
        match = self.matcher.response(fork.grid, xy, normals, carried[k], self.cfg.fork_place_m,
                                      np.radians(self.cfg.fork_place_deg))
        return compose(match.pose, inverse(estimates[k]))

    def _chosen_on_free(self, fork: Fork, k: int, estimates: dict[int, np.ndarray],
                        scans: dict[int, ScanPoints]) -> tuple[int, int]:
        """:meth:`_on_free` of the chosen branch since ``fork``, where the map from before places it
        (:meth:`_placed`), as each rival branch is counted where it places that one; placed only when its
        estimates are contradicted (placing moves a branch onto the map's walls, off its free space)."""
        counted = self._on_free(fork, k, estimates, scans)
        if not self._contradicted(*counted):
            return counted
        return self._on_free(fork, k, estimates, scans, self._placed(fork, k, estimates, scans, np.zeros(3)))

    def contested(self, k: int, estimates: dict[int, np.ndarray], loop_closer: LoopCloser, step: Step,
                  points: ScanPoints) -> bool:
        """Whether an open fork's chosen branch, scan k at its ``step`` with its ``points`` included, put
        ``fork_contradicted`` of its points since the fork on space the map from before saw through: a scan
        k that contradicts its local map is then that fork's to decide, not a relocalization's (a fold
        running into the map's free space: relocalized, the scan would be placed on the fold's turned
        twin)."""
        estimates, scans = {**estimates, k: step.pose}, {**loop_closer.keyframes.points, k: points}
        return any(self._contradicted(*self._chosen_on_free(f, k, estimates, scans)) for f in self.open
                   if f.key < k)

    def hypotheses(self, k: int, estimates: dict[int, np.ndarray]):
        """(name, fork, switches, jump) for every rival branch to test at scan k: each open fork's rivals,
        and each pair of forks' rivals together (a second ambiguous turn inside the first's memory: in the
        first's rival branch the second choice may be wrong too). ``name`` names the branch across scans,
        ``jump`` carries scan k's pose; the switches are latest first."""
        forks = [f for f in self.open if f.key < k]
        for fork in forks:
            for i, jump in enumerate(fork.jumps(estimates)):
                yield (fork.key, i), fork, [(fork.key, jump)], jump
        for i, first in enumerate(forks):
            for second in forks[i + 1:]:
                for a, jump_a in enumerate(first.jumps(estimates)):
                    for b, jump_b in enumerate(second.jumps(estimates)):
                        yield (first.key, a, second.key, b), first, [(second.key, jump_b), (first.key, jump_a)], \
                            compose(jump_a, jump_b)

    def observe(self, k: int, status: ScanStatus, estimates: dict[int, np.ndarray],
                loop_closer: LoopCloser, last: bool = False) -> Decision | None:
        """Scan k; the decision of a fork (or two) for its rival, else None. Each branch's best match with
        the map from before the fork is remembered from scan to scan: a rival branch walking back into that
        map matches it at once, while the chosen branch's walls on its free space pile up only over the
        scans after.

        At the walk's ``last`` scan no more evidence will come, so the contradiction alone decides at the
        plain significance, not its square: the square guards a decision that is tested again at every
        scan, and could wait for the next, against the many looks (a sequential test's truncation decides
        on the evidence there is): a fold taken a few scans before the end gathers a contradiction near
        the squared level, which a micrometre of range would otherwise decide."""
        if status not in (ScanStatus.MATCHED, ScanStatus.AMBIGUOUS):
            return None
        open_keys = {f.key for f in self.open}
        self.chosen_scores = {key: s for key, s in self.chosen_scores.items() if key in open_keys}
        self.rival_loops = {name: lc for name, lc in self.rival_loops.items() if name[0] in open_keys}
        chosen_on_free: dict[int, tuple[int, int]] = {}  # per fork: the chosen branch's (on free space, points)
        unlooped = []  # (rival's points on free space, fork, switches) of contradicted forks without a rival loop
        for name, fork, switches, jump in self.hypotheses(k, estimates):
            if fork.key not in chosen_on_free:
                chosen = loop_closer.matched_in(fork.pyramid, k, estimates[k], fork.keys, estimates)
                self.chosen_scores[fork.key] = max(self.chosen_scores.get(fork.key, 0.0),
                                                  0.0 if chosen is None else chosen.score)
                chosen_on_free[fork.key] = self._chosen_on_free(fork, k, estimates, loop_closer.keyframes.points)
            found = loop_closer.matched_in(fork.pyramid, k, compose(jump, estimates[k]), fork.keys, estimates)
            if found is not None and found.weight >= self.cfg.fork_weight and \
                    (name not in self.rival_loops or found.score > self.rival_loops[name].score):
                self.rival_loops[name] = found
            on_free, points = chosen_on_free[fork.key]
            if not self._contradicted(on_free, points):
                continue
            best = self.rival_loops.get(name)
            # no rival loop: an exploring rival closes none (a corridor's corner taken for the corridor folded
            # back onto itself); the contradiction alone decides, at the square of the significance
            looped = best is not None and best.score > (1.0 + self.cfg.fork_gain) * self.chosen_scores[fork.key]
            level = self.cfg.fork_significance ** (1 if looped or last else 2)
            if not self._contradicted_more(on_free, 0, level):
                continue  # too few of the chosen branch's points on free space even against none of the rival's
            placed = self._placed(fork, k, estimates, loop_closer.keyframes.points, jump)
            rival_on_free = self._on_free(fork, k, estimates, loop_closer.keyframes.points, placed)[0]
            switches = placed_switches(switches, placed)
            if not self._contradicted_more(on_free, rival_on_free, level):
                continue  # the chosen branch disagrees with the map from before the fork no more than the rival
            if not looped:
                unlooped.append((rival_on_free, fork.key, fork, switches))
                continue
            self.open = [f for f in self.open if f.key < fork.key]
            return Decision(switches, best)
        if unlooped:  # the rival the map from before contradicts least
            _, _, fork, switches = min(unlooped, key=lambda u: u[:2])
            self.open = [f for f in self.open if f.key < fork.key]
            return Decision(switches, None)
        return None
