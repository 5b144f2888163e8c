"""M-bit DFT codebook, beam selection and the two-way beam gain ϖ (paper §III, §II-C).

w_i = a(ϑ_i)/√N with ϑ_i = i/2^M. The paper keeps i = −23…23 (47 beams, ±45.95°
for M = 6, N = 8) and rotates the terminal to 4 orientations k·π/2: 188 beams.

The two-way gain of beam i towards a path at angle θ (eq. (4)) is
ϖ_i(θ) = w_i^H a_R(θ) a_T^H(θ) w_i = |w_i^H a(θ)|² for the identical TX and RX
arrays, sidelobes included; its peak is N. An element pattern cos^q(θ) (power,
each way) bounds the arrays to the half space in front of them.

Elevation (issue #16): the 8×8 array's N rows take a second DFT codebook over its
columns, v_j = a(j/2^M)/√N for the odd set j = −J … J of ``elevation_beams`` indices.
Beam (i, j) is w_i ⊗ v_j; with the direction cosines u_y = cos ε sin φ, u_z = sin ε
of a path at azimuth φ (off the array normal) and elevation ε its two-way gain is

    ϖ_{ij}(φ, ε) = |w_i^H a(u_y/2)|² · |v_j^H a(u_z/2)|²/N · (cos ε cos φ)^q,

the vertical factor normalized to 1 at its peak, so the horizontal beam j = 0 on a
horizontal path is the flat scan's ϖ_i. Beam (i, j) points where u_y = 2i/2^M,
u_z = 2j/2^M: at elevation arcsin(u_z) and azimuth arcsin(u_y/cos ε) (a cone: a
raised beam of the same i points further off the normal).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.antenna.array import array_response, stacked_coupling, steering_vector
from radioslam.config import Impairments, LeakageCoupling, RadioConfig

# a path's row (:meth:`BeamSet.two_way_gain`) when it reaches every elevation row through its vertical gain
ANY_ROW = np.iinfo(np.int32).min


def dft_codebook(n_elements: int, bits: int, indices: np.ndarray) -> np.ndarray:
    """Weights w_i = a(i/2^M)/√N, shape (len(indices), N)."""
    return steering_vector(np.asarray(indices) / 2**bits, n_elements) / np.sqrt(n_elements)


def vertical_factors(n_elements: int, bits: int, indices: np.ndarray, u_z: np.ndarray) -> np.ndarray:
    """|v_j^H a(u_z/2)|/√N (J, ...) of the elevation rows j towards direction cosines u_z (...), one way."""
    v = dft_codebook(n_elements, bits, np.asarray(indices))
    return np.abs(array_response(v, 0.5 * np.asarray(u_z))) / np.sqrt(n_elements)


def beam_angle(indices: np.ndarray, bits: int) -> np.ndarray:
    """Physical angle arcsin(2·ϑ_i) of codebook entry i (d = λ/2), radians."""
    return np.arcsin(2.0 * np.asarray(indices) / 2**bits)


def nearest_beam_row(beam_angles: np.ndarray, bearing_rad: float) -> int:
    """Row of the beam whose terminal-frame pointing angle is closest to ``bearing_rad``."""
    return int(np.argmin(np.abs(np.angle(np.exp(1j * (np.asarray(beam_angles) - bearing_rad))))))


def element_responses(impairments: Impairments, n_elements: int) -> tuple[tuple[complex, ...], ...] | None:
    """Each array's per-element complex response (TX, RX): (1 + gain error)·e^{j phase error}, drawn once
    from ``element_seed`` (they belong to the hardware); None for ideal arrays."""
    if impairments.element_gain_db == 0.0 and impairments.element_phase_deg == 0.0:
        return None
    rng = np.random.default_rng(impairments.element_seed)
    gain = 10.0 ** (rng.normal(0.0, impairments.element_gain_db, (2, n_elements)) / 20.0)
    phase = np.radians(rng.normal(0.0, impairments.element_phase_deg, (2, n_elements)))
    response = gain * np.exp(1j * phase)
    return tuple(map(complex, response[0])), tuple(map(complex, response[1]))


@dataclass(frozen=True)
class BeamSet:
    """The swept beams of one pose: every (orientation, codebook index) pair, flattened.

    Beam order: orientation-major, then codebook index ascending, 188 by default.
    """

    n_elements: int
    bits: int
    beams_per_side: int
    orientations: int
    element_exponent: float = 1.0
    element_response: tuple[tuple[complex, ...], ...] | None = None  # (TX, RX) per element; None: ideal
    baseline_wavelengths: float = 0.0  # TX/RX array centre spacing b/λ (0: no coupling model)
    elevation_indices: tuple[int, ...] = (0,)  # codebook indices j of the rows' DFT codebook; (0,): flat

    @classmethod
    def from_config(cls, radio: RadioConfig) -> "BeamSet":
        return cls(radio.array_elements, radio.codebook_bits, radio.beams_per_side, radio.orientations,
                   radio.element_exponent, element_responses(radio.impairments, radio.array_elements),
                   radio.array_baseline_m / radio.wavelength_m if radio.leakage_coupling is LeakageCoupling.ARRAYS
                   else 0.0,
                   tuple(range(-radio.elevation_span, radio.elevation_span + 1, radio.elevation_spacing)))

    @property
    def codebook_indices(self) -> np.ndarray:
        return np.arange(-self.beams_per_side, self.beams_per_side + 1)

    @property
    def per_orientation(self) -> int:
        return len(self.codebook_indices) * len(self.elevation_indices)

    def __len__(self) -> int:
        return self.per_orientation * self.orientations

    @property
    def orientation(self) -> np.ndarray:
        """Orientation k of each beam."""
        return np.repeat(np.arange(self.orientations), self.per_orientation)

    @property
    def index(self) -> np.ndarray:
        """Codebook index i of each beam (azimuth)."""
        return np.tile(self.codebook_indices, self.orientations * len(self.elevation_indices))

    @property
    def elevation_index(self) -> np.ndarray:
        """Elevation codebook index j of each beam (0: horizontal); beams go orientation, j, then i."""
        rows = np.repeat(np.asarray(self.elevation_indices, dtype=np.int64), len(self.codebook_indices))
        return np.tile(rows, self.orientations)

    @property
    def direction_cosines(self) -> tuple[np.ndarray, np.ndarray]:
        """(u_y, u_z) each beam points at, off its array's normal: 2i/2^M, 2j/2^M."""
        return 2.0 * self.index / 2**self.bits, 2.0 * self.elevation_index / 2**self.bits

    @property
    def elevation(self) -> np.ndarray:
        """Elevation each beam points at, radians (0 for the flat scan)."""
        return np.arcsin(self.direction_cosines[1])

    @property
    def slot(self) -> np.ndarray:
        """Position 0 … 46 of each beam within its orientation's sweep (its SSB index)."""
        return np.tile(np.arange(self.per_orientation), self.orientations)

    @property
    def orientation_angle(self) -> np.ndarray:
        """Array normal of each beam in the terminal frame: k·2π/orientations."""
        return self.orientation * (2 * np.pi / self.orientations)

    @property
    def angle(self) -> np.ndarray:
        """Beam pointing azimuth in the terminal frame, radians in (−π, π]: arcsin(u_y/cos ε) off the
        orientation's normal (arcsin(2ϑ_i) for the flat scan)."""
        u_y, u_z = self.direction_cosines
        raw = self.orientation_angle + np.arcsin(u_y / np.sqrt(1.0 - u_z**2))
        return np.angle(np.exp(1j * raw))

    def weights(self) -> np.ndarray:
        """Azimuth weights w_i (B, N) of each beam."""
        return dft_codebook(self.n_elements, self.bits, self.index)

    def vertical_factor(self, elevation: np.ndarray) -> np.ndarray:
        """|v_j^H a(sin ε/2)|/√N (B, ...) of each beam's rows towards elevations ε (...), one way: 1 at the peak."""
        table = vertical_factors(self.n_elements, self.bits, np.asarray(self.elevation_indices), np.sin(elevation))
        return table[np.searchsorted(self.elevation_indices, self.elevation_index)]

    def vertical_gain(self, elevation: np.ndarray) -> np.ndarray:
        """The two-way vertical factor |v_j^H a(sin ε/2)|²/N (B, ...)."""
        return self.vertical_factor(elevation) ** 2

    def coupling(self) -> np.ndarray:
        """Complex TX→RX leakage (B,) of each beam between the stacked TX and RX arrays, relative to its
        mean power over the ideal codebook: L_i = (w̄_i∘e_R)^T C (w̄_i∘e_T) with the coupling C of
        :func:`~radioslam.antenna.array.stacked_coupling` (both arrays steered by w_i, as in
        :meth:`two_way_gain`). Broadside beams couple most (22 dB above the edge beams at b = 4.7λ)."""
        if self.baseline_wavelengths <= 0.0:
            return np.ones(len(self), dtype=np.complex128)
        c = stacked_coupling(self.n_elements, self.baseline_wavelengths)
        w = self.weights().conj()
        ideal = np.einsum("bm,mn,bn->b", w, c, w)
        actual = ideal
        if self.element_response is not None:
            tx, rx = map(np.array, self.element_response)
            actual = np.einsum("bm,mn,bn->b", w * rx, c, w * tx)
        return actual / np.sqrt(np.mean(np.abs(ideal) ** 2))

    def two_way_gain(self, theta_terminal: np.ndarray, elevation: np.ndarray | None = None,
                     path_rows: np.ndarray | None = None) -> np.ndarray:
        """Amplitude gain (B, P) of every beam towards paths at terminal-frame azimuths (P,) and
        elevations (P,) (None: horizontal). A path with a ``path_rows`` entry j other than ``ANY_ROW`` has its
        vertical pattern in its amplitude already (a wall column integrated over row j's elevations,
        :mod:`radioslam.sim.elevated`): it reaches the beams of row j only, with their horizontal gain.

        ϖ_{ij} of the module docstring (ϖ_i(θ − k·π/2) for the flat scan), the element pattern
        cos^q each way; zero behind the array. Per orientation only the paths in front of its
        array are evaluated.
        """
        theta = np.asarray(theta_terminal, dtype=np.float64)
        cos_el = np.ones_like(theta) if elevation is None else np.cos(elevation)
        out = np.zeros((len(self), theta.size))
        w = self.weights()
        tx, rx = (None, None) if self.element_response is None else map(np.array, self.element_response)
        for k in range(self.orientations):  # 4 orientations; beams and paths stay vectorized
            rows = np.flatnonzero(self.orientation == k)
            local = (theta - k * 2 * np.pi / self.orientations + np.pi) % (2 * np.pi) - np.pi  # [−π, π)
            front = np.flatnonzero(np.abs(local) < np.pi / 2)
            vartheta = 0.5 * cos_el[front] * np.sin(local[front])  # u_y/2
            if tx is None:
                gain = np.abs(array_response(w[rows], vartheta)) ** 2
            else:  # each array's elements respond e_n·a_n: |w^H (e_T∘a)|·|w^H (e_R∘a)|
                gain = np.abs(array_response(w[rows] * tx.conj(), vartheta)) * \
                    np.abs(array_response(w[rows] * rx.conj(), vartheta))
            out[np.ix_(rows, front)] = gain * (cos_el[front] * np.cos(local[front])) ** self.element_exponent
        if elevation is not None or len(self.elevation_indices) > 1:  # horizontal paths: the rows' factor at ε = 0
            vertical = self.vertical_gain(np.zeros_like(theta) if elevation is None else elevation)
            if path_rows is not None:
                own = np.flatnonzero(np.asarray(path_rows) != ANY_ROW)
                vertical[:, own] = self.elevation_index[:, None] == np.asarray(path_rows)[own][None, :]
            out *= vertical
        return out
