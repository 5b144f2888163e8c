"""16-QAM with the Gray mapping of 3GPP TS 38.211 §5.1.4 (unit average energy)."""

from __future__ import annotations

import numpy as np

BITS_PER_SYMBOL = 4
_SCALE = 1.0 / np.sqrt(10.0)


def qam16_modulate(bits: np.ndarray, dtype=np.complex128, out: np.ndarray | None = None,
                   conjugate: bool = False) -> np.ndarray:
    """Map bits (..., 4k) of 0/1 to 16-QAM symbols (..., k), into ``out`` if given (any array of that
    shape whose last axis is contiguous, e.g. a slice of a larger grid: no temporary); their complex
    conjugates with ``conjugate`` (what a matched filter multiplies by, without a second pass).

    d = [(1−2b0)(2−(1−2b2)) + j(1−2b1)(2−(1−2b3))] / √10, 38.211 §5.1.4.
    """
    pairs = _PAIRS.astype(dtype if out is None else out.dtype, copy=False)
    return _map_pairs(bits, pairs.conj() if conjugate else pairs, out)


def qam16_energy(bits: np.ndarray, dtype=np.float32) -> np.ndarray:
    """|d|² (..., k) of the 16-QAM symbols of bits (..., 4k): 0.2, 1 or 1.8, the same values as
    ``|qam16_modulate(bits, complex dtype)|²`` computed in ``dtype`` (re² + im² of the rounded parts)."""
    parts = _PAIRS.astype(np.result_type(dtype, np.complex64))
    return _map_pairs(bits, (parts.real**2 + parts.imag**2).astype(dtype, copy=False), None)


def _map_pairs(bits: np.ndarray, pairs: np.ndarray, out: np.ndarray | None) -> np.ndarray:
    """Look up each byte's two symbols in ``pairs`` (256, 2)."""
    b = np.asarray(bits, dtype=np.uint8)
    if b.shape[-1] % BITS_PER_SYMBOL:
        raise ValueError("the bit count must be a multiple of 4")
    if b.shape[-1] % 8:  # an odd symbol count: pad one symbol, drop it after mapping
        padded = np.concatenate([b, np.zeros((*b.shape[:-1], BITS_PER_SYMBOL), np.uint8)], axis=-1)
        return _map_pairs(padded, pairs, None)[..., :-1]
    # packbits puts two symbols' b0b1b2b3 into one byte: the high nibble, then the low one
    packed = np.packbits(b, axis=-1)
    if out is None:
        return np.take(pairs, packed, axis=0).reshape(*packed.shape[:-1], -1)
    target = out.view()
    target.shape = (*packed.shape, 2)  # a view of ``out`` (raises where only a copy could be)
    np.take(pairs, packed, axis=0, out=target, mode="clip")  # "clip": written in place, not buffered
    return out


def _table() -> np.ndarray:
    q = np.arange(16)
    s = 1 - 2 * ((q[:, None] >> np.array([3, 2, 1, 0])) & 1).astype(np.float64)
    return ((s[:, 0] * (2 - s[:, 2])) + 1j * (s[:, 1] * (2 - s[:, 3]))) * _SCALE


_TABLE = _table()  # the 16 points of 38.211 §5.1.4, indexed by b0b1b2b3
_PAIRS = np.stack([_TABLE[np.arange(256) >> 4], _TABLE[np.arange(256) & 15]], axis=-1)  # the two symbols of a byte


def qam16_demodulate(symbols: np.ndarray) -> np.ndarray:
    """Hard decision, the inverse of :func:`qam16_modulate`: symbols (..., k) → bits (..., 4k)."""
    z = np.asarray(symbols) / _SCALE
    re, im = z.real, z.imag
    bits = np.stack([re < 0, im < 0, np.abs(re) > 2, np.abs(im) > 2], axis=-1)
    return bits.reshape(*z.shape[:-1], -1).astype(np.uint8)


def random_bits(rng: np.random.Generator, shape: tuple[int, ...]) -> np.ndarray:
    """Uniform random bits from the caller's generator (drawn as bytes, then unpacked)."""
    count = int(np.prod(shape))
    packed = rng.integers(0, 256, size=-(-count // 8), dtype=np.uint8)
    return np.unpackbits(packed, count=count).reshape(shape)
