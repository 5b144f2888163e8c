"""Numerology and the sensing frame schedule (paper §II-D, 38.211 §5.3.1, 38.213 §4.1)."""

import numpy as np
import pytest

from radioslam.config import RadioConfig
from radioslam.nr import FrameSchedule, Numerology, NumerologyError, case_d_ssb_starts


def test_cyclic_prefix_lengths_mu3(radio):
    num = Numerology.from_config(radio)
    assert num.mu == 3 and num.sample_rate_hz == 122.88e6
    cp = num.cp_lengths(np.arange(112))
    assert cp[0] == 136 and cp[56] == 136
    assert set(np.delete(cp, [0, 56])) == {72}
    # a subframe is exactly 1 ms
    assert (cp + 1024).sum() == 122_880
    assert num.cp_lengths(np.array([112, 168, 113])).tolist() == [136, 136, 72]


def test_other_fft_size_scales_cp():
    num = Numerology(2048, 1584, 120e3)
    assert num.cp_normal == 144 and num.cp_extra == 128


def test_bad_spacing_is_rejected():
    with pytest.raises(NumerologyError):
        Numerology(1024, 792, 100e3)


def test_case_d_ssb_positions():
    starts = case_d_ssb_starts()
    assert len(starts) == 64
    n = np.array([0, 1, 2, 3, 5, 6, 7, 8, 10, 11, 12, 13, 15, 16, 17, 18])
    expected = np.sort(np.concatenate([np.array([4, 8, 16, 20]) + 28 * k for k in n]))
    assert np.array_equal(np.sort(starts), expected)


def test_frame_has_304_reserved_symbols(radio):
    fs = FrameSchedule.from_config(radio)
    assert fs.symbols_per_frame_total == 20 * 8 * 14 == 2240
    assert fs.burst_symbols == 560  # the first 5 ms
    ssb = fs.ssb_symbols()
    assert len(np.unique(ssb)) == 256
    reserved = fs.reserved_symbols()
    assert len(reserved) == 304
    assert not np.intersect1d(reserved, ssb).size


def test_beam_schedule_gives_twelve_distinct_reserved_symbols_per_beam(radio):
    fs = FrameSchedule.from_config(radio)
    k, b = np.meshgrid(np.arange(4), np.arange(47), indexing="ij")
    sens = fs.sensing_symbols(k.ravel(), b.ravel())
    assert sens.shape == (188, 12) and fs.repetitions == 12
    assert len(np.unique(sens)) == 188 * 12  # no symbol serves two beams
    frame = sens // 2240
    within = sens % 2240
    assert np.all(np.isin(within, fs.reserved_symbols()))
    # orientation k uses frames 2k and 2k+1, six symbols in each
    assert np.all(frame[:, :6] == 2 * k.ravel()[:, None]) and np.all(frame[:, 6:] == 2 * k.ravel()[:, None] + 1)
    pss = fs.pss_symbol(k.ravel(), b.ravel())
    assert np.all(np.isin(pss % 2240, case_d_ssb_starts()))
    assert len(np.unique(pss)) == 188


def test_more_beams_than_a_burst_take_more_frames():
    """61 azimuth beams, or 7 elevation rows of 47 (issue #16): ⌈beams/50⌉ bursts of 2 frames per orientation,
    every beam on an SSB of its burst's first frame and 12 reserved symbols of its own."""
    for radio, bursts in ((RadioConfig(codebook_bits=7, beams_per_side=30), 2), (RadioConfig(elevation_beams=7), 7)):
        fs = FrameSchedule.from_config(radio)
        assert fs.beams_per_burst == 50 and fs.bursts == bursts and fs.frames_per_orientation == 2 * bursts
        k, b = (a.ravel() for a in np.meshgrid(np.arange(4), np.arange(fs.beams), indexing="ij"))
        sens, pss = fs.sensing_symbols(k, b), fs.pss_symbol(k, b)
        assert len(np.unique(sens)) == sens.size == 4 * fs.beams * 12  # no symbol serves two beams
        assert np.all(np.isin(sens % 2240, fs.reserved_symbols()))
        assert np.array_equal(pss % 2240, case_d_ssb_starts()[fs.ssb_index(b)]) and len(np.unique(pss)) == len(b)
        first_frame = (k * bursts + b // 50) * 2
        assert np.array_equal(pss // 2240, first_frame)
        assert np.all(sens[:, :6] // 2240 == first_frame[:, None])
        assert np.all(sens[:, 6:] // 2240 == first_frame[:, None] + 1)
        assert sens.max() // 2240 == 4 * 2 * bursts - 1  # the pose's last frame


def test_flat_scan_schedule_is_one_burst(radio):
    fs = FrameSchedule.from_config(radio)
    assert fs.bursts == 1 and fs.frames_per_orientation == 2
    assert np.array_equal(fs.ssb_index(np.arange(47)), np.arange(47))
