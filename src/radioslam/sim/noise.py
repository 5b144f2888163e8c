"""Noise level from the ★ SNR definition (DESIGN.md §2).

``snr_db`` is the per-resource-element SNR of a reference echo: a concrete wall
at normal incidence 5 m away, seen on the beam pointing at it, before any
integration. The reference echo power is computed by the simulator itself (same
ray caster, materials and beam gains), so every other echo scales physically from
it. With orthonormal FFTs the per-RE noise variance equals the time-domain one.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from radioslam.antenna.codebook import BeamSet
from radioslam.config import RadioConfig
from radioslam.nr.numerology import Numerology
from radioslam.scene.loader import scene_from_mapping
from radioslam.sim.channel import beam_path_gains, channel_response
from radioslam.sim.paths import echo_paths
from radioslam.sim.workers import worker_pool

REFERENCE_RANGE_M = 5.0
REFERENCE_MATERIAL = "concrete"


def reference_scene(radio: RadioConfig):
    """A long concrete wall 5 m in front of a terminal at the origin facing +x."""
    r = REFERENCE_RANGE_M
    return scene_from_mapping({
        "version": 1, "name": "snr-reference",
        "walls": [{"points": [[r, -200.0], [r, 200.0]], "material": REFERENCE_MATERIAL}],
        "trajectory": {"poses": [[0.0, 0.0, 0.0]]},
        "radio": radio.model_dump(),
    }, "builtin:snr-reference")


@lru_cache(maxsize=16)
def reference_echo_power(radio: RadioConfig) -> float:
    """Mean over subcarriers of |H(p)|² of the reference echo on the boresight beam."""
    scene = reference_scene(radio)
    beams = BeamSet.from_config(radio)
    paths = echo_paths(scene, scene.poses[0], radio, leakage=False)
    boresight = np.flatnonzero((beams.orientation == 0) & (beams.index == 0))
    gains = beam_path_gains(beams, paths)[boresight]
    num = Numerology.from_config(radio)
    h = channel_response(gains, paths.delay_s, num.subcarrier_indices(), radio.subcarrier_spacing_hz)
    return float(np.mean(np.abs(h) ** 2))


def noise_variance(radio: RadioConfig) -> float:
    """σ² per resource element (and per time sample) for ``radio.snr_db``."""
    return reference_echo_power(radio) / 10.0 ** (radio.snr_db / 10.0)


def measured_snr_db(received: np.ndarray, sent: np.ndarray) -> float:
    """Per-RE SNR measured from R observations y = H(p)·x + z of known symbols, (R, n_sc).

    H is estimated per subcarrier by least squares over the R symbols; the noise
    variance from the residual with R − 1 degrees of freedom per subcarrier; the
    estimator's own noise is removed from the signal power. This is how the ★ SNR
    is checked on a simulated capture of the reference echo.
    """
    energy = np.sum(np.abs(sent) ** 2, axis=0)
    h = np.sum(received * sent.conj(), axis=0) / energy
    noise = np.sum(np.abs(received - h * sent) ** 2) / (received.size - received.shape[1])
    signal = np.mean(np.abs(h) ** 2) - np.mean(noise / energy)
    return float(10 * np.log10(signal / noise))


NOISE_CHUNK_SAMPLES = 1 << 16
MANTISSA_ONE = np.uint32(0x3F800000)  # the bits of 1.0f: OR-ing 23 random bits under it gives [1, 2)


def add_noise(x: np.ndarray, variance: float, rng: np.random.Generator, inplace: bool = False) -> np.ndarray:
    """x + circular complex Gaussian noise of the given variance, as complex64.

    Box–Muller in polar form (Box & Muller, Ann. Math. Stat. 1958): with U, V uniform, the
    circular Gaussian is z = σ·√(−ln U)·e^{j2πV}, |z| Rayleigh and its phase uniform. U and V
    take 23 random bits each (1 − U and V are floats in [0, 1) built from the bits directly), so
    |z| ≤ σ·√(23 ln 2) = 3.99σ: each rail is Gaussian out to 5.6 of its σ/√2, beyond which lies
    a probability of 1.2·10⁻⁷ per sample. Four ufunc passes of SIMD transcendentals per sample
    instead of a ziggurat draw per rail: three times faster here.

    The draw is split into two fixed halves along the first axis, each from its own child of
    ``rng`` (``Generator.spawn``), each drawn and added in its own thread, a chunk at a time. The
    result depends on the seed only, never on the core count. With ``inplace`` a complex64 ``x``
    receives the noise itself.
    """
    out = x if inplace and x.dtype == np.complex64 and x.flags.c_contiguous else np.array(x, dtype=np.complex64)
    rows = out.shape[0] if out.ndim > 1 else 1
    flat = out.reshape(rows, -1)
    half = (rows + 1) // 2
    children = rng.spawn(2)
    sigma = float(np.sqrt(variance))

    def draw(k: int) -> None:
        part = (flat[:half] if k == 0 else flat[half:]).reshape(-1)
        for start in range(0, len(part), NOISE_CHUNK_SAMPLES):  # chunks held in cache, each vectorized
            add_circular_gaussian(part[start:start + NOISE_CHUNK_SAMPLES], children[k].bit_generator, sigma)

    list(worker_pool().map(draw, (0, 1)))
    return out


def add_circular_gaussian(out: np.ndarray, bits: np.random.BitGenerator, sigma: float) -> None:
    """Add σ·√(−ln U)·e^{j2πV} to each sample of the contiguous complex64 ``out`` (Box–Muller,
    see :func:`add_noise`). Every pass but the last two runs on contiguous float32 arrays."""
    count = out.size
    words = bits.random_raw(count).view(np.uint32)  # 2·count words of 32 random bits
    np.right_shift(words, 9, out=words)
    np.bitwise_or(words, MANTISSA_ONE, out=words)
    uniform = words.view(np.float32)  # [1, 2)
    radius, turn = uniform[:count], uniform[count:]
    np.subtract(np.float32(2.0), radius, out=radius)  # U ∈ (0, 1]
    np.log(radius, out=radius)
    np.multiply(radius, np.float32(-sigma * sigma), out=radius)
    np.sqrt(radius, out=radius)
    np.multiply(turn, np.float32(2.0 * np.pi), out=turn)  # 2πV, shifted by a whole turn
    real = np.cos(turn)
    np.sin(turn, out=turn)
    real *= radius
    turn *= radius
    rails = out.reshape(-1).view(np.float32)
    rails[0::2] += real
    rails[1::2] += turn
