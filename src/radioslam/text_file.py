"""An input file's text, read only when it is a regular file of bounded size (issue #15): a FIFO would
block for ever, ``/dev/zero`` would never end, a gigabyte of YAML would exhaust the parser."""

from __future__ import annotations

from pathlib import Path

from radioslam.errors import RadioslamError


def read_text(path: str | Path, error: type[RadioslamError], max_bytes: int) -> str:
    """The UTF-8 text of the regular file ``path`` of at most ``max_bytes``; ``error`` names the file."""
    path = Path(path)
    if not path.exists():
        raise error("no such file", file=path, field="(file)")
    if not path.is_file():
        raise error("not a regular file", file=path, field="(file)")
    if path.stat().st_size > max_bytes:
        raise error(f"larger than {max_bytes // 2**20} MiB", file=path, field="(file)")
    try:
        return path.read_bytes().decode("utf-8")
    except UnicodeDecodeError:
        raise error("not UTF-8 text", file=path, field="(file)") from None
    except OSError as exc:
        raise error(f"cannot read: {exc.strerror or exc}", file=path, field="(file)") from None
