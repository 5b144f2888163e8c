"""16-QAM (38.211 §5.1.4) and CP-OFDM (38.211 §5.3.1)."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from radioslam.nr import Numerology, demodulate, modulate, qam16_demodulate, qam16_modulate, random_bits
from radioslam.nr.ofdm import from_fft_bins, symbol_starts, to_fft_bins
from radioslam.nr.qam import qam16_energy


def test_qam16_table_of_38_211():
    s10 = np.sqrt(10)
    cases = {"0000": 1 + 1j, "0010": 3 + 1j, "0001": 1 + 3j, "0011": 3 + 3j,
             "1000": -1 + 1j, "0100": 1 - 1j, "1111": -3 - 3j, "1010": -3 + 1j}
    for bits, point in cases.items():
        b = np.array([int(c) for c in bits])
        assert qam16_modulate(b)[0] == point / s10


def test_qam16_unit_energy_and_gray_mapping():
    q = np.arange(16)
    bits = ((q[:, None] >> np.array([3, 2, 1, 0])) & 1).reshape(-1)
    pts = qam16_modulate(bits)
    assert np.mean(np.abs(pts) ** 2) == pytest.approx(1.0, abs=1e-12)
    b = bits.reshape(16, 4)
    for i in range(16):
        for j in range(16):
            if np.isclose(abs(pts[i] - pts[j]), 2 / np.sqrt(10)):  # nearest neighbours
                assert np.sum(b[i] != b[j]) == 1


@given(st.integers(0, 2**32 - 1))
@settings(max_examples=25, deadline=None)
def test_qam16_round_trip(seed):
    bits = random_bits(np.random.default_rng(seed), (3, 40))
    assert np.array_equal(qam16_demodulate(qam16_modulate(bits)), bits)


def test_random_bits_are_balanced(rng):
    assert abs(random_bits(rng, (100_000,)).mean() - 0.5) < 0.01


@given(st.lists(st.sampled_from([72, 136]), min_size=1, max_size=6), st.integers(0, 2**31))
@settings(max_examples=25, deadline=None)
def test_ofdm_round_trip_with_any_cp_pattern(cps, seed, ):
    num = Numerology(1024, 792, 120e3)
    rng = np.random.default_rng(seed)
    grid = qam16_modulate(random_bits(rng, (2, len(cps), 792 * 4)))
    cp = np.array(cps)
    x = modulate(grid, cp, num)
    assert x.shape == (2, (cp + 1024).sum())
    # cut anywhere inside the CP: a circular shift by s multiplies subcarrier p by e^{−j2πps/N}
    for back_off in (0, 17):
        start = symbol_starts(cp, 1024) + cp - back_off
        y = demodulate(x, start, num)
        p = num.subcarrier_indices()
        assert np.allclose(y * np.exp(2j * np.pi * p * back_off / 1024), grid, atol=1e-12)


def test_ofdm_subcarrier_is_a_tone_and_cp_is_the_tail():
    num = Numerology(1024, 792, 120e3)
    grid = np.zeros((1, 792), complex)
    p = num.subcarrier_indices()
    grid[0, p == 5] = 1.0
    x = modulate(grid, np.array([72]), num)
    n = np.arange(-72, 1024)
    assert np.allclose(x, np.exp(2j * np.pi * 5 * n / 1024) / np.sqrt(1024))
    assert np.allclose(x[:72], x[-72:])


def test_ofdm_is_energy_preserving(rng):
    num = Numerology(1024, 792, 120e3)
    grid = qam16_modulate(random_bits(rng, (1, 792 * 4)))
    x = modulate(grid, np.array([0]), num)
    assert np.isclose(np.sum(np.abs(x) ** 2), np.sum(np.abs(grid) ** 2))


@given(st.integers(1, 9), st.integers(0, 2**32 - 1))
@settings(max_examples=20, deadline=None)
def test_qam16_any_symbol_count_matches_the_formula(k, seed):
    """Odd and even symbol counts (packbits pairs symbols) against d of 38.211 §5.1.4."""
    b = random_bits(np.random.default_rng(seed), (2, 4 * k)).reshape(2, k, 4).astype(float)
    s = 1 - 2 * b
    expected = (s[..., 0] * (2 - s[..., 2]) + 1j * s[..., 1] * (2 - s[..., 3])) / np.sqrt(10)
    assert np.allclose(qam16_modulate(b.reshape(2, -1).astype(np.uint8)), expected, atol=1e-15)


def test_from_fft_bins_inverts_to_fft_bins(rng):
    num = Numerology(1024, 792, 120e3)
    grid = rng.standard_normal((2, 792)) + 0j
    assert np.array_equal(from_fft_bins(to_fft_bins(grid, num), num), grid)
    assert np.array_equal(from_fft_bins(np.arange(1024), num), np.arange(1024)[num.fft_bins()])


def test_qam16_conjugates_and_energies_are_those_of_the_symbols(rng):
    bits = random_bits(rng, (3, 5, 4 * 11))  # an odd symbol count too
    for dtype in (np.complex64, np.complex128):
        symbols = qam16_modulate(bits, dtype)
        assert np.array_equal(qam16_modulate(bits, dtype, conjugate=True), symbols.conj())
        energy = qam16_energy(bits, symbols.real.dtype)
        assert np.array_equal(energy, symbols.real**2 + symbols.imag**2)
    assert set(np.round(np.unique(qam16_energy(bits, np.float64)), 12)) <= {0.2, 1.0, 1.8}
