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
