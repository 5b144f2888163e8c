"""Ambiguous scans decided by the loops the scans after them close (issue #12, point 2):
the fork's decision rule, the back end's switch to a rival branch, and a hall U-turn."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from radioslam.slam import RadioSlam, ScanStatus, SlamConfig
from radioslam.slam.back_end import BackEnd
from radioslam.slam.forks import Forks
from radioslam.slam.front_end import Step
from radioslam.slam.loop_closer import LoopClosure
from radioslam.slam.rivals import Rivals
from radioslam.slam.se2 import between, compose, inverse, pose_covariance, transform_points, wrap_angle

COV = pose_covariance(0.02, 0.3)


def walk(n: int, turn_at: int | None = None) -> np.ndarray:
    """Poses 1 m apart along x, turned by 180° on the spot at ``turn_at`` and walked back."""
    poses, pose = [], np.zeros(3)
    for k in range(n):
        if k:
            pose = compose(pose, [0.0, 0.0, np.pi] if k == turn_at else [1.0, 0.0, 0.0])
        poses.append(pose)
    return np.array(poses)


class StubKeyframes:
    """Every scan before ``before`` is a keyframe, with no points: every branch is placed where it is
    (:meth:`Forks._placed`)."""

    points: dict = {}

    @staticmethod
    def before(k, before=None):
        return list(range(before))


class StubCloser:
    """The loop closer's side of a fork: a match with the map from before it near ``place`` (tied to
    scan 0) of ``score`` for the rival branch, and ``chosen`` (a score) for the chosen branch."""

    def __init__(self, place: np.ndarray, score: float, chosen: float = 0.0):
        self.place, self.score, self.chosen, self.asked = place, score, chosen, []
        self.keyframes = StubKeyframes()

    def matched_in(self, matcher, k, pose, keys, estimates):
        self.asked.append((k, pose, tuple(keys)))
        if np.allclose(pose, estimates[k]):  # the chosen branch
            return LoopClosure(0, k, between(estimates[0], pose), COV, self.chosen, 1.0) if self.chosen else None
        if np.linalg.norm(pose[:2] - self.place[:2]) > 0.5:
            return None
        return LoopClosure(0, k, between(estimates[0], pose), COV, self.score, 1.0)

    def whole_map(self, keys, estimates):
        from radioslam.slam.grid import LikelihoodGrid

        wall = np.column_stack([np.full(5, 3.0), np.linspace(-1, 1, 5)])
        return LikelihoodGrid.from_points(wall, 0.1, 0.05, 1.0, np.full(5, np.pi), np.radians(1.0), 0.5), None


def chosen_branch(jump: np.ndarray | None) -> bool:
    """Whether ``_on_free`` was asked about the chosen branch: at its estimates, or placed by a loop of
    :class:`StubCloser`, which places it there too."""
    return jump is None or np.allclose(jump, 0.0)


def fork_at_scan_3(closer: StubCloser, contradicted: bool = True, on_free: int = 10, last: bool = False):
    """Scan 3 is ambiguous (the chosen pose walked on, the rival turned by 180°); scan 5 (the walk's
    ``last`` or not) is then observed, the chosen branch ``contradicted`` by the map before the fork
    (``on_free`` of its 400 points on its free space, the rival's none) or not. Returns the decision and
    the estimates."""
    forks = Forks.from_config(SlamConfig(), Rivals())
    forks._on_free = lambda fork, k, estimates, loop_closer, jump=None: \
        (on_free if contradicted and chosen_branch(jump) else 0, 400)
    estimates = {k: p for k, p in enumerate(walk(6))}  # the chosen branch: straight on
    rival = compose(estimates[2], [0.0, 0.0, np.pi])
    for k in range(6):
        rivals = rival[None] if k == 3 else np.zeros((0, 3))
        forks.remember(k, Step(estimates[k], COV, ScanStatus.AMBIGUOUS if k == 3 else ScanStatus.MATCHED,
                               0.6, rivals), {m: estimates[m] for m in range(k + 1)}, closer)
    decided = forks.observe(5, ScanStatus.MATCHED, estimates, closer, last=last)
    return decided, estimates


def test_a_rival_branch_that_closes_a_loop_the_chosen_one_does_not_is_taken():
    """The rival branch (turned back at scan 3) puts scan 5 at x = 0, next to the walk's start: a
    loop there decides the fork, with the jump that carries the chosen branch onto the rival's."""
    truth_5 = compose(compose(walk(3)[2], [0.0, 0.0, np.pi]), [2.0, 0.0, 0.0])  # back at x = 0
    closer = StubCloser(truth_5, 0.6)
    decided, estimates = fork_at_scan_3(closer)
    assert decided is not None and decided.fork == 3 and len(decided.switches) == 1
    np.testing.assert_allclose(compose(decided.switches[0][1], estimates[5]), truth_5, atol=1e-9)
    assert all(keys == (0, 1, 2) for _, _, keys in closer.asked)  # only the map before it


def placing(forks: Forks, rival_place: np.ndarray | None = None, chosen_shift: np.ndarray | None = None):
    """``forks._placed`` as the map from before a fork would answer: the rival branch's scan k carried to
    ``rival_place``, the chosen branch's shifted by ``chosen_shift`` (in its own frame), else as they are."""
    def placed(fork, k, estimates, scans, jump):
        chosen = np.allclose(jump, 0.0)
        if chosen and chosen_shift is not None:
            return compose(compose(estimates[k], chosen_shift), inverse(estimates[k]))
        if not chosen and rival_place is not None:
            return compose(rival_place, inverse(estimates[k]))
        return jump

    forks._placed = placed


def ambiguous_walk(forks: Forks, closer: StubCloser) -> dict[int, np.ndarray]:
    """:func:`walk` (6 scans) remembered by ``forks``, scan 3 ambiguous with its rival turned back by 180°."""
    estimates = {k: p for k, p in enumerate(walk(6))}
    for k in range(6):
        forks.remember(k, Step(estimates[k], COV, ScanStatus.AMBIGUOUS if k == 3 else ScanStatus.MATCHED, 0.6,
                               compose(estimates[2], [0.0, 0.0, np.pi])[None] if k == 3 else np.zeros((0, 3))),
                       {m: estimates[m] for m in range(k + 1)}, closer)
    return estimates


def test_the_rival_branch_is_counted_and_taken_where_the_map_places_it_not_where_its_fork_scan_put_it():
    """narrow-corridor seed 2's fourth corner: the rival, the motion's choice among the candidates, sat
    0.4 m along the corridor from the truth; carried by its own jump its branch put 51 points on the old
    map's free space against the folded choice's 15, placed by that map none. Both the count and the
    switch take the branch where the map places it."""
    slid = compose(compose(walk(3)[2], [0.0, 0.0, np.pi]), [2.0, 0.0, 0.0])  # scan 5 by the rival's jump
    place = compose(slid, [0.4, 0.0, 0.0])
    counted = []
    forks = Forks.from_config(SlamConfig(), Rivals())

    def on_free(fork, k, estimates, scans, jump=None):
        carried = None if jump is None else compose(jump, estimates[k])
        counted.append(carried)
        return (40 if chosen_branch(jump) else 0 if np.allclose(carried, place) else 80, 400)

    forks._on_free = on_free
    placing(forks, rival_place=place)
    closer = StubCloser(slid, 0.6)
    estimates = ambiguous_walk(forks, closer)
    decided = forks.observe(5, ScanStatus.MATCHED, estimates, closer)
    assert decided is not None and decided.fork == 3
    assert any(c is not None and np.allclose(c, place) for c in counted)
    np.testing.assert_allclose(compose(decided.switches[0][1], estimates[5]), place, atol=1e-9)
    placing(forks)  # counted where its jump puts it (80 against 40), the rival would not be taken
    forks.open, forks.rival_loops = [], {}
    assert forks.observe(5, ScanStatus.MATCHED, ambiguous_walk(forks, closer), closer) is None


def test_a_branch_is_placed_where_its_scans_together_fit_the_map_from_before_the_fork():
    """:meth:`Forks._placed` on real walls: a corner mapped before the fork, and a branch whose three scans
    of it are carried 0.3 m and 2° off; the match of the three together puts them back within a cell."""
    from radioslam.slam.forks import Fork
    from radioslam.slam.grid import LikelihoodGrid
    from radioslam.slam.scan_points import ScanPoints

    along = np.linspace(-3.0, 3.0, 61)
    walls = np.vstack([np.column_stack([along, np.full(61, 1.2)]), np.column_stack([np.full(61, 3.0), along])])
    normals = np.concatenate([np.full(61, -np.pi / 2), np.full(61, np.pi)])  # facing the terminal at the origin
    grid = LikelihoodGrid.from_points(walls, 0.05, 0.05, 1.0, normals, np.radians(10.0), 0.5)
    fork = Fork(1, np.zeros((1, 3)), grid, (0,), 4)
    truth = {m: np.array([0.5 * m, 0.0, 0.1 * m]) for m in (1, 2, 3)}
    scans = {}
    for m, pose in truth.items():
        local = transform_points(inverse(pose), walls[::3])
        scans[m] = ScanPoints(local, normals[::3] - pose[2], np.zeros((0, 2)))
    off = np.array([0.3, -0.2, np.radians(2.0)])
    estimates = {m: compose(off, pose) for m, pose in truth.items()}  # the branch as its estimates put it
    placed = Forks.from_config(SlamConfig(), Rivals())._placed(fork, 3, estimates, scans, np.zeros(3))
    for m in truth:
        error = compose(placed, estimates[m]) - truth[m]
        assert np.all(np.abs(error[:2]) <= 0.05) and abs(wrap_angle(error[2])) <= np.radians(0.5)


def test_a_new_fork_evicts_the_oldest_fork_the_map_does_not_contradict_yet():
    """At ``fork_limit`` open forks a new one takes the place of the oldest, unless the map from before
    that one already contradicts its chosen branch (narrow-corridor seed 8: the second corner's fold runs
    into the first corner and opens four forks of its own, which evicted the fork that was to be
    decided); then the oldest uncontradicted one goes, and the latest when all are contradicted (forks
    opened on a wrong branch are contradicted by its error: narrow-corridor's fourth corner)."""
    def remembered(contradicted: set[int]) -> list[int]:
        forks = Forks.from_config(SlamConfig(), Rivals())
        forks._on_free = lambda fork, k, estimates, loop_closer, jump=None: \
            (40 if fork.key in contradicted else 0, 400)
        estimates = {k: p for k, p in enumerate(walk(12))}
        closer = StubCloser(np.full(3, 99.0), 0.6)
        for k in range(12):
            ambiguous = k in (3, 5, 7, 9)
            forks.remember(k, Step(estimates[k], COV, ScanStatus.AMBIGUOUS if ambiguous else ScanStatus.MATCHED, 0.6,
                                   compose(estimates[k - 1], [0, 0, np.pi])[None] if ambiguous else np.zeros((0, 3))),
                           {m: estimates[m] for m in range(k + 1)}, closer)
        return [f.key for f in forks.open]

    assert SlamConfig().loop_closure.fork_limit == 3
    assert remembered(set()) == [5, 7, 9]
    assert remembered({3}) == [3, 7, 9]
    assert remembered({3, 5, 7}) == [3, 5, 9]


def test_the_chosen_branch_is_judged_where_the_map_places_it_too():
    """narrow-corridor seed 9: at its estimates the true (chosen) branch put 26 of 162 points on the old
    map's free space, 0.25 m across the corridor from where that map places it (none there); its rival,
    placed, none. Judging the rival where the map puts it and the choice where its estimates do took the
    wrong branch; judged alike, nothing contradicts the choice, and no fork contests a suspicious scan."""
    truth_5 = compose(compose(walk(3)[2], [0.0, 0.0, np.pi]), [2.0, 0.0, 0.0])
    closer = StubCloser(truth_5, 0.9, 0.6)
    forks = Forks.from_config(SlamConfig(), Rivals())
    forks._on_free = lambda fork, k, estimates, scans, jump=None: (40 if chosen_branch(jump) else 0, 400)
    placing(forks, chosen_shift=np.array([0.0, 0.25, 0.0]))
    estimates = ambiguous_walk(forks, closer)
    assert forks.observe(5, ScanStatus.MATCHED, estimates, closer) is None
    assert not forks.contested(5, estimates, closer, Step(estimates[5], COV, ScanStatus.MATCHED, 0.6), None)
    placing(forks)  # where its estimates put it, the choice is contradicted
    assert forks.contested(5, estimates, closer, Step(estimates[5], COV, ScanStatus.MATCHED, 0.6), None)
    assert forks.observe(5, ScanStatus.MATCHED, estimates, closer) is not None


def test_placed_switches_carry_the_latest_poses_by_the_placed_jump_in_all():
    """Two forks' switches, latest first, as :meth:`BackEnd.switch` applies them: with the latest jump
    replaced, the poses after both forks are carried by the placed jump, the earlier fork's own."""
    from radioslam.slam.forks import placed_switches

    rng = np.random.default_rng(3)
    pose, placed = rng.normal(size=3), rng.normal(size=3)
    jump_2, jump_5 = rng.normal(size=3), rng.normal(size=3)
    switches = placed_switches([(5, jump_5), (2, jump_2)], placed)
    assert [key for key, _ in switches] == [5, 2] and np.allclose(switches[1][1], jump_2)
    carried = pose
    for _, jump in switches:  # the latest first, then the earlier one on top
        carried = compose(jump, carried)
    np.testing.assert_allclose(carried, compose(placed, pose), atol=1e-9)
    np.testing.assert_allclose(placed_switches([(2, jump_2)], placed)[0][1], placed, atol=1e-12)


def test_the_choice_stands_when_the_chosen_branch_closes_as_good_a_loop_or_nothing_contradicts_it():
    """A rival's match alone is not enough: the chosen branch matching the map from before the fork as
    well (within fork_gain), or a chosen branch nothing contradicts (a room that looks alike under the
    jump: both branches on its walls), keep the choice."""
    truth_5 = compose(compose(walk(3)[2], [0.0, 0.0, np.pi]), [2.0, 0.0, 0.0])
    assert fork_at_scan_3(StubCloser(truth_5, 0.6, 0.55))[0] is None  # within fork_gain of the rival's 0.6
    assert fork_at_scan_3(StubCloser(truth_5, 0.6), contradicted=False)[0] is None  # nothing against the choice
    assert fork_at_scan_3(StubCloser(truth_5, 0.2))[0] is not None  # weight 1: score alone does not gate
    # 10 of 400 against none (P = 1e-3) needs a rival loop; 40 against none (P = 1e-12, beyond the
    # significance squared) decides alone: a walk's first corner taken for its corridor folded back
    # onto itself matches the map from before as well as the corner, which explores and closes no loop
    assert fork_at_scan_3(StubCloser(truth_5, 0.6, 0.55), on_free=40)[0] is not None
    assert fork_at_scan_3(StubCloser(np.full(3, 99.0), 0.6), on_free=40)[0] is not None  # no rival loop at all
    assert fork_at_scan_3(StubCloser(np.full(3, 99.0), 0.6), on_free=10)[0] is None


def test_at_the_walks_last_scan_the_contradiction_alone_decides_at_the_plain_significance():
    """No later scan can add evidence: without a rival loop, 7 of 400 points on the map's free space
    against none (P = 1/128: beyond the significance squared, within it) decide at the last scan, and
    not at an earlier one; 5 against none (P = 1/32) do not, nor does a choice nothing contradicts."""
    nowhere = StubCloser(np.full(3, 99.0), 0.6)  # the rival closes no loop
    assert fork_at_scan_3(nowhere, on_free=7)[0] is None
    decided, _ = fork_at_scan_3(nowhere, on_free=7, last=True)
    assert decided is not None and decided.fork == 3 and decided.loop is None
    assert fork_at_scan_3(nowhere, on_free=5, last=True)[0] is None
    assert fork_at_scan_3(nowhere, contradicted=False, last=True)[0] is None


def test_a_branch_is_contradicted_by_walls_where_the_map_before_the_fork_saw_through():
    """Points of the chosen branch on cells the map before the fork saw through (a specular line from
    the terminal to a wall) count against it; the same points on the wall do not."""
    from types import SimpleNamespace

    from radioslam.slam.forks import Fork
    from radioslam.slam.grid import LikelihoodGrid

    wall = np.column_stack([np.full(41, 5.0), np.linspace(-2, 2, 41)])
    seen_through = np.column_stack([np.linspace(0.0, 4.5, 91), np.zeros(91)])  # the line to the wall's foot
    grid = LikelihoodGrid.from_points(wall, 0.05, 0.05, 5.5, np.full(41, np.pi), np.radians(1.0), 1.5,
                                      seen_through, 1.0)
    fork = Fork(1, np.zeros((1, 3)), grid, (0,), 4)
    across = np.column_stack([np.full(20, 2.0), np.linspace(-0.5, 0.5, 20)])  # a wall across the line
    forks = Forks.from_config(SlamConfig(), Rivals())
    scans = {1: SimpleNamespace(xy=across, normals=np.full(20, np.nan))}
    assert forks._contradicted(*forks._on_free(fork, 1, {1: np.zeros(3)}, scans))
    assert not forks._contradicted(*forks._on_free(fork, 1, {1: np.array([3.0, 0.0, 0.0])}, scans))  # on the wall


def test_the_chosen_branch_must_be_contradicted_significantly_more_than_the_rivals():
    """A sign test on the points each branch puts on the frozen map's free space: 15 against 0 is
    evidence (a wrong wall, hall-random-13), 6 against 2 (a ghost a scan, shelf-hall seed 2) and
    3 against 3 are not; the evidence grows with the counts, not with one point's place."""
    forks = Forks.from_config(SlamConfig(), Rivals())
    decided = forks._contradicted_more

    assert decided(15, 0) and decided(7, 0) and decided(12, 2)
    assert not decided(6, 2) and not decided(3, 3) and not decided(0, 0) and not decided(6, 0)
    assert [decided(c, 2) for c in range(20)] == sorted(decided(c, 2) for c in range(20))  # monotone in the count


def test_switching_carries_every_pose_since_the_fork_and_the_graph_keeps_the_rivals_step():
    """Poses before the fork stay, the fork and every later pose are carried by the jump, the
    graph's step into the fork measures the rival's (a turn on the spot), and the front-end chain
    follows it."""
    cfg = SlamConfig()
    back_end = BackEnd.from_config(cfg)
    poses = walk(6)
    for k, pose in enumerate(poses):
        back_end.add(k, Step(pose, COV, ScanStatus.MATCHED, 0.6))
    jump = compose(compose(poses[2], [0.0, 0.0, np.pi]), inverse(poses[3]))  # carries pose 3 onto the rival
    before = {k: p.copy() for k, p in back_end.estimates.items()}
    back_end.switch([(3, jump)])
    for k in range(3):
        np.testing.assert_allclose(back_end.estimates[k], before[k], atol=1e-6)
    for k in range(3, 6):
        np.testing.assert_allclose(back_end.estimates[k], compose(jump, before[k]), atol=1e-6)
    # the step into the fork is now the rival's turn on the spot; the chain (front end only) follows
    np.testing.assert_allclose(between(back_end.estimates[2], back_end.estimates[3]), [0, 0, np.pi], atol=1e-6)
    np.testing.assert_allclose(back_end.chain[5], back_end.estimates[5], atol=1e-6)


def test_a_u_turn_in_a_hall_taken_for_walking_on_is_found_by_the_loop_it_closes(monkeypatch):
    """A 28 m hall walked at a slant, U-turns between two scans near its centre line. Where the
    front end takes one for walking on (the motion deciding among candidates within the margin, as it
    did before ``front_end.choose`` let a turn the scan shows clearly win), the walk back over the
    mapped hall runs metres off; the rival's branch closes a loop with the map from before the turn,
    and its points since agree with that map where the chosen branch's land on space it saw through:
    taken, the walk is at its true place. A straight hall looks alike under a U-turn about its centre
    line, so only the sign test, not the map's look, decides. With ``choose`` the front end takes the
    U-turns itself."""
    from test_slam_motion import sensed

    from radioslam.eval.trajectory_metrics import ate_rmse
    from radioslam.scene.procedural import MotionKind, RoomKind, generate_case
    from radioslam.slam import front_end

    def motion_decides(candidates, scores, discount, margin, turn_rad, trusted):
        adjusted = scores * (1.0 - discount)
        close = np.flatnonzero(adjusted >= (1.0 - margin) * adjusted.max())
        return int(close[np.argmin(discount[close])]), close

    case = generate_case(RoomKind.HALL, MotionKind.RANDOM, 13, max_poses=24)
    scans = sensed(case.scene, case.seed)
    no_forks = SlamConfig.model_validate({"loop_closure": {"fork_limit": 0}})
    with monkeypatch.context() as patched:
        patched.setattr(front_end, "choose", motion_decides)
        without = RadioSlam(no_forks).run(scans)
        result = RadioSlam().run(scans)
    assert ate_rmse(without.poses, case.scene.poses) > 1.0
    assert ate_rmse(result.poses, case.scene.poses) <= 0.2
    turned = np.abs(wrap_angle(np.diff(case.scene.poses[:, 2])))
    u_turns = set(np.flatnonzero(turned > np.radians(150.0)) + 1)  # the scans the walk turns back at
    taken = {int(w.split(":")[0].split()[1]) for w in result.warnings if "rival taken" in w}
    assert taken and taken <= u_turns  # a U-turn taken for walking on, and its rival taken
    assert all(result.status[k] is ScanStatus.AMBIGUOUS for k in taken)
    assert ate_rmse(RadioSlam(no_forks).run(scans).poses, case.scene.poses) <= 0.2


def test_two_open_forks_are_also_tested_together_latest_switch_first():
    """A second ambiguous turn inside the first's memory: the pair's branch carries scan k by both
    jumps (the first's after the second's), and its switches come latest first, so that carrying
    the later poses first leaves the earlier fork's jump valid."""
    from radioslam.slam.forks import Fork

    poses = walk(8)
    estimates = {k: p for k, p in enumerate(poses)}
    turn = np.array([[0.0, 0.0, np.pi]])  # each rival: turned on the spot instead of walking on
    forks = Forks.from_config(SlamConfig(), Rivals())
    forks.open = [Fork(2, turn, None, (0, 1), 4), Fork(5, turn, None, (0, 1, 2, 3, 4), 4)]  # no map: names only
    found = list(forks.hypotheses(7, estimates))
    assert [[key for key, _ in switches] for _, _, switches, _ in found] == [[2], [5], [5, 2]]
    assert len({name for name, _, _, _ in found}) == 3  # each branch named apart, across scans
    _, fork, switches, jump = found[2]
    assert fork.key == 2
    jump_2, jump_5 = forks.open[0].jumps(estimates)[0], forks.open[1].jumps(estimates)[0]
    np.testing.assert_allclose(jump, compose(jump_2, jump_5), atol=1e-12)
    # the pair's branch: back from pose 1 at scan 2, then walking on, turned back again at scan 5
    both = compose(jump, estimates[7])
    np.testing.assert_allclose(both, compose(compose(compose(poses[1], [0, 0, np.pi]), [2.0, 0, np.pi]), [2.0, 0, 0]),
                               atol=1e-9)


def test_a_rival_loop_closed_before_the_chosen_branch_is_contradicted_is_remembered():
    """The rival branch closes its loop with the map from before the fork at once (the terminal walks
    back into it), while the chosen branch's walls on that map's free space pile up only over the
    scans after: the loop found at scan 4, when nothing contradicted the choice yet, decides at scan 5."""
    truth_4 = compose(compose(walk(3)[2], [0.0, 0.0, np.pi]), [1.0, 0.0, 0.0])  # the rival's scan 4
    closer = StubCloser(truth_4, 0.6)
    forks = Forks.from_config(SlamConfig(), Rivals())
    evidence = {4: 0, 5: 40}  # the chosen branch's points on the map's free space, by scan
    forks._on_free = lambda fork, k, estimates, loop_closer, jump=None: \
        (evidence[k] if chosen_branch(jump) else 0, 400)
    estimates = {k: p for k, p in enumerate(walk(6))}
    rival = compose(estimates[2], [0.0, 0.0, np.pi])
    for k in range(4):
        forks.remember(k, Step(estimates[k], COV, ScanStatus.AMBIGUOUS if k == 3 else ScanStatus.MATCHED, 0.6,
                               rival[None] if k == 3 else np.zeros((0, 3))), {m: estimates[m] for m in range(k + 1)},
                       closer)
    assert forks.observe(4, ScanStatus.MATCHED, estimates, closer) is None  # not yet
    decided = forks.observe(5, ScanStatus.MATCHED, estimates, closer)
    assert decided is not None and decided.loop.key == 4 and decided.fork == 3
    # forgotten with the fork: a new fork at another scan starts with nothing remembered
    forks.open = []
    assert forks.observe(6, ScanStatus.MATCHED, estimates, closer) is None
    assert not forks.rival_loops and not forks.chosen_scores


def test_a_weak_match_turned_from_the_prediction_keeps_it_as_a_rival_for_the_map_to_decide():
    """polygon-fixed-2038 (the terminal never turns): scan 12 sees little (59 points) and its best
    match, weak (score 0.26), is turned by −41°; the true step scores lower. Fused as a weak match, the
    turn stood and every later scan followed it (1.72 m over 40 poses, tracking_lost false). The
    motion's prediction stays a rival: the scan is ambiguous, and once the turned branch's walls land
    where the map from before saw through while the prediction's branch matches that map, the rival
    is taken and no heading is off by more than a degree or two. The scans are sensed with the paper's
    bisection, as when this case was found: the bracketed refinement's scan 12 scores 0.20, is
    predicted, and the fork never opens (ATE 0.18 m, headings as good). The leakage is the same on
    every beam, as it was simulated then. The 27 scans are recorded (``tests/data``, sensed before
    session 14 changed the noise generator's stream), so the case tests the fork logic on fixed input
    rather than on one noise draw."""
    from radioslam.eval.trajectory_metrics import ate_rmse
    from radioslam.scene.procedural import MotionKind, RoomKind, generate_case

    case = generate_case(RoomKind.POLYGON, MotionKind.FIXED, 2038, max_poses=27)
    scans = recorded_scans("polygon-fixed-2038-scans.npz")
    result = RadioSlam().run(scans)
    # The turned weak match is never fused. Which of the two ways it is refused depends on the CPU: the
    # map's float32 sums are reduced in an order set by the vector width (AVX-512 or AVX2), and scan
    # 12's best score falls either side of min_score (0.26 on the machine this case was found on, 0.22
    # on an AVX2 one). Either way the heading holds. Where it lands below, this case does not reach the
    # weak-match branch; the forks it opens are tested on fixed estimates above.
    assert result.status[12] in (ScanStatus.AMBIGUOUS, ScanStatus.PREDICTED)
    if result.status[12] is ScanStatus.AMBIGUOUS:
        assert any(w.startswith("scan 12:") and "motion's prediction" in w and "rival taken" in w
                   for w in result.warnings)
    else:
        assert any(w.startswith("scan 12: match score") for w in result.warnings)
    assert np.degrees(np.abs(wrap_angle(result.poses[:, 2] - result.poses[0, 2]))).max() < 3.0
    assert ate_rmse(result.poses, case.scene.poses) <= 0.35


def recorded_scans(name: str) -> list:
    """The scans recorded in tests/data/``name`` (their fields concatenated, with each scan's count)."""
    from radioslam.sensing.pointcloud import Scan

    recorded = np.load(Path(__file__).parent / "data" / name)
    ends = np.cumsum(recorded["counts"])
    fields = ("range_m", "angle_rad", "power_db", "beam", "orientation")
    return [Scan(*(recorded[f][end - count:end] for f in fields)) for end, count in zip(ends, recorded["counts"])]


def recorded_walk(name: str):
    """The scans recorded in tests/data/``name`` and narrow-corridor's true poses of as many scans."""
    from radioslam.scene import load_scene

    scans = recorded_scans(name)
    return scans, load_scene("narrow-corridor").poses[:len(scans)]


def corner_taken(name: str, corner: int) -> list[str]:
    """SLAM on the recorded walk ``name``: its scan ``corner`` is ambiguous and its rival is taken, the
    trajectory within 0.2 m (ATE) and 3° of the truth. Returns the warnings saying so."""
    from radioslam.eval.trajectory_metrics import ate_rmse

    scans, truth = recorded_walk(name)
    result = RadioSlam().run(scans)
    assert result.status[corner] is ScanStatus.AMBIGUOUS
    taken = [w for w in result.warnings if w.startswith(f"scan {corner}:") and "rival taken" in w]
    assert taken
    assert ate_rmse(result.poses, truth) <= 0.2
    turn = wrap_angle(wrap_angle(result.poses[:, 2] - result.poses[0, 2]) - wrap_angle(truth[:, 2] - truth[0, 2]))
    assert np.degrees(np.abs(turn)).max() < 3.0
    return taken


def test_a_walk_around_a_block_turns_its_first_corner():
    """narrow-corridor (2.4 m wide around an 11.2 m × 4 m block), seed 1, the first 50 scans, recorded
    (sensed by session 15's receiver). At scan 37, just into the side corridor, 16 of the scan's 37
    points are that corridor's side walls, which no pose in the first corridor faced (specular walls
    parallel to its lines of sight): the true pose scores 0.45, the first corridor turned back onto
    itself 0.65, and that turn, seen in the scan, was taken (2.84 m over these 50 scans, 5.15 m over the
    walk, silent). The motion's choice now stays a rival; the folded branch puts 10 of its next scan's 71
    points where the terminal walked, the corner's branch none, and exploring it closes no loop: the
    contradiction alone decides, two scans later."""
    assert any("saw through" in w for w in corner_taken("narrow-corridor-1-scans.npz", 37))


def test_a_walk_around_a_block_closes_its_last_corner_onto_its_start():
    """narrow-corridor, seed 6, the first 122 scans, recorded (sensed by session 15's receiver). At scan 110,
    the fourth corner, the terminal turns back into the corridor it started in. The left corridor it just
    came down, folded onto the start's corridor (the corner is symmetric about its diagonal), explains the
    scan best (0.82); the true pose scores 0.38 against the map's corner clutter and was no candidate:
    the motion's choice among the candidates was 0.4 m ahead of it, and that branch puts as many points
    on the old map's free space as the folded one (1.74 m over the walk, silent). The prediction's own fit
    now stays a rival too, within 0.1 m of the truth; the folded branch reaches the far end of the corridor
    it folds onto and puts its points where the terminal walked (18 against the rival's 1), and the
    contradiction alone decides, eleven scans on."""
    corner_taken("narrow-corridor-6-scans.npz", 110)


def test_a_walk_around_a_block_turns_its_second_corner():
    """narrow-corridor, seed 8, the first 80 scans, recorded (sensed by session 15's receiver). At scan 57,
    the second corner, the corridor folded back onto itself was taken; the rivals, the motion's choice
    among the candidates, sat 0.3–0.4 m off the truth in the corner's clutter, where their branches put
    about as many points on the old map's free space as the fold (24 and 13 against its 27 by scan 70),
    and the forks the fold opened when it ran into the first corner (scans 67–70) evicted its fork
    (4.08 m over these scans, silent). Each branch counted where the map from before places it, and a
    contradicted fork kept, the fork is decided ten scans on."""
    corner_taken("narrow-corridor-8-scans.npz", 57)


def test_a_corner_folded_beyond_a_step_keeps_the_prediction_as_a_rival_decided_at_the_walks_end():
    """narrow-corridor, seed 17, the whole walk, recorded with every range moved by up to 1 µm (a draw of
    the stability check). At scan 110, the fourth corner, the start's corridor folded onto the one just
    walked explains the scan best (0.84), 1.6 m from the last pose: beyond any step. Branch and bound had
    kept no candidate near the motion (without the draw it keeps one, which scores 0.45 and stays a
    rival), so no rival and no fork: 1.74 m over the walk, silent. The prediction's own fit now stays a
    rival (with the incremental back end's estimates, issue #14, the motion's candidate is kept and the
    scan is turned from it), and the fork is decided when the walk ends, eleven scans on: the fold's
    points on the old map's free space against the rival's, at the plain significance, as no later scan
    can add evidence."""
    taken = corner_taken("narrow-corridor-17-scans.npz", 110)
    assert any("rival" in w and "taken at scan 121" in w for w in taken)
