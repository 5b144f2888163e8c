"""M-bit DFT codebook, beam selection and the two-way beam gain ϖ (paper §III, §II-C).

w_i = a(ϑ_i)/√N with ϑ_i = i/2^M. The paper keeps i = −23…23 (47 beams, ±45.95°
for M = 6, N = 8) and rotates the terminal to 4 orientations k·π/2: 188 beams.

The two-way gain of beam i towards a path at angle θ (eq. (4)) is
ϖ_i(θ) = w_i^H a_R(θ) a_T^H(θ) w_i = |w_i^H a(θ)|² for the identical TX and RX
arrays, sidelobes included; its peak is N. An element pattern cos^q(θ) (power,
each way) bounds the arrays to the half space in front of them.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from radioslam.antenna.array import array_response, spatial_frequency, stacked_coupling, steering_vector
from radioslam.config import Impairments, LeakageCoupling, RadioConfig


def dft_codebook(n_elements: int, bits: int, indices: np.ndarray) -> np.ndarray:
    """Weights w_i = a(i/2^M)/√N, shape (len(indices), N)."""
    return steering_vector(np.asarray(indices) / 2**bits, n_elements) / np.sqrt(n_elements)


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

    @classmethod
    def from_config(cls, radio: RadioConfig) -> "BeamSet":
        return cls(radio.array_elements, radio.codebook_bits, radio.beams_per_side, radio.orientations,
                   radio.element_exponent, element_responses(radio.impairments, radio.array_elements),
                   radio.array_baseline_m / radio.wavelength_m if radio.leakage_coupling is LeakageCoupling.ARRAYS
                   else 0.0)

    @property
    def codebook_indices(self) -> np.ndarray:
        return np.arange(-self.beams_per_side, self.beams_per_side + 1)

    @property
    def per_orientation(self) -> int:
        return len(self.codebook_indices)

    def __len__(self) -> int:
        return self.per_orientation * self.orientations

    @property
    def orientation(self) -> np.ndarray:
        """Orientation k of each beam."""
        return np.repeat(np.arange(self.orientations), self.per_orientation)

    @property
    def index(self) -> np.ndarray:
        """Codebook index i of each beam."""
        return np.tile(self.codebook_indices, self.orientations)

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
        """Beam pointing angle in the terminal frame, radians in (−π, π]."""
        raw = self.orientation_angle + beam_angle(self.index, self.bits)
        return np.angle(np.exp(1j * raw))

    def weights(self) -> np.ndarray:
        return dft_codebook(self.n_elements, self.bits, self.index)

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

    def two_way_gain(self, theta_terminal: np.ndarray) -> np.ndarray:
        """Amplitude gain (B, P) of every beam towards paths at terminal-frame angles (P,).

        ϖ_i(θ − k·π/2) times the element pattern cos^q each way; zero behind the array. Per
        orientation only the paths in front of its array are evaluated.
        """
        theta = np.asarray(theta_terminal, dtype=np.float64)
        out = np.zeros((len(self), theta.size))
        w = self.weights()
        tx, rx = (None, None) if self.element_response is None else map(np.array, self.element_response)
        for k in range(self.orientations):  # 4 orientations; beams and paths stay vectorized
            rows = np.flatnonzero(self.orientation == k)
            local = (theta - k * 2 * np.pi / self.orientations + np.pi) % (2 * np.pi) - np.pi  # [−π, π)
            front = np.flatnonzero(np.abs(local) < np.pi / 2)
            vartheta = spatial_frequency(local[front])
            if tx is None:
                gain = np.abs(array_response(w[rows], vartheta)) ** 2
            else:  # each array's elements respond e_n·a_n: |w^H (e_T∘a)|·|w^H (e_R∘a)|
                gain = np.abs(array_response(w[rows] * tx.conj(), vartheta)) * \
                    np.abs(array_response(w[rows] * rx.conj(), vartheta))
            out[np.ix_(rows, front)] = gain * np.cos(local[front]) ** self.element_exponent
        return out
