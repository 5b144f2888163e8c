"""Write-then-rename, so a file that exists is always complete: the file and its directory are synced
before and after the rename, so a power cut leaves the old file or the new one, never an empty one.

A write that fails (a full disk, a file-size limit, an I/O error) raises an ``OSError`` that names the
file being written, not its temporary, whatever the writer raised: numpy's ``tofile`` says only
"N requested and M written", without a file (issue #15: the real file named every time)."""

from __future__ import annotations

import os
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path


@contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it replaces ``path``, else it is removed."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        try:
            yield Path(tmp)
            umask = os.umask(0)
            os.umask(umask)
            os.chmod(tmp, 0o666 & ~umask)
            _sync(tmp)
            os.replace(tmp, path)
        except OSError as exc:
            # a writer's short write carries no errno: say what it means
            reason = exc.strerror or f"a short write, the disk full or a file-size limit reached ({exc})"
            raise OSError(exc.errno, reason, str(path)) from None
        _sync(path.parent)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def _sync(path: str | Path) -> None:
    """fsync a file or a directory (where the platform lets a directory be opened)."""
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def atomic_write_text(path: str | Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
