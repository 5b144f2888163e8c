"""Lost and found by trial (issue #12, point 3): the evidence a trial gathers is a bounded log
ratio of scores, and a trial is decided only by enough scans together."""

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from radioslam.slam.config import SlamConfig
from radioslam.slam.lost_found import LostAndFound, Trial, evidence

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
