"""Steering vector (eq. (1)), DFT codebook and the two-way beam gain ϖ (eq. (4))."""

import numpy as np
import pytest
from scipy.signal import find_peaks

from radioslam.antenna import BeamSet, array_response, beam_angle, dft_codebook, steering_vector


def _first_sidelobe_db(gain: np.ndarray) -> float:
    peaks, _ = find_peaks(gain)
    levels = np.sort(gain[peaks])[::-1]
    return 10 * np.log10(levels[1] / levels[0])


def test_steering_vector_eq1():
    a = steering_vector(np.array(0.125), 8)
    assert np.allclose(a, np.exp(-2j * np.pi * 0.125 * np.arange(8)))


def test_beam_set_has_188_beams_within_45_95_degrees(radio):
    beams = BeamSet.from_config(radio)
    assert len(beams) == 188 and beams.per_orientation == 47
    edge = np.degrees(beam_angle(np.array([-23, 23]), 6))
    assert edge == pytest.approx([-45.95, 45.95], abs=0.005)
    assert np.degrees(np.arcsin(2 * 23 / 64)) == pytest.approx(45.95, abs=0.005)
    assert sorted(set(beams.orientation_angle)) == pytest.approx([0, np.pi / 2, np.pi, 3 * np.pi / 2])


def test_codebook_is_unit_norm_dft(radio):
    w = dft_codebook(8, 6, np.arange(64))
    assert np.allclose(np.linalg.norm(w, axis=1), 1.0)
    # entries 8 apart are orthogonal (spatial frequencies 1/8 apart for N = 8)
    assert abs(np.vdot(w[0], w[8])) < 1e-12


def test_one_way_first_sidelobe_is_minus_12_8_db():
    theta = np.linspace(-np.pi / 2, np.pi / 2, 400_001)
    w = dft_codebook(8, 6, np.array([0]))
    af = np.abs(array_response(w, 0.5 * np.sin(theta))[0]) ** 2 / 8  # normalized power
    assert af.max() == pytest.approx(1.0)
    assert _first_sidelobe_db(af) == pytest.approx(-12.8, abs=0.05)


def test_two_way_gain_sidelobe_is_minus_25_6_db_and_peak_is_n():
    beams = BeamSet(8, 6, 23, 4, element_exponent=0.0)
    theta = np.linspace(-np.pi / 2 + 1e-6, np.pi / 2 - 1e-6, 200_001)
    gain = beams.two_way_gain(theta)[23]  # orientation 0, i = 0
    assert gain.max() == pytest.approx(8.0)  # ϖ = |w^H a|² peaks at N
    power = (gain / gain.max()) ** 2  # two-way power pattern
    assert _first_sidelobe_db(power) == pytest.approx(-25.6, abs=0.1)


def test_two_way_gain_matches_brute_force_and_peaks_at_beam_angle(radio):
    beams = BeamSet.from_config(radio)
    rng = np.random.default_rng(1)
    theta = rng.uniform(-np.pi, np.pi, 50)
    gain = beams.two_way_gain(theta)
    w = beams.weights()
    for b in rng.choice(len(beams), 10, replace=False):
        local = np.angle(np.exp(1j * (theta - beams.orientation_angle[b])))
        a = steering_vector(0.5 * np.sin(local), 8)
        varpi = (w[b].conj() @ a.T) * (a.conj() @ w[b])  # w^H a_R a_T^H w, eq. (4)
        element = np.where(np.abs(local) < np.pi / 2, np.cos(local), 0.0)
        assert np.allclose(gain[b], varpi.real * element, atol=1e-12)
        assert np.allclose(varpi.imag, 0, atol=1e-12)
    # each beam's maximum over a fine grid sits at its physical angle arcsin(2ϑ_i)
    fine = np.linspace(-np.pi, np.pi, 72_001)
    g = BeamSet(8, 6, 23, 4, element_exponent=0.0).two_way_gain(fine)
    peak = fine[np.argmax(g, axis=1)]
    assert np.allclose(np.angle(np.exp(1j * (peak - beams.angle))), 0, atol=2e-4)


def test_nothing_behind_the_array(radio):
    beams = BeamSet.from_config(radio)
    gain = beams.two_way_gain(np.array([np.pi]))  # behind orientation 0
    assert np.all(gain[beams.orientation == 0] == 0)
    assert np.all(gain[beams.orientation == 2].max() > 0)
