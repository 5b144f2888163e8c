"""The Cramér–Rao bound against a numerical Fisher information, and the bisection against the bound."""

import numpy as np

from radioslam.config import RadioConfig
from radioslam.eval.crb import delay_crb_s, range_crb_m
from radioslam.eval.experiments.table1 import crb_sweep


def test_closed_form_matches_numerical_fisher_information():
    n, df, r, snr_db = 48, 120e3, 3, 7.0
    p = np.arange(-n // 2, n // 2)
    gamma = 10 ** (snr_db / 10)
    tau, b = 20e-9, np.sqrt(gamma) * np.exp(0.4j)  # σ² = 1
    mu = lambda t, a: np.tile(a * np.exp(-2j * np.pi * p * df * t), r)  # noqa: E731
    eps = 1e-13
    grads = [(mu(tau + eps, b) - mu(tau - eps, b)) / (2 * eps), np.tile(np.exp(-2j * np.pi * p * df * tau), r),
             1j * np.tile(np.exp(-2j * np.pi * p * df * tau), r)]  # ∂/∂τ, ∂/∂Re b, ∂/∂Im b
    fim = np.array([[2 * np.real(np.vdot(gi, gj)) for gj in grads] for gi in grads])
    assert np.isclose(np.sqrt(np.linalg.inv(fim)[0, 0]), delay_crb_s(n, df, r, snr_db), rtol=1e-4)


def test_range_bound_scales_with_snr_and_symbols():
    a = range_crb_m(792, 120e3, 12, 10.0)
    assert np.isclose(range_crb_m(792, 120e3, 12, 20.0), a / np.sqrt(10))
    assert np.isclose(range_crb_m(792, 120e3, 3, 10.0), 2 * a)
    assert 1e-3 < a < 3e-3  # 2 mm at the default SNR


def test_bisection_rmse_is_within_twice_the_bound_plus_a_millimetre():
    radio = RadioConfig()
    snr = np.array([0.0, 10.0, 20.0])
    rmse, crb = crb_sweep(radio, snr, trials=60, seed=3)
    assert np.all(rmse <= 2 * crb + 1e-3), (rmse, crb)
