"""Lost and found by trial (issues #12, #47): a trial gathers the log posterior odds of its places against the
front end's poses, and is decided only by enough scans together at the ending's odds."""

from dataclasses import replace

import numpy as np

from radioslam.slam.config import SlamConfig
from radioslam.slam.loop_closer import LoopCloser
from radioslam.slam.lost_found import LostAndFound, Trial
from radioslam.slam.posterior import Posterior
from radioslam.slam.rivals import Cause, Rivals
from radioslam.slam.status import ScanStatus


def test_a_trial_is_decided_by_enough_scans_at_the_endings_odds():
    """A trial confirms once confirm_scans scans are followed and its log posterior odds reach the ending's
    1 : odds (a probability ratio, not a tuned gain): one overwhelming scan alone does not decide it."""
    cfg = SlamConfig()
    lost_and_found = LostAndFound.from_config(cfg, Posterior.from_config(cfg, None), Rivals())
    assert np.isclose(lost_and_found.bound, np.log(cfg.ending.odds))
    trial = Trial([0], np.zeros(3), [object()], log_odds=40.0)
    lost_and_found.trial = trial
    assert not lost_and_found.decided()
    trial.found += [object()] * (cfg.loop_closure.confirm_scans - 1)
    assert lost_and_found.decided()
    trial.log_odds = lost_and_found.bound - 1e-3  # the later scans spoke a little against it
    assert not lost_and_found.decided()


class GridStub:
    area_m2 = 400.0


class KeyframesStub:
    """Every scan before k is a keyframe (with no points: the stubbed searches read none)."""

    points: dict = {}

    @staticmethod
    def before(k, before=None):
        return list(range(k if before is None else min(k, before)))


class MapStub:
    """The loop closer's searches as a test sets them: ``follow`` finds a place a step on from the
    first guess with ``score``; the whole-map search places a scan 5 m off; nothing looks alike."""

    keyframes = KeyframesStub()

    def __init__(self, follow_score: float = 0.6):
        self.follow_score, self.followed = follow_score, []

    def whole_map(self, keys, estimates):
        return GridStub(), np.zeros(0)

    def follow(self, grid, normals, points, guesses, radius_m):
        self.followed.append(np.array(guesses[0]))
        return guesses[0] + np.array([0.5, 0.0, 0.0]), self.follow_score, np.eye(3) * 1e-4

    def relocalize(self, k, points, estimates, before=None, whole=None):
        return replace(LoopCloser.placed(k, estimates[k - 1] + np.array([5.0, 0.0, 0.0]), 0.9, np.eye(3) * 1e-4,
                                         self.keyframes.before(k, before), estimates), searched_m2=400.0)

    def looks_alike(self, *args):
        return False

    placed = staticmethod(LoopCloser.placed)
    placed_pose = staticmethod(LoopCloser.placed_pose)


ESTIMATES = {k: np.array([float(k), 0.0, 0.0]) for k in range(40)}  # the walk: a step of 1 m per scan


def _odds(monkeypatch, value, jump=0.0):
    """Every scan a trial opens or follows adds ``value`` to its log odds; a jump's prior odds are ``jump``."""
    monkeypatch.setattr(LostAndFound, "log_odds", lambda *args, **kwargs: value)  # a followed scan's
    monkeypatch.setattr(Posterior, "log_odds", lambda *args, **kwargs: value)  # the first scan's
    monkeypatch.setattr(LostAndFound, "jump_log_odds", lambda *args, **kwargs: jump)
    monkeypatch.setattr(LostAndFound, "_front_placements", lambda self, pose, *args: pose[None])


def _walk(lost_and_found, stub, scores, odds, monkeypatch, start=0):
    """Scans start, start + 1, … each matched by the front end with ``scores[i]`` at x = k; every scan a trial
    opens or follows brings log odds ``odds``."""
    _odds(monkeypatch, odds)
    for i, score in enumerate(scores):
        k = start + i
        assert not lost_and_found.observe(k, ScanStatus.MATCHED, ESTIMATES[k], score, None, _before(k), stub)


def _before(k):
    return {m: p for m, p in ESTIMATES.items() if m < k}


def test_a_trial_that_never_gathers_enough_evidence_is_recorded_undecided(monkeypatch):
    """A score drop opens a trial where its scan is more probable than at the front end's pose, whatever the
    jump's prior (the scans after it pay for that, or the trial fails); each scan after it is a little more
    probable there (0.1 nat each), never enough to reach the ending's odds in max_trial_scans: the trial
    ends and its scans are recorded as undecided (the driver marks them ambiguous). A trial whose scans the
    front end's poses explain better ends at once and is not recorded; a place where the scan is less
    probable opens none. The undecided trial's jump stays an alternative for the ending to weigh."""
    cfg = SlamConfig()
    lc = cfg.loop_closure
    lost_and_found, stub = LostAndFound.from_config(cfg, Posterior.from_config(cfg, None), Rivals()), MapStub()
    _walk(lost_and_found, stub, [0.6] * 8, 0.1, monkeypatch)
    assert lost_and_found.trial is None  # no drop, no trial
    _odds(monkeypatch, -0.5)
    lost_and_found.observe(8, ScanStatus.MATCHED, ESTIMATES[8], 0.3, None, _before(8), stub)
    assert lost_and_found.trial is None  # the drop's place found, but the scan is less probable there
    _odds(monkeypatch, -1.0, jump=-2.0)  # the scan more probable there (+1 nat), the jump's prior against it
    lost_and_found.observe(9, ScanStatus.MATCHED, ESTIMATES[9], 0.3, None, _before(9), stub)
    assert lost_and_found.trial is not None and lost_and_found.trial.evidence == 1.0
    lost_and_found.forget()
    _odds(monkeypatch, 1.0)
    lost_and_found.observe(9, ScanStatus.MATCHED, ESTIMATES[9], 0.3, None, _before(9), stub)
    assert lost_and_found.trial is not None and lost_and_found.trial.found[0].key == 9
    _walk(lost_and_found, stub, [0.6] * lc.max_trial_scans, 0.1, monkeypatch, start=10)
    assert lost_and_found.trial is None and not lost_and_found.decided()
    assert lost_and_found.undecided == [list(range(9, 9 + lc.max_trial_scans))]
    # and the walk with its jump stays an alternative for the ending: the place found for its first scan
    (rival,) = lost_and_found.rivals.kept
    assert rival.key == 9 and rival.cause is Cause.PLACE_FOUND and np.allclose(rival.step, [5.0, 0.0, 0.0])
    # the front end explains the next trial's scans better: it ends, unrecorded
    lost_and_found.undecided.clear()
    _odds(monkeypatch, 1.0)
    lost_and_found.observe(30, ScanStatus.MATCHED, ESTIMATES[30], 0.2, None, _before(30), stub)
    assert lost_and_found.trial is not None
    _walk(lost_and_found, stub, [0.6] * 3, -2.0, monkeypatch, start=31)
    assert lost_and_found.trial is None and lost_and_found.undecided == [] and len(lost_and_found.rivals.kept) == 1


def test_after_a_jump_each_scan_is_also_searched_for_where_the_terminal_was_taken(monkeypatch):
    """For alert_scans scans after a confirmed trial, a scan is searched for within a step of the last
    pose before the jump whatever its score (no drop needed), and a place there more probable than the
    front end's pose opens a trial; one less probable opens none; once the alert is over, a scan that did
    not drop is not searched for."""
    cfg = SlamConfig()
    lost_and_found, stub = LostAndFound.from_config(cfg, Posterior.from_config(cfg, None), Rivals()), MapStub()
    _walk(lost_and_found, stub, [0.6] * 8, 0.0, monkeypatch)
    estimates = _before(8)
    lost_and_found.alert, lost_and_found.taken_from = cfg.loop_closure.alert_scans, 3
    _odds(monkeypatch, -0.2)
    lost_and_found.observe(8, ScanStatus.MATCHED, ESTIMATES[8], 0.6, None, estimates, stub)
    assert lost_and_found.trial is None and np.allclose(stub.followed[-1], estimates[3])  # searched there: no better
    assert lost_and_found.alert == cfg.loop_closure.alert_scans - 1
    _odds(monkeypatch, 0.5)
    estimates = _before(9)
    lost_and_found.observe(9, ScanStatus.MATCHED, ESTIMATES[9], 0.6, None, estimates, stub)
    trial = lost_and_found.trial
    assert trial is not None and trial.found[0].key == 9
    assert np.allclose(LoopCloser.placed_pose(trial.found[0], estimates), estimates[3] + [0.5, 0, 0])
    lost_and_found.forget()
    lost_and_found.alert, searched = 0, len(stub.followed)
    lost_and_found.observe(10, ScanStatus.MATCHED, ESTIMATES[10], 0.6, None, _before(10), stub)
    assert lost_and_found.trial is None and len(stub.followed) == searched


class LookAlikeStub(MapStub):
    """A room that looks the same from the place the whole-map search finds (a symmetric room)."""

    def looks_alike(self, *args):
        return True


def test_a_look_alike_place_opens_no_trial_but_stays_the_endings_alternative(monkeypatch):
    """A score drop whose whole-map search finds a place the room looks the same from cannot be weighed by the
    scans (both places explain them alike): the front end's pose stays, and the place found is kept as an
    alternative (its step from the pose before, the jump) that the ending weighs with the whole walk. Before,
    it was dropped: a terminal carried to a look-alike place was silently lost."""
    cfg = SlamConfig()
    rivals = Rivals()
    lost_and_found, stub = LostAndFound.from_config(cfg, Posterior.from_config(cfg, None), rivals), LookAlikeStub()
    _walk(lost_and_found, stub, [0.6] * 8, 0.1, monkeypatch)
    assert rivals.kept == []
    _odds(monkeypatch, 1.0)
    lost_and_found.observe(8, ScanStatus.MATCHED, ESTIMATES[8], 0.3, None, _before(8), stub)
    assert lost_and_found.trial is None
    (rival,) = rivals.kept
    assert rival.key == 8 and rival.cause is Cause.LOOKALIKE
    assert np.allclose(rival.step, [5.0, 0.0, 0.0])  # from pose 7 to the place found (5 m on)
    (_, branch), = rivals.branches(np.array([ESTIMATES[k] for k in range(12)]))  # every later pose carried along
    assert np.allclose(branch[8:, 0], np.arange(8, 12) + 4.0) and np.allclose(branch[:8, 0], np.arange(8))


def test_a_relocalization_not_taken_on_odds_within_the_endings_stays_an_alternative(monkeypatch):
    """A lost scan's place in the whole map is taken where its posterior beats the front end's pose; where it
    falls short by less than the ending's odds (1 : odds), the decision was not the data's to make, and the place
    stays an alternative the ending weighs with the whole walk; beyond those odds it is dropped. Taken, the front
    end's pose is the one kept."""
    from radioslam.slam.front_end import Step
    from radioslam.slam.loop_closer import LoopClosure
    from radioslam.slam.session import SlamSession

    session = SlamSession()
    session.back_end.estimates = {0: np.zeros(3), 1: np.array([0.5, 0.0, 0.0])}
    place = LoopClosure(0, 2, np.array([4.0, 1.0, 0.5]), np.eye(3) * 1e-4, 0.8, relocalization=True)
    monkeypatch.setattr(type(session.loop_closer), "relocalize", lambda self, *args, **kwargs: place)
    bound = np.log(session.cfg.ending.odds)
    lost = Step(np.array([1.0, 0.0, 0.0]), np.eye(3), ScanStatus.PREDICTED, 0.0)
    for log_odds, kept in ((-0.5 * bound, Cause.PLACE_FOUND), (-2.0 * bound, None), (1.0, Cause.RELOCALIZATION)):
        session.rivals.kept.clear()
        session.lost = session.cfg.loop_closure.relocalize_after  # a lost stretch: relocalization searches
        monkeypatch.setattr(SlamSession, "_relocation_log_odds", lambda self, *args, odds=log_odds: odds)
        step, found = session._relocalized(2, lost, None)
        assert [r.cause for r in session.rivals.kept] == ([] if kept is None else [kept])
        assert bool(found) == (log_odds > 0)
        if kept is Cause.PLACE_FOUND:  # the alternative is the place found, stepped from pose 1
            assert np.allclose(session.rivals.kept[0].step, [3.5, 1.0, 0.5])
