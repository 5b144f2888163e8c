"""Band-limited sums at fractional lags (Kaiser–Bessel interpolation) and summed phase ramps,
against the direct n_sc-term sums they replace."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from radioslam.nr.nufft import LagSums, kaiser_bessel, kernel_table
from radioslam.nr.ofdm import phase_ramp, summed_phase_ramps

# measured: 1e-13, 4e-12 and 2e-10 of Σ|X·(jω)^d| at the paper's band (σ = 1024/792)
TOLERANCE = (1e-12, 5e-11, 2e-9)


def direct(x, p, n, lags, order):
    """Σ_p X(p)·(jω)^d·e^{j2πpt/N}, d = 0 … order: (order + 1, B, K)."""
    jw = 2j * np.pi * p / n
    ramp = np.exp(2j * np.pi * lags[..., None] * p / n)
    return np.stack([np.einsum("bkp,bp->bk", ramp, x * jw**d) for d in range(order + 1)])


@pytest.mark.parametrize("p, n", [
    (np.arange(-396, 396), 1024),  # the paper's band: oversampling 1.29 on the profile's own grid
    (np.arange(-410, 410), 1024),  # below 1.25: the grid doubles
    (np.arange(3, 700), 1024),  # off centre: the band's centre is modulated out
    (np.arange(-512, 512), 1024),  # every bin
    (np.arange(0, 12), 16),
])
def test_lag_sums_and_their_derivatives_equal_the_direct_sums(rng, p, n):
    x = rng.standard_normal((3, len(p))) + 1j * rng.standard_normal((3, len(p)))
    integers = np.round(rng.uniform(-50, 50, (3, 4)))
    lags = np.concatenate([rng.uniform(-n, n, (3, 6)), integers + np.array([0.0, 1e-12, -1e-9, 0.5])], axis=1)
    sums = LagSums(x, p, n)(lags, order=2)
    reference = direct(x, p, n, lags, 2)
    jw = 2j * np.pi * p / n
    for d in range(3):
        assert np.abs(sums[d] - reference[d]).max() <= TOLERANCE[d] * np.abs(x * jw**d).sum(axis=1).max(), d


@settings(max_examples=30, deadline=None)
@given(st.floats(-2000, 2000, allow_nan=False), st.integers(0, 2**32 - 1))
def test_any_lag_is_interpolated_to_the_direct_sum(lag, seed):
    rng = np.random.default_rng(seed)
    p = np.arange(-396, 396)
    x = rng.standard_normal((1, len(p))) + 1j * rng.standard_normal((1, len(p)))
    lags = np.array([[lag]])
    assert np.abs(LagSums(x, p, 1024)(lags)[0] - direct(x, p, 1024, lags, 0)[0]).max() <= 1e-12 * np.abs(x).sum()


def test_rows_evaluate_only_those_rows_and_a_gap_in_the_band_is_refused(rng):
    p = np.arange(-396, 396)
    x = rng.standard_normal((5, len(p))) + 1j * rng.standard_normal((5, len(p)))
    sums = LagSums(x, p, 1024)
    lags = rng.uniform(-100, 100, (5, 3))
    rows = np.array([4, 1, 1])
    assert np.array_equal(sums(lags[rows], rows, order=1), sums(lags, order=1)[:, rows])
    assert sums(np.zeros((0, 2)), np.array([], dtype=int)).shape == (1, 0, 2)
    with pytest.raises(ValueError):
        LagSums(x[:, :-1], np.delete(p, 5), 1024)


def test_the_kernel_table_reproduces_the_kernel_and_its_slope():
    """The Chebyshev table against φ itself and its central-difference derivative, at every tap."""
    width, beta = 20, 38.4
    table = kernel_table(width, beta, 12)
    f = np.linspace(0.0, 1.0, 257)[1:-1]
    basis = np.polynomial.chebyshev.chebvander(2 * f - 1, 12)
    taps = np.arange(1 - width // 2, 1 + width // 2)
    x = f[:, None] - taps[None, :]
    assert np.abs(basis @ table[:, 0] - kaiser_bessel(x, width, beta)).max() < 1e-15
    h = 1e-5
    slope = (kaiser_bessel(x + h, width, beta) - kaiser_bessel(x - h, width, beta)) / (2 * h)
    assert np.abs(basis @ table[:, 1] - slope).max() < 1e-9


def test_summed_phase_ramps_equal_the_weighted_sum_of_ramps(rng):
    p = np.arange(-396, 396)
    lags = rng.uniform(-300, 300, (4, 3))
    weights = rng.standard_normal((4, 3)) + 1j * rng.standard_normal((4, 3))
    expected = np.einsum("bk,bkp->bp", weights, phase_ramp(lags, p, 1024))
    assert np.allclose(summed_phase_ramps(lags, weights, p, 1024), expected, rtol=0, atol=1e-12)


@pytest.mark.parametrize("p, n", [(np.arange(-396, 396), 1024), (np.arange(-410, 410), 1024)])
def test_a_run_of_integer_spaced_lags_equals_the_general_evaluation_and_the_direct_sums(rng, p, n):
    x = rng.standard_normal((4, len(p))) + 1j * rng.standard_normal((4, len(p)))
    sums = LagSums(x, p, n)
    start = rng.uniform(-n, n, 4)
    lags = start[:, None] + np.arange(37)
    run = sums.run(start, 37)
    # The same taps and weights, only shared: equal to rounding (a matrix product and an einsum sum the
    # taps in an order that depends on the CPU's vector width, so not bit for bit), below the NUFFT's
    # own error bound (a tenth of it), which a wrong tap or weight would exceed by orders of magnitude.
    rounding = 1e-13 * np.abs(x).sum(axis=1).max()
    assert np.abs(run - sums(lags)[0]).max() <= rounding
    assert np.abs(run - direct(x, p, n, lags, 0)[0]).max() <= TOLERANCE[0] * np.abs(x).sum(axis=1).max()
    rows = np.array([2, 0])
    assert np.abs(sums.run(start[:2], 5, rows) - sums(lags[:2, :5], rows)[0]).max() <= rounding
