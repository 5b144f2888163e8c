"""Joint path estimation in the lag domain: the variable-projection Gauss–Newton step against its
direct (B, M, n_sc) form, the ML fit of paths closer than a range cell, and cancellation in the
lag domain against the residual spectrum it replaces."""

import numpy as np

from radioslam.nr.ofdm import phase_ramp
from radioslam.sensing.cancelled import CancelledSpectrum
from radioslam.sensing.joint import MAX_STEP, gauss_newton_step, joint_amplitudes, refine_paths
from radioslam.sensing.profile import RangeSpectrum

P = np.arange(-396, 396)
N = 1024


def spectrum_of(lags, amps, model, noise=0.0, rng=None):
    clean = RangeSpectrum(np.zeros(model.shape, complex), model, P, N).path_spectrum(lags, amps)
    if noise:
        clean = clean + noise * (rng.standard_normal(model.shape) + 1j * rng.standard_normal(model.shape))
    return RangeSpectrum(clean, model, P, N)


def direct_step(spec, lag, present, movable):
    """Kaufman's projected Gauss–Newton step of Σ_p |S − Σ_k a_k m e_k|² / m, with explicit ramps."""
    jw = 2j * np.pi * spec.p / N
    e = phase_ramp(lag, spec.p, N) * present[..., None]
    m = spec.model[:, None, :]
    gram = (e.conj() * m) @ e.transpose(0, 2, 1) + np.eye(lag.shape[1]) * (~present)[:, :, None]
    amp = np.linalg.solve(gram, e.conj() @ spec.s[..., None])[..., 0]
    resid = spec.s - (amp[:, None, :] @ e)[:, 0] * spec.model
    d = amp[..., None] * m * e * (-jw)
    d = d - (np.linalg.solve(gram, e.conj() @ d.transpose(0, 2, 1)).transpose(0, 2, 1) @ e) * m
    hess = ((d.conj() / m) @ d.transpose(0, 2, 1)).real
    grad = ((d.conj() / m) @ resid[..., None])[..., 0].real
    hess = hess * movable[:, :, None] * movable[:, None, :] + np.eye(lag.shape[1]) * (~movable)[:, :, None]
    return np.clip(np.linalg.solve(hess, (grad * movable)[..., None])[..., 0], -MAX_STEP, MAX_STEP)


def test_the_lag_domain_step_is_the_direct_variable_projection_step(rng):
    b, m = 6, 4
    model = 12.0 + rng.standard_normal((b, len(P)))  # the MF model Σ_q |x_q|²: varies per subcarrier
    truth = np.array([3.2, 10.4, 11.3, 40.3]) + 0.1 * rng.standard_normal((b, m))
    amps = rng.standard_normal((b, m)) + 1j * rng.standard_normal((b, m))
    spec = spectrum_of(truth, amps, model, 0.3, rng)
    start = truth + rng.uniform(-0.2, 0.2, (b, m))
    present = np.ones((b, m), bool)
    present[1, 3] = present[4, 2] = False
    movable = present & np.array([False, True, True, True])
    start = np.where(present, start, 0.0)
    step = gauss_newton_step(spec, np.arange(b), start, present, movable)
    assert np.abs(step - direct_step(spec, start, present, movable)).max() < 1e-6  # samples (ridge, 1e-13 sums)
    assert (step[:, 0] == 0).all() and (step[~present] == 0).all()


def test_two_paths_closer_than_a_range_cell_are_resolved_to_their_truth(rng):
    """Noiseless: the ML fit of the leakage (fixed) and two paths 0.6 sample apart lands on them."""
    b = 5
    model = 12.0 + rng.standard_normal((b, len(P)))
    truth = np.stack([np.full(b, 1.0), 20.0 + rng.uniform(0, 1, b), np.zeros(b)], axis=1)
    truth[:, 2] = truth[:, 1] + 0.6
    amps = np.array([30.0, 1.0, 0.7j]) * np.exp(2j * np.pi * rng.uniform(size=(b, 1)))
    spec = spectrum_of(truth, amps, model)
    start = truth + np.array([0.0, -0.15, 0.15])
    lag, amp, _ = refine_paths(spec, np.arange(b), start, np.ones((b, 3), bool), np.array([True, False, False]),
                               1e-9, 30)
    assert np.abs(lag - truth).max() < 1e-6
    assert np.abs(amp - amps).max() < 1e-6 * np.abs(amps).max()
    assert np.allclose(joint_amplitudes(spec, np.arange(b), truth, np.ones((b, 3), bool)), amps, atol=1e-9)


def test_cancelling_in_the_lag_domain_equals_the_residual_spectrum(rng):
    b = 4
    model = 12.0 + rng.standard_normal((b, len(P)))
    spec = spectrum_of(rng.uniform(0, 80, (b, 3)), rng.standard_normal((b, 3)) + 0j, model, 0.1, rng)
    lags = rng.uniform(0, 80, (b, 2))
    amps = rng.standard_normal((b, 2)) + 1j * rng.standard_normal((b, 2))
    lags[2, 1] = np.nan  # nothing to cancel there
    residual = spec.minus(spec.path_spectrum(np.nan_to_num(lags), np.where(np.isfinite(lags), amps, 0)))
    at = rng.uniform(0, 80, (b, 5))
    cancelled = CancelledSpectrum(spec, np.arange(b), lags, amps)
    assert np.allclose(cancelled.with_derivatives(at), residual.with_derivatives(at), rtol=0, atol=1e-8)
    rows = np.array([3, 0])
    assert np.allclose(cancelled.rows(rows).at(at[rows]), residual.at(at)[rows], rtol=0, atol=1e-10)
