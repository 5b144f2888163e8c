"""PSS against 3GPP TS 38.211 §7.4.2.2, cross-checked with py3gpp."""

import numpy as np
import pytest
from py3gpp import nrPSS

from radioslam.config import PssKind
from radioslam.nr import pss, pss_grid, pss_zadoff_chu
from radioslam.nr.numerology import Numerology
from radioslam.nr.pss import pss_subcarrier_indices


@pytest.mark.parametrize("n_id2", [0, 1, 2])
def test_pss_equals_py3gpp(n_id2):
    # py3gpp's nrPSS takes N_ID^cell; N_ID2 = N_ID^cell mod 3
    assert np.array_equal(pss(n_id2), nrPSS(n_id2))
    assert np.array_equal(pss(n_id2), nrPSS(3 * 7 + n_id2))


def test_pss_first_values_from_the_recursion():
    # x(0..6) = 0 1 1 0 1 1 1 → d(0..6) = 1 −1 −1 1 −1 −1 −1 for N_ID2 = 0
    assert pss(0)[:7].tolist() == [1, -1, -1, 1, -1, -1, -1]


@pytest.mark.parametrize("n_id2", [0, 1, 2])
def test_pss_periodic_autocorrelation_is_ideal_m_sequence(n_id2):
    d = pss(n_id2)
    corr = np.array([np.dot(d, np.roll(d, k)) for k in range(127)])
    assert corr[0] == 127
    assert np.all(corr[1:] == -1)


def test_pss_ids_are_cyclic_shifts_by_43():
    # d(n) uses m = (n + 43·N_ID2) mod 127: the three PSS are one m-sequence shifted
    for n_id2 in (1, 2):
        assert np.array_equal(pss(n_id2), np.roll(pss(0), -43 * n_id2))


@pytest.mark.parametrize("n_id2", [0, 1, 2])
def test_zadoff_chu_variant_is_cazac(n_id2):
    z = pss_zadoff_chu(n_id2)
    assert np.allclose(np.abs(z), 1.0)
    corr = np.array([np.vdot(z, np.roll(z, k)) for k in range(127)])
    assert abs(corr[0]) == pytest.approx(127)
    assert np.max(np.abs(corr[1:])) < 1e-9


def test_pss_grid_is_centred_and_fits_the_decimated_band(radio):
    num = Numerology.from_config(radio)
    p = num.subcarrier_indices()
    grid = pss_grid(PssKind.M_SEQUENCE, 0, p)
    occupied = p[grid != 0]
    assert occupied.min() == -63 and occupied.max() == 63
    assert np.array_equal(grid[np.isin(p, pss_subcarrier_indices())], pss(0))
    # bandwidth 127·Δf fits in f_s/4 after decimation by 4 (paper §III-C)
    assert 127 * radio.subcarrier_spacing_hz < radio.sample_rate_hz / 4


def test_bad_n_id2_is_rejected():
    with pytest.raises(ValueError):
        pss(3)
