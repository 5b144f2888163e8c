"""The walks not taken (issue #47): each decision's alternative is the answer with that one step replaced, every
later pose carried with it; and the ending finds a wrong decision whose alternative it was given."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from test_slam_ending import _in_frame, _room, _scans

from radioslam.slam.config import SlamConfig
from radioslam.slam.ending import Judge, Source
from radioslam.slam.motion import MotionModel
from radioslam.slam.posterior import Posterior
from radioslam.slam.rivals import Cause, Rivals
from radioslam.slam.se2 import between, compose, wrap_angle

poses_strategy = st.lists(st.tuples(st.floats(-5, 5), st.floats(-5, 5), st.floats(-3.1, 3.1)), min_size=3,
                          max_size=12)


@given(poses_strategy, st.data())
@settings(max_examples=60, deadline=None)
def test_a_branch_is_the_trajectory_with_one_step_replaced(raw, data):
    poses = np.array(raw)
    key = data.draw(st.integers(1, len(poses) - 1))
    step = np.array(data.draw(st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(-3.1, 3.1))))
    rivals = Rivals()
    rivals.keep(key, step, Cause.TURNED)
    (rival, branch), = rivals.branches(poses)
    assert rival.cause is Cause.TURNED and np.array_equal(branch[:key], poses[:key])
    into = between(branch[key - 1], branch[key])
    assert np.allclose(into[:2], step[:2], atol=1e-9) and abs(wrap_angle(into[2] - step[2])) < 1e-9
    for m in range(key + 1, len(poses)):  # every later step as the answer's
        a, b = between(poses[m - 1], poses[m]), between(branch[m - 1], branch[m])
        assert np.allclose(a[:2], b[:2], atol=1e-9) and abs(wrap_angle(a[2] - b[2])) < 1e-9


def test_a_wrong_turn_is_found_by_the_ending_from_its_kept_alternative():
    """An L-shaped room walked along its long leg and back: a SLAM that took scan 9 turned by 180° (the walk
    folded back where it went on) answers a trajectory the scans contradict; the alternative it kept at that
    decision (the true step) beats it, so the run is flagged ambiguous, with the truth as the alternative."""
    segments = _room([[0, 0], [16, 0], [16, 6], [8, 6], [8, 12], [0, 12]])
    x = np.r_[np.linspace(2, 14, 13), np.full(4, 14.0)]
    y = np.r_[np.full(13, 2.0), np.linspace(2.8, 5.2, 4)]
    heading = np.arctan2(np.gradient(y), np.gradient(x))
    world = np.column_stack([x, y, heading])
    scans, truth = _scans(segments, world), _in_frame(world)
    fork = 9
    folded = truth.copy()
    wrong_step = compose(between(truth[fork - 1], truth[fork]), np.array([0.0, 0.0, np.pi]))
    folded[fork:] = [compose(compose(truth[fork - 1], wrong_step), between(truth[fork], p)) for p in truth[fork:]]
    rivals = Rivals()
    rivals.keep_poses(fork, folded[fork - 1], truth[fork], Cause.TURNED)  # the true pose, the decision's rival
    cfg = SlamConfig()
    judge = Judge.from_config(cfg, Posterior.from_config(cfg, MotionModel.from_config(cfg.motion, None)))
    candidates = [(Source.POSE_GRAPH, folded)] + [(Source.RIVAL_BRANCH, b) for _, b in rivals.branches(folded)]
    ending = judge.judge(candidates, scans)
    assert ending.best.source is Source.POSE_GRAPH and ending.ambiguous  # the answer stays; the run says so
    assert ending.runner_up.source is Source.RIVAL_BRANCH and ending.runner_up_odds < 1.0
    assert np.allclose(ending.runner_up.poses, truth, atol=1e-9)


def test_the_shortlist_keeps_the_alternatives_their_own_scan_supports():
    """Three alternatives at one scan of a hall walked straight: the true step, the step turned by 90° and the
    step slid 1.5 m on. Kept to one, the shortlist holds the one whose scan fits its map and whose step the
    motion expects: the truth's."""
    segments = _room([[0, 0], [20, 0], [20, 5], [0, 5]])
    world = np.column_stack([np.linspace(2, 10, 9), np.full(9, 2.0), np.zeros(9)])
    scans, truth = _scans(segments, world), _in_frame(world)
    key = 6
    wrong = [compose(truth[key], np.array(d)) for d in ([0.0, 0.0, np.pi / 2], [1.5, 0.0, 0.0])]
    rivals = Rivals()
    rivals.keep_poses(key, truth[key - 1], np.array(wrong + [truth[key]]), Cause.TURNED)
    cfg = SlamConfig()
    judge = Judge.from_config(cfg, Posterior.from_config(cfg, MotionModel.from_config(cfg.motion, None)))
    answer = truth.copy()
    answer[key:] = [compose(wrong[0], between(truth[key], p)) for p in truth[key:]]
    branches = [(rival.key, poses) for rival, poses in rivals.branches(answer)]
    kept, = judge.shortlist(branches, scans, 1)
    assert np.allclose(kept, truth, atol=1e-9)
    assert len(judge.shortlist(branches, scans, 3)) == 3  # within the count, all
