"""The ★ SNR definition: per-RE SNR of the reference echo (concrete, 5 m, normal, boresight beam)."""

import numpy as np
import pytest

from radioslam.capture import CaptureMode
from radioslam.config import RadioConfig
from radioslam.nr import demodulate
from radioslam.sim import Simulator, measured_snr_db, noise_variance, reference_echo_power
from radioslam.sim.noise import reference_scene


def _boresight(cap):
    return int(np.flatnonzero((cap.orientation == 0) & (cap.beam_index == 0))[0])


@pytest.mark.parametrize("snr_db", [0.0, 10.0, 20.0])
def test_noise_level_matches_snr_on_the_reference_echo(snr_db):
    radio = RadioConfig(snr_db=snr_db, isolation_db=400.0)  # leakage far below the noise
    scene = reference_scene(radio)
    sim = Simulator.from_scene(scene)
    cap = sim.simulate_pose(0, np.random.default_rng(int(snr_db) + 1))
    b = _boresight(cap)
    timing = int(np.floor(radio.hardware_delay_s * radio.sample_rate_hz))
    y = demodulate(cap.samples[b].astype(complex), cap.useful_starts()[b, 1:] + timing, sim.numerology)
    measured = measured_snr_db(y, cap.tx_symbols()[b])
    assert measured == pytest.approx(snr_db, abs=0.3)
    # before the first echo arrives the window holds noise only, of variance σ²
    quiet = cap.samples[:, :3800].astype(complex)
    assert 10 * np.log10(np.mean(np.abs(quiet) ** 2) / noise_variance(radio)) == pytest.approx(0, abs=0.05)


def test_grid_mode_noise_matches_too():
    radio = RadioConfig(snr_db=10.0, isolation_db=400.0)
    cap = Simulator.from_scene(reference_scene(radio), CaptureMode.GRID).simulate_pose(0, np.random.default_rng(5))
    b = _boresight(cap)
    assert measured_snr_db(cap.grid[b].astype(complex), cap.tx_symbols()[b]) == pytest.approx(10.0, abs=0.3)


def test_echoes_scale_physically_from_the_reference():
    radio = RadioConfig()
    p5 = reference_echo_power(radio)
    assert noise_variance(radio) == pytest.approx(p5 / 10.0)
    assert noise_variance(RadioConfig(snr_db=20.0)) == pytest.approx(p5 / 100.0)
    # the reference echo is dominated by the specular return ∝ 1/(2r)²: compare with the closed form
    concrete_gamma, concrete_s = 0.40, 0.40
    specular = (radio.wavelength_m / (4 * np.pi * 10.0) * concrete_gamma * np.sqrt(1 - concrete_s**2) * 8) ** 2
    assert 1.0 < p5 / specular < 2.0  # plus the diffuse echo within the beam


def test_default_leakage_is_as_strong_as_the_reference_echo():
    # documented in docs/architecture.md: 70 dB isolation ↔ leakage 0.3 dB below the reference echo
    radio = RadioConfig()
    ratio_db = -radio.isolation_db - 10 * np.log10(reference_echo_power(radio))
    assert ratio_db == pytest.approx(-0.3, abs=0.1)
    assert 10 * np.log10(reference_echo_power(radio)) == pytest.approx(-69.7, abs=0.1)


def test_box_muller_noise_is_circular_gaussian_of_the_asked_variance():
    from scipy import stats

    from radioslam.sim.noise import add_noise
    variance = 2.5
    z = add_noise(np.zeros((4, 150_000), np.complex64), variance, np.random.default_rng(7)).ravel().astype(complex)
    assert np.mean(np.abs(z) ** 2) == pytest.approx(variance, rel=0.01)
    assert abs(np.mean(z**2)) < 0.01 * variance  # circular: E[z²] = 0, so the rails are equal and uncorrelated
    assert abs(np.mean(z)) < 0.01 * np.sqrt(variance)
    for rail in (z.real, z.imag):  # each rail N(0, σ²/2)
        assert stats.kstest(rail / np.sqrt(variance / 2), "norm").pvalue > 1e-3
        assert stats.kurtosis(rail) == pytest.approx(0.0, abs=0.05)
    # Box–Muller from 23-bit uniforms: |z| ≤ σ·√(23·ln 2), reached with probability 2^-23 per sample
    assert np.abs(z).max() <= np.sqrt(variance * 23 * np.log(2)) * (1 + 1e-6)
    # the tail up to there is Rayleigh: P(|z|² > 9σ²) = e^-9
    assert np.mean(np.abs(z) ** 2 > 9 * variance) == pytest.approx(np.exp(-9.0), rel=0.15)


def test_noise_depends_on_the_seed_only_and_its_halves_differ():
    from radioslam.sim.noise import add_noise
    a = add_noise(np.zeros((6, 70_001), np.complex64), 1.0, np.random.default_rng(3))
    b = add_noise(np.zeros((6, 70_001), np.complex64), 1.0, np.random.default_rng(3))
    c = add_noise(np.zeros((6, 70_001), np.complex64), 1.0, np.random.default_rng(4))
    assert np.array_equal(a, b) and not np.array_equal(a, c)
    assert abs(np.corrcoef(a[0].real, a[3].real)[0, 1]) < 0.02  # the two halves' streams are independent
    x = np.ones((2, 10), np.complex64)
    assert np.array_equal(add_noise(x, 0.0, np.random.default_rng(0)), x)  # zero variance adds nothing
