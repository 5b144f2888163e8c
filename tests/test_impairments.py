"""Hardware impairments (issue #13, point 5) against their closed forms: the image rejection ratio
of an I/Q imbalance, the SNR of a b-bit quantizer and its clipping, the sidelobe floor that random
element errors raise; off by default, refused where the capture mode cannot model them."""

import numpy as np
import pytest
import yaml

from radioslam.antenna.array import array_response, spatial_frequency
from radioslam.antenna.codebook import BeamSet, dft_codebook, element_responses
from radioslam.capture import CaptureMode
from radioslam.config import Impairments, RadioConfig
from radioslam.scene import load_scene, scene_to_yaml
from radioslam.scene.loader import scene_from_mapping
from radioslam.sim import Simulator
from radioslam.sim.errors import SimulationError
from radioslam.sim.impairments import (
    apply_iq_imbalance,
    compress,
    gaussian_adc_snr_db,
    image_rejection_db,
    quantization_snr_db,
    quantize,
    rapp,
    receiver_chain,
)


@pytest.mark.parametrize("gain_db, phase_deg", [(0.5, 0.0), (0.0, 3.0), (1.0, 5.0), (-0.3, -2.0)])
def test_iq_imbalance_leaves_an_image_at_minus_f_one_irr_below_the_tone(gain_db, phase_deg):
    n, k = 1024, 37
    tone = np.exp(2j * np.pi * k * np.arange(n) / n)
    spectrum = np.abs(np.fft.fft(apply_iq_imbalance(tone, gain_db, phase_deg))) ** 2
    g, phi = 10 ** (gain_db / 20), np.radians(phase_deg)
    closed_form = 10 * np.log10((1 + 2 * g * np.cos(phi) + g**2) / (1 - 2 * g * np.cos(phi) + g**2))
    assert np.isclose(10 * np.log10(spectrum[k] / spectrum[n - k]), closed_form, atol=1e-6)
    assert np.isclose(image_rejection_db(gain_db, phase_deg), closed_form)
    others = np.delete(spectrum, [k, n - k])
    assert others.max() < 1e-12 * spectrum[k]  # nothing but the tone and its image


def test_a_balanced_receiver_and_an_ideal_adc_change_nothing():
    x = np.random.default_rng(0).standard_normal((3, 500)).astype(np.complex64)
    assert np.array_equal(receiver_chain(x, Impairments()), x)
    assert image_rejection_db(0.0, 0.0) == float("inf")


# (12 bits, 12 dB) is left out: its error is 60 clipped samples of 2·10⁶, too few for a 0.3 dB estimate
@pytest.mark.parametrize("bits, backoff_db", [(4, 9.0), (4, 12.0), (4, 15.0), (8, 9.0), (8, 12.0), (8, 15.0),
                                              (12, 9.0), (12, 15.0)])
def test_quantization_snr_is_six_db_per_bit_less_the_backoff_until_clipping_sets_it(bits, backoff_db):
    """A Gaussian rail (OFDM): SNR = −10 log10(Δ²/12 + clipped tails) in units of σ², which is
    6.02·b + 4.77 − backoff while the tails are negligible."""
    rng = np.random.default_rng(bits)
    x = (rng.standard_normal((4, 250_000)) + 1j * rng.standard_normal((4, 250_000))) / np.sqrt(2)
    error = quantize(x, bits, backoff_db) - x
    measured = 10 * np.log10(np.mean(np.abs(x) ** 2) / np.mean(np.abs(error) ** 2))
    assert abs(measured - gaussian_adc_snr_db(bits, backoff_db)) < 0.3
    if bits == 4 and backoff_db >= 12:  # quantization-limited: the textbook rule
        assert abs(gaussian_adc_snr_db(bits, backoff_db) - quantization_snr_db(bits, backoff_db)) < 0.1


def test_the_adc_clips_at_its_full_scale_and_has_2_to_the_b_levels():
    x = np.linspace(-10, 10, 4001)[None, :] * (1 + 1j)
    rms = np.sqrt(np.mean(x.real**2))
    q = quantize(x, 3, 6.0)
    full_scale = rms * 10 ** (6.0 / 20)
    step = 2 * full_scale / 8
    assert len(np.unique(q.real)) == 8
    assert np.isclose(q.real.max(), full_scale - step / 2) and np.isclose(q.real.min(), -full_scale + step / 2)


def test_element_errors_raise_the_sidelobe_floor_by_their_variance():
    """Random element responses e_n: at the ideal pattern's nulls the one-way power |w^H(e∘a)|² averages
    E|e − 1|²·‖w‖² (‖w‖ = 1), the classic random-error sidelobe floor."""
    n, bits = 8, 6
    w = dft_codebook(n, bits, np.array([0]))
    nulls = spatial_frequency(np.arcsin(2 * np.arange(1, 4) / n))  # sin θ = 2k/N: nulls of boresight
    assert np.abs(array_response(w, nulls)).max() < 1e-12
    impairment = dict(element_gain_db=0.5, element_phase_deg=8.0)
    powers, deviations = [], []
    for seed in range(400):
        tx, _ = element_responses(Impairments(**impairment, element_seed=seed), n)
        e = np.array(tx)
        powers.append(np.abs(array_response(w * e.conj(), nulls)) ** 2)
        deviations.append(np.abs(e - 1) ** 2)
    assert np.isclose(np.mean(powers), np.mean(deviations), rtol=0.15)
    assert element_responses(Impairments(), n) is None


def test_element_errors_change_the_two_way_gain_and_ideal_arrays_keep_it():
    ideal = BeamSet.from_config(RadioConfig())
    radio = RadioConfig(impairments=Impairments(element_gain_db=1.0, element_phase_deg=10.0, element_seed=3))
    distorted = BeamSet.from_config(radio)
    angles = np.radians(np.linspace(-80, 80, 161))
    g0, g1 = ideal.two_way_gain(angles), distorted.two_way_gain(angles)
    assert np.allclose(g0.max(), ideal.n_elements)  # the two-way peak is N
    assert 0.5 < g1.max() / g0.max() < 1.5 and not np.allclose(g0, g1)


def test_impairments_live_in_the_scene_file_and_grid_mode_refuses_the_time_domain_ones():
    scene = load_scene("single-plate:4.8").with_radio(impairments={"adc_bits": 8, "iq_phase_deg": 2.0})
    again = scene_from_mapping(yaml.safe_load(scene_to_yaml(scene)), "round-trip")
    assert again.radio.impairments == scene.radio.impairments
    with pytest.raises(SimulationError, match="waveform"):
        Simulator.from_scene(scene, CaptureMode.GRID, rows=[23]).simulate_pose(0, np.random.default_rng(0))
    capture = Simulator.from_scene(scene, rows=[23]).simulate_pose(0, np.random.default_rng(0))
    assert len(np.unique(capture.samples.real)) <= 2**8


def test_a_hardware_delay_drift_after_calibration_moves_every_range_by_c_times_drift_over_two():
    """Calibrated before the drift (eq. (11) on the plates), sensed after it: the ranges move by c·δ/2."""
    from radioslam.config import SPEED_OF_LIGHT
    from radioslam.sensing import Receiver, estimate_hardware_delay
    from radioslam.sim.calibration_targets import calibration_ranges, plate_simulator, simulate_calibration_captures

    drift = 200e-12
    radio = RadioConfig(impairments=Impairments(hardware_delay_drift_s=drift))
    ranges = calibration_ranges(radio)
    calibration = estimate_hardware_delay(simulate_calibration_captures(radio, ranges, 0), ranges)
    assert abs(calibration.hardware_delay_s - radio.hardware_delay_s) < 20e-12  # calibrated before the drift
    capture = plate_simulator(radio, 4.8).simulate_pose(0, np.random.default_rng(1))
    sensed = Receiver(radio, calibration.hardware_delay_s).sense(capture).range_m[0, 0]
    assert abs(sensed - 4.8 - SPEED_OF_LIGHT * drift / 2) < 4e-3


@pytest.mark.parametrize("smoothness", [1.0, 2.0, 5.0])
def test_rapp_is_linear_when_small_saturates_when_large_and_compresses_1_db_where_the_closed_form_says(smoothness):
    saturation = 2.0
    assert np.isclose(rapp(np.array(1e-4), saturation, smoothness), 1e-4)
    assert np.isclose(rapp(np.array(1e6), saturation, smoothness), saturation, rtol=1e-6)
    one_db = saturation * (10 ** (smoothness / 10) - 1) ** (1 / (2 * smoothness))
    assert np.isclose(20 * np.log10(rapp(np.array(one_db), saturation, smoothness) / one_db), -1.0)


@pytest.mark.parametrize("backoff_db", [0.0, 3.0, 8.0])
def test_pa_compression_in_band_is_bussgangs_gain_times_the_symbols_plus_uncorrelated_distortion(backoff_db):
    """OFDM time samples are nearly complex Gaussian: a memoryless PA gives y = α·x + d with
    α = E[f(A)·A]/E[A²] (A Rayleigh) and d uncorrelated with x, on every subcarrier."""
    from radioslam.nr.numerology import Numerology
    from radioslam.nr.qam import qam16_modulate, random_bits

    radio = RadioConfig()
    num = Numerology.from_config(radio)
    rng = np.random.default_rng(0)
    x = qam16_modulate(random_bits(rng, (64, 12, radio.n_subcarriers * 4)))
    y = compress(x, num, backoff_db, 2.0)
    measured = np.vdot(x, y) / np.vdot(x, x)
    # the Bussgang gain of the Rapp curve over a Rayleigh amplitude (σ² = the time samples' mean power)
    sigma2 = np.mean(np.abs(x) ** 2) * radio.n_subcarriers / radio.fft_size
    a = np.linspace(0, 8 * np.sqrt(sigma2), 200_001)
    density = 2 * a / sigma2 * np.exp(-a**2 / sigma2)
    saturation = np.sqrt(sigma2) * 10 ** (backoff_db / 20)
    integrand = rapp(a, saturation, 2.0) * a * density  # (np.trapezoid is numpy ≥ 2; the pin is 1.26)
    alpha = float(np.sum(0.5 * (integrand[1:] + integrand[:-1]) * np.diff(a))) / sigma2
    assert abs(measured.imag) < 1e-3 and np.isclose(measured.real, alpha, rtol=0.01)
    distortion = y - measured * x
    assert abs(np.vdot(x, distortion)) / np.sqrt(np.vdot(x, x).real * np.vdot(distortion, distortion).real) < 1e-3


def test_reproduce_impairments_tabulates_table1_per_profile_and_the_drift_is_the_bias_it_predicts(tmp_path):
    """`radioslam reproduce impairments`: one row per profile; the hardware-delay drift moves Table I's
    refined ranges by c·δ/2 (1.5 cm for 100 ps), the ideal radio stays at millimetres; an unknown
    profile for table1 is one line and exit status 2."""
    import json
    import subprocess
    import sys

    from radioslam.config import SPEED_OF_LIGHT
    from radioslam.eval.experiments.impairments import PROFILES

    def cli(*args):
        return subprocess.run([sys.executable, "-m", "radioslam.cli", *args], capture_output=True, text=True,
                              timeout=600)

    done = cli("reproduce", "impairments", "--out", str(tmp_path), "--json", "--trials", "2")
    assert done.returncode == 0, done.stderr
    rows = {r["profile"]: r for r in json.loads(done.stdout)["rows"]}
    assert list(rows) == list(PROFILES) and (tmp_path / "impairments.csv").exists()
    assert rows["ideal"]["rmse_refined_m"] < 5e-3 < rows["ideal"]["rmse_ifft_m"]
    assert rows["ideal"]["rmse_paper_bisection_m"] < 5e-3  # a lone plate: one lobe, the bisection holds too
    # the IFFT grid peak is at most half a cell (0.61 m) off when it is the plate's own lobe (the leakage's
    # skirt, 10 dB stronger at broadside since the arrays' coupling, once made it 6 m)
    assert all(r["rmse_ifft_m"] < 0.61 for r in rows.values())
    bias = SPEED_OF_LIGHT * PROFILES["drift"].hardware_delay_drift_s / 2
    assert abs(rows["drift"]["rmse_refined_m"] - bias) < 3e-3
    bad = cli("reproduce", "table1", "--out", str(tmp_path), "--impairments", "bogus")
    assert bad.returncode == 2 and "--impairments" in bad.stderr and len(bad.stderr.strip().splitlines()) == 1


def _residual_phase(oscillators, linewidth_hz=1e3, range_m=30.0):
    """angle(r/r₀) of a lone echo with and without phase noise (same data, no noise to speak of), on the
    received samples whose transmitted sample lies inside a symbol's useful part; and the echo's delay."""
    from radioslam.eval.point_targets import capture_point_targets, point_paths
    from radioslam.nr.ofdm import symbol_starts
    from radioslam.sim import Simulator

    base = RadioConfig(snr_db=300.0)
    phases = []
    for width in (0.0, linewidth_hz):
        radio = base.model_copy(update={"impairments": Impairments(phase_noise_linewidth_hz=width,
                                                                   oscillators=oscillators)})
        paths = point_paths(radio, range_m, 0.0, 300.0)
        capture = capture_point_targets(radio, paths, list(range(radio.beams_per_orientation)),
                                        np.random.default_rng(7))
        phases.append(capture.samples.astype(np.complex128))
    sim = Simulator.from_radio(base, rows=np.arange(base.beams_per_orientation))
    n = base.fft_size
    delay = int(round((base.hardware_delay_s + paths.delay_s[0]) * base.sample_rate_hz))
    starts = symbol_starts(sim.window_cp, n) + sim.window_cp  # (B, L) useful parts from the burst's start
    u = np.arange(phases[0].shape[1]) - delay  # the transmitted sample behind each received one
    inside = ((u[None, None, :] >= starts[..., None] + 32)
              & (u[None, None, :] < starts[..., None] + n - 32)).any(axis=1)
    ratio = phases[1] / phases[0]
    return np.angle(ratio[inside]), paths.delay_s[0]


def test_with_one_lo_the_phase_noise_left_on_an_echo_has_the_variance_two_pi_linewidth_times_its_delay():
    """φ(t − τ) − φ(t) of a Wiener LO: 2π·Δf·τ (1.26·10⁻³ rad² for 1 kHz and 30 m), whatever the capture's
    length; two separate LOs wander by far more over the same samples."""
    from radioslam.config import Oscillators

    residual, tau = _residual_phase(Oscillators.SHARED)
    assert np.var(residual) == pytest.approx(2 * np.pi * 1e3 * tau, rel=0.1)
    separate, _ = _residual_phase(Oscillators.SEPARATE)
    assert np.var(separate) > 20 * np.var(residual)


def test_phase_noise_needs_the_waveform_and_changes_nothing_when_off():
    from radioslam.capture import CaptureMode
    from radioslam.sim import Simulator
    from radioslam.sim.errors import SimulationError

    noisy = RadioConfig(impairments=Impairments(phase_noise_linewidth_hz=100.0))
    with pytest.raises(SimulationError):
        Simulator.from_scene(load_scene("single-plate:4").with_radio(**noisy.model_dump()), CaptureMode.GRID,
                             rows=[23]).simulate_pose(0, np.random.default_rng(0))


def _plate(range_m, width_m):
    return scene_from_mapping({"version": 1, "name": "plate", "trajectory": {"poses": [[0.0, 0.0, 0.0]]},
                               "walls": [{"points": [[range_m, -width_m / 2], [range_m, width_m / 2]],
                                          "material": "metal"}]}, "test")


@pytest.mark.parametrize("range_m", [0.8, 4.0, 12.8])
def test_facets_of_a_wall_sum_to_its_image_source_and_of_a_plate_to_the_fresnel_integral(range_m):
    """Stationary phase: a wall far wider than its first Fresnel zone √(λR/2) returns the image source's
    echo; a strip of width L ≪ R returns √2·|C(w) + jS(w)| of it, w = (L/2)·√(4/(λR)) (Fresnel integrals;
    paraxial, so not at 0.8 m, where the 1 m plate spans ±32°)."""
    from scipy.special import fresnel

    from radioslam.sim.facets import facet_paths
    from radioslam.sim.paths import _echo, specular_paths

    for width, expected in ((20.0, None), (1.0, "fresnel"))[:1 if range_m < 1 else 2]:
        scene = _plate(range_m, width)
        image = specular_paths(scene, np.zeros(3), scene.radio)[1][0]
        r, gain, *_ = facet_paths(scene, np.zeros(3), scene.radio)
        total = _echo(r, gain, scene.radio)[1].sum()
        if expected is None:
            assert abs(total / image - 1) < 0.02
        else:
            s, c = fresnel(width / 2 * np.sqrt(4 / (scene.radio.wavelength_m * range_m)))
            assert abs(abs(total / image) - np.sqrt(2) * abs(c + 1j * s)) < 0.02
