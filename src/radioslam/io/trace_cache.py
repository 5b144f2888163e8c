"""A cache of ray-traced echo paths (issue #16, point 4): one ``.npz`` per traced pose in a directory,
named by the trace's key, so that simulating a scene again (another seed, SNR or receiver, IQ saved this
time) reads Sionna RT's paths instead of tracing them again (seconds a pose).

The key (:meth:`radioslam.sim.sionna_channel.SionnaChannel.trace_key`) hashes everything a trace depends
on, so a stale entry is never read: it is simply never asked for. An entry is written to a temporary
file and renamed (:mod:`radioslam.io.atomic`); one that cannot be read back is traced again."""

from __future__ import annotations

import re
import zipfile
from pathlib import Path

import numpy as np

from radioslam.io.atomic import atomic_path

KEY = re.compile(r"[0-9a-f]{16,64}")


class TraceCache:
    """Traced arrays by key, as ``DIRECTORY/KEY.npz``; counts what it served (``hits``) and stored."""

    def __init__(self, directory: str | Path):
        self.directory = Path(directory)
        self.hits = 0
        self.stored = 0

    def path(self, key: str) -> Path:
        if not KEY.fullmatch(key):
            raise ValueError(f"a trace key is a hex digest, not {key!r}")
        return self.directory / f"{key}.npz"

    def load(self, key: str) -> dict[str, np.ndarray] | None:
        """The arrays stored under ``key``, or None (not stored, or not readable: traced again)."""
        path = self.path(key)
        if not path.is_file():
            return None
        try:
            with np.load(path, allow_pickle=False) as archive:
                arrays = {name: archive[name] for name in archive.files}
        except (OSError, ValueError, EOFError, zipfile.BadZipFile):
            return None
        self.hits += 1
        return arrays

    def store(self, key: str, arrays: dict[str, np.ndarray]) -> None:
        with atomic_path(self.path(key)) as tmp, open(tmp, "wb") as out:
            np.savez(out, **arrays)
        self.stored += 1
