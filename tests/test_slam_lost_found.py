"""Lost and found by trial (issue #12, point 3): the evidence a trial gathers is a bounded log
ratio of scores, and a trial is decided only by enough scans together."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from radioslam.slam.config import SlamConfig
from radioslam.slam.loop_closer import LoopCloser
from radioslam.slam.lost_found import LostAndFound, Trial, evidence
from radioslam.slam.status import ScanStatus

CAP = 3.0 * np.log1p(0.25)
scores = st.floats(-1.0, 1.0, allow_nan=False)


@given(scores, scores)
def test_evidence_is_the_log_ratio_within_its_bound(trial_score, front_score):
    e = evidence(trial_score, front_score, CAP)
    assert np.isfinite(e) and -CAP - 1e-12 <= e <= CAP + 1e-12
    if trial_score > 0 and front_score > 0 and abs(np.log(trial_score / front_score)) < CAP:
        assert np.isclose(e, np.log(trial_score / front_score))
    assert np.isclose(evidence(front_score, trial_score, CAP), -e)  # the two hypotheses are treated alike


def test_evidence_is_monotone_in_each_score():
    grid = np.linspace(-0.5, 1.0, 31)
    e = np.array([evidence(s, 0.5, CAP) for s in grid])
    assert np.all(np.diff(e) >= 0) and np.isclose(e[0], -CAP) and e[-1] > 0
    assert np.all(np.diff([evidence(0.5, s, CAP) for s in grid]) <= 0)


def test_a_trial_is_decided_by_enough_scans_together():
    """One overwhelming scan reaches the bound; the trial still needs its confirm_scans scans, and
    together as much evidence as each explained ``gain`` better."""
    cfg = SlamConfig()
    lost_and_found = LostAndFound.from_config(cfg)
    assert np.isclose(lost_and_found.bound, cfg.loop_closure.confirm_scans * np.log1p(cfg.loop_closure.relocalize_gain))
    trial = Trial([0], np.zeros(3), [object()], evidence(0.8, -0.2, lost_and_found.bound))
    lost_and_found.trial = trial
    assert trial.evidence == lost_and_found.bound and not lost_and_found.decided()
    trial.found += [object()] * (cfg.loop_closure.confirm_scans - 1)
    assert lost_and_found.decided()
    trial.evidence -= 1e-3  # the later scans spoke a little against it
    assert not lost_and_found.decided()


class MapStub:
    """The loop closer's searches as a test sets them: ``follow`` finds a place a step on from the
    first guess with ``score``; the whole-map search places a scan 5 m off; nothing looks alike."""

    def __init__(self, follow_score: float = 0.6):
        self.follow_score, self.followed = follow_score, []

    def map_keys(self, k, before=None):
        return list(range(k if before is None else min(k, before)))

    def whole_map(self, keys, estimates):
        return None, np.zeros(0)

    def follow(self, grid, normals, points, guesses, radius_m):
        self.followed.append(np.array(guesses[0]))
        return guesses[0] + np.array([0.5, 0.0, 0.0]), self.follow_score, np.eye(3) * 1e-4

    def relocalize(self, k, points, estimates, before=None, whole=None):
        return LoopCloser.placed(k, estimates[k - 1] + np.array([5.0, 0.0, 0.0]), 0.9, np.eye(3) * 1e-4,
                                 self.map_keys(k, before), estimates)

    def looks_alike(self, *args):
        return False

    placed = staticmethod(LoopCloser.placed)
    placed_pose = staticmethod(LoopCloser.placed_pose)


ESTIMATES = {k: np.array([float(k), 0.0, 0.0]) for k in range(40)}  # the walk: a step of 1 m per scan


def _walk(lost_and_found, stub, scores, pair, monkeypatch, start=0):
    """Scans start, start + 1, … each matched by the front end with ``scores[i]`` at x = k; the two
    hypotheses' scores of every scan a trial opens or follows are ``pair``."""
    monkeypatch.setattr("radioslam.slam.lost_found.hypothesis_scores", lambda *args: pair)
    for i, score in enumerate(scores):
        k = start + i
        assert not lost_and_found.observe(k, ScanStatus.MATCHED, ESTIMATES[k], score, None, _before(k), stub)


def _before(k):
    return {m: p for m, p in ESTIMATES.items() if m < k}


def test_a_trial_that_never_gathers_enough_evidence_is_recorded_undecided(monkeypatch):
    """A score drop opens a trial (its scan explained log(0.50/0.38) better at the trial's place); each
    scan after it is explained a little better there (log(0.40/0.39) each), never enough to confirm
    it in max_trial_scans: the trial ends and its scans are recorded as undecided (the driver marks
    them ambiguous). A trial the front end's pose explains better ends at once and is not recorded."""
    cfg = SlamConfig()
    lc = cfg.loop_closure
    lost_and_found, stub = LostAndFound.from_config(cfg), MapStub()
    _walk(lost_and_found, stub, [0.6] * 8, (0.40, 0.39), monkeypatch)
    assert lost_and_found.trial is None  # no drop, no trial
    monkeypatch.setattr("radioslam.slam.lost_found.hypothesis_scores", lambda *args: (0.50, 0.38))
    lost_and_found.observe(8, ScanStatus.MATCHED, ESTIMATES[8], 0.3, None, _before(8), stub)
    assert lost_and_found.trial is not None and lost_and_found.trial.found[0].key == 8
    _walk(lost_and_found, stub, [0.6] * lc.max_trial_scans, (0.40, 0.39), monkeypatch, start=9)
    assert lost_and_found.trial is None and not lost_and_found.decided()
    assert lost_and_found.undecided == [list(range(8, 8 + lc.max_trial_scans))]
    # the front end explains the next trial's scans better: it ends, unrecorded
    lost_and_found.undecided.clear()
    monkeypatch.setattr("radioslam.slam.lost_found.hypothesis_scores", lambda *args: (0.60, 0.30))
    lost_and_found.observe(30, ScanStatus.MATCHED, ESTIMATES[30], 0.2, None, _before(30), stub)
    assert lost_and_found.trial is not None
    _walk(lost_and_found, stub, [0.6] * 3, (0.30, 0.60), monkeypatch, start=31)
    assert lost_and_found.trial is None and lost_and_found.undecided == []


def test_after_a_jump_each_scan_is_also_searched_for_where_the_terminal_was_taken(monkeypatch):
    """For alert_scans scans after a confirmed trial, a scan is searched for within a step of the last
    pose before the jump whatever its score (no drop needed), and a place there explaining it gain
    better than the front end's pose opens a trial; one explaining it no better opens none; once the
    alert is over, a scan that did not drop is not searched for."""
    cfg = SlamConfig()
    lost_and_found, stub = LostAndFound.from_config(cfg), MapStub()
    _walk(lost_and_found, stub, [0.6] * 8, (0.6, 0.6), monkeypatch)
    estimates = _before(8)
    lost_and_found.alert, lost_and_found.taken_from = cfg.loop_closure.alert_scans, 3
    monkeypatch.setattr("radioslam.slam.lost_found.hypothesis_scores", lambda *args: (0.6, 0.55))
    lost_and_found.observe(8, ScanStatus.MATCHED, ESTIMATES[8], 0.6, None, estimates, stub)
    assert lost_and_found.trial is None and np.allclose(stub.followed[-1], estimates[3])  # searched there: no better
    assert lost_and_found.alert == cfg.loop_closure.alert_scans - 1
    monkeypatch.setattr("radioslam.slam.lost_found.hypothesis_scores", lambda *args: (0.8, 0.55))
    estimates = _before(9)
    lost_and_found.observe(9, ScanStatus.MATCHED, ESTIMATES[9], 0.6, None, estimates, stub)
    trial = lost_and_found.trial
    assert trial is not None and trial.found[0].key == 9
    assert np.allclose(LoopCloser.placed_pose(trial.found[0], estimates), estimates[3] + [0.5, 0, 0])
    lost_and_found.forget()
    lost_and_found.alert, searched = 0, len(stub.followed)
    lost_and_found.observe(10, ScanStatus.MATCHED, ESTIMATES[10], 0.6, None, _before(10), stub)
    assert lost_and_found.trial is None and len(stub.followed) == searched
