"""Noise level from the ★ SNR definition (DESIGN.md §2).

``snr_db`` is the per-resource-element SNR of a reference echo: a concrete wall
at normal incidence 5 m away, seen on the beam pointing at it, before any
integration. The reference echo power is computed by the simulator itself (same
ray caster, materials and beam gains), so every other echo scales physically from
it. With orthonormal FFTs the per-RE noise variance equals the time-domain one.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache

import numpy as np

from radioslam.antenna.codebook import BeamSet
from radioslam.config import RadioConfig
from radioslam.nr.numerology import Numerology
from radioslam.scene.loader import scene_from_mapping
from radioslam.sim.channel import beam_path_gains, channel_response
from radioslam.sim.paths import echo_paths

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


NOISE_CHUNK_ROWS = 8


def add_noise(x: np.ndarray, variance: float, rng: np.random.Generator, inplace: bool = False) -> np.ndarray:
    """x + circular complex Gaussian noise of the given variance, as complex64.

    The draw is split into two fixed halves along the first axis, each from its own
    child of ``rng`` (``Generator.spawn``), drawn, scaled and added in its own thread,
    a few rows at a time. The result depends on the seed only, never on the core
    count. With ``inplace`` a complex64 ``x`` receives the noise itself.
    """
    out = x if inplace and x.dtype == np.complex64 and x.flags.c_contiguous else np.array(x, dtype=np.complex64)
    rows = out.shape[0] if out.ndim > 1 else 1
    flat = out.view(np.float32).reshape(rows, -1)
    half = (rows + 1) // 2
    children = rng.spawn(2)
    scale = np.float32(np.sqrt(variance / 2.0))

    def draw(k: int) -> None:
        lo, hi = (0, half) if k == 0 else (half, rows)
        buffer = np.empty((min(NOISE_CHUNK_ROWS, max(hi - lo, 1)), flat.shape[1]), dtype=np.float32)
        for start in range(lo, hi, NOISE_CHUNK_ROWS):  # chunks of rows, each fully vectorized
            chunk = buffer[: min(NOISE_CHUNK_ROWS, hi - start)]
            children[k].standard_normal(out=chunk, dtype=np.float32)
            np.multiply(chunk, scale, out=chunk)
            flat[start:start + len(chunk)] += chunk

    with ThreadPoolExecutor(max_workers=2) as pool:
        list(pool.map(draw, (0, 1)))
    return out
