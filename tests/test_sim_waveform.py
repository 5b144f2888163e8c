"""Waveform synthesis against the continuous-time NR signal, and waveform ≡ grid mode (eq. (4))."""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from radioslam.capture import CaptureMode
from radioslam.nr import Numerology, demodulate, qam16_modulate, random_bits
from radioslam.nr.ofdm import symbol_starts
from radioslam.scene import builtin_scene
from radioslam.sim import Simulator
from radioslam.sim.channel import binned_channel_response, channel_response, delay_phasors
from radioslam.sim.waveform import synthesize_windows

NUM = Numerology(1024, 792, 120e3)


def brute_force(grid, cp, delays_samples, gains, length):
    """y[n] = Σ_k g_k s(n − τ_k): 38.211 §5.3.1 evaluated sample by sample, no FFT.

    A sample within 1e-9 of a symbol boundary counts as inside the later symbol, the
    synthesizer's convention against round-off in τ·f_s.
    """
    n_fft = NUM.fft_size
    p = NUM.subcarrier_indices()
    starts = symbol_starts(cp, n_fft)
    ends = starts + cp + n_fft
    n = np.arange(length)
    y = np.zeros(length, complex)
    for g, tau in zip(gains, delays_samples):  # a handful of paths in this reference
        t = n - tau
        for sym in range(len(cp)):
            inside = (t >= starts[sym] - 1e-9) & (t < ends[sym] - 1e-9)
            phase = np.exp(2j * np.pi * np.outer(t[inside] - starts[sym] - cp[sym], p) / n_fft)
            y[inside] += g * phase @ grid[sym] / np.sqrt(n_fft)
    return y


@given(st.lists(st.floats(0.0, 60.0), min_size=1, max_size=5),
       st.lists(st.sampled_from([72, 136]), min_size=1, max_size=3), st.integers(0, 2**31))
@example([10.37, 12.0, 15.81, 33.5, 12.0001], [72, 136, 72], 1)  # an exact integer and a near-tie
@settings(max_examples=15, deadline=None)
def test_synthesis_equals_the_continuous_time_signal_for_any_delays(delays, cps, seed):
    rng = np.random.default_rng(seed)
    cp = np.array(cps)
    grid = qam16_modulate(random_bits(rng, (len(cp), 792 * 4)))
    delays = np.array(delays)
    gains = rng.standard_normal(len(delays)) + 1j * rng.standard_normal(len(delays))
    length = int((cp + 1024).sum() + 64)
    d_min, _, cum = binned_channel_response(gains[None], delays, NUM.subcarrier_indices(), 120e3,
                                            NUM.sample_rate_hz)
    fast = synthesize_windows(grid[None], cp[None], cum, d_min, NUM, length)[0]
    slow = brute_force(grid, cp, delays, gains, length)
    assert np.max(np.abs(fast - slow)) < 2e-6 * np.max(np.abs(slow))


def test_single_path_demodulates_to_the_eq4_phase_ramp(rng):
    cp = np.array([72, 72])
    grid = qam16_modulate(random_bits(rng, (2, 792 * 4)))
    tau = 3932.16  # 32 µs at 122.88 MSps
    d_min, _, cum = binned_channel_response(np.ones((1, 1)), np.array([tau]), NUM.subcarrier_indices(), 120e3,
                                            NUM.sample_rate_hz)
    window = synthesize_windows(grid[None], cp[None], cum, d_min, NUM, 6400)
    timing = 3933  # any FFT start inside the CP after the arrival
    y = demodulate(window, symbol_starts(cp, 1024) + cp + timing, NUM)[0]
    p = NUM.subcarrier_indices()
    expected = grid * np.exp(-2j * np.pi * p * tau / 1024) * np.exp(2j * np.pi * p * timing / 1024)
    assert np.allclose(y, expected, atol=2e-6)


def test_delay_phasors_match_direct_exponentials(rng):
    tau = rng.uniform(0, 40e-6, 17)
    p = NUM.subcarrier_indices()
    assert np.allclose(delay_phasors(tau, p, 120e3), np.exp(-2j * np.pi * 120e3 * np.outer(tau, p)), atol=1e-9)


def test_waveform_mode_demodulates_to_grid_mode():
    scene = builtin_scene("paper-cnv").with_radio(snr_db=300.0)
    wave = Simulator.from_scene(scene, CaptureMode.WAVEFORM).simulate_pose(7, np.random.default_rng(3))
    grid_sim = Simulator.from_scene(scene, CaptureMode.GRID)
    grid = grid_sim.simulate_pose(7, np.random.default_rng(3))
    assert np.array_equal(wave.tx_bits, grid.tx_bits)
    y = demodulate(wave.samples.astype(complex), wave.useful_starts()[:, 1:] + grid.fft_offset_samples, NUM)
    assert np.max(np.abs(y - grid.grid)) < 1e-6 * np.max(np.abs(grid.grid))


def test_grid_mode_is_eq4(radio):
    scene = builtin_scene("single-plate:4").with_radio(snr_db=300.0)
    sim = Simulator.from_scene(scene, CaptureMode.GRID)
    cap = sim.simulate_pose(0, np.random.default_rng(0))
    from radioslam.sim import beam_path_gains, echo_paths
    paths = echo_paths(scene, scene.poses[0])
    gains = beam_path_gains(sim.beams, paths)
    p = NUM.subcarrier_indices()
    h = channel_response(gains, paths.delay_s + radio.hardware_delay_s, p, 120e3)
    expected = h[:, None, :] * np.exp(2j * np.pi * p * sim.timing_offset() / 1024) * cap.tx_symbols()
    assert np.allclose(cap.grid, expected, atol=1e-6 * np.abs(expected).max())


def test_pss_arrives_after_hardware_delay_plus_round_trip(radio):
    r = 9.6
    scene = builtin_scene(f"single-plate:{r}").with_radio(snr_db=300.0, isolation_db=300.0)
    sim = Simulator.from_scene(scene)
    cap = sim.simulate_pose(0, np.random.default_rng(0))
    from radioslam.config import PssKind
    from radioslam.nr import modulate, pss_grid
    b = np.flatnonzero((cap.orientation == 0) & (cap.beam_index == 0))[0]
    ref = modulate(pss_grid(PssKind.M_SEQUENCE, 0, NUM.subcarrier_indices())[None], np.array([72]), NUM)
    x = cap.samples[b].astype(complex)
    corr = np.abs(np.correlate(x, ref, mode="valid"))
    expected = (radio.hardware_delay_s + 2 * r / 299_792_458.0) * radio.sample_rate_hz
    assert abs(np.argmax(corr) - expected) <= 1.0


def test_identical_mode_repeats_the_payload():
    scene = builtin_scene("single-plate:4").with_radio(data="identical")
    cap = Simulator.from_scene(scene, CaptureMode.GRID).simulate_pose(0, np.random.default_rng(0))
    assert np.all(cap.tx_bits == cap.tx_bits[:, :1])
    different = Simulator.from_scene(builtin_scene("single-plate:4"), CaptureMode.GRID)
    bits = different.simulate_pose(0, np.random.default_rng(0)).tx_bits
    assert not np.all(bits == bits[:, :1])


def test_same_seed_same_capture_and_pose_streams_are_independent():
    sim = Simulator.from_scene(builtin_scene("paper-cnv"))
    a = sim.simulate_pose(4, np.random.default_rng(11))
    b = sim.simulate_pose(4, np.random.default_rng(11))
    c = sim.simulate_pose(4, np.random.default_rng(12))
    assert np.array_equal(a.samples, b.samples) and np.array_equal(a.tx_bits, b.tx_bits)
    assert not np.array_equal(a.samples, c.samples)
    first_two = [cap.samples for _, cap in zip(range(2), sim.simulate(5))]
    again = [cap.samples for _, cap in zip(range(2), sim.simulate(5))]
    assert all(np.array_equal(x, y) for x, y in zip(first_two, again))
    assert not np.array_equal(first_two[0], first_two[1])


def test_window_holds_burst_plus_hardware_delay_plus_max_range(radio):
    sim = Simulator.from_scene(builtin_scene("paper-cnv"))
    burst = (sim.numerology.cp_lengths(sim.schedule.window_symbols(0, 0)) + 1024).sum()
    assert sim.window_length >= burst + radio.hardware_delay_s * radio.sample_rate_hz + \
        2 * radio.max_range_m / 299_792_458.0 * radio.sample_rate_hz
    with pytest.raises(ValueError):
        synthesize_windows(np.zeros((1, 1, 792)), np.array([[72]]), np.ones((1, 1, 792)), 10, NUM, 1000)


@given(st.lists(st.floats(0.0, 4000.0), min_size=1, max_size=40), st.integers(0, 2**31),
       st.sampled_from([(1024, 792), (1024, 1024), (256, 200)]))
@settings(max_examples=20, deadline=None)
def test_binned_response_equals_the_direct_phasor_sums(delays, seed, sizes):
    # the per-bin Taylor series is exact to single precision on any band, up to the full FFT
    n, n_sc = sizes
    rng = np.random.default_rng(seed)
    delays = np.array(delays)
    gains = rng.standard_normal((3, len(delays))) + 1j * rng.standard_normal((3, len(delays)))
    p = np.arange(n_sc) - n_sc // 2
    d_min, d_max, cum = binned_channel_response(gains, delays, p, 120e3, n * 120e3)
    d = np.ceil(delays - 1e-9).astype(int)
    assert (d_min, d_max) == (d.min(), d.max()) and cum.shape == (d_max - d_min + 1, 3, n_sc)
    scale = np.abs(gains).sum(axis=1, keepdims=True)
    for m in range(d_max - d_min + 1):
        arrived = d <= d_min + m
        direct = gains[:, arrived] @ np.exp(-2j * np.pi * np.outer(delays[arrived], p) / n)
        assert np.max(np.abs(cum[m] - direct) / scale) < 1e-6


def _simulate_one_beam(seed):
    sim = Simulator.from_scene(builtin_scene("single-plate:4"), rows=np.array([0, 1]))
    return sim.simulate_pose(0, np.random.default_rng(seed)).samples


def test_a_forked_child_simulates_with_its_own_workers_and_the_same_result():
    # the synthesis's thread pool lives for the process; a child made by fork inherits none of its
    # threads and must start its own (a pool object without threads would hang the child)
    import multiprocessing

    here = _simulate_one_beam(5)  # the parent's pool is running now
    with multiprocessing.get_context("fork").Pool(1) as pool:
        there = pool.apply_async(_simulate_one_beam, (5,)).get(timeout=120)
    assert np.array_equal(here, there)
