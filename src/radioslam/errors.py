"""The project's base exception.

Every module raises its own subclass (``SceneError``, ``SigMFError``, ...), so a
caller can catch one stage's failures. Each error names the file, the field
(a dotted key path or a sample range) and the reason, and renders as the one
line that the command line prints before exiting with status 2.
"""

from __future__ import annotations

from pathlib import Path


class RadioslamError(Exception):
    """Bad input: names the file, the field and the reason."""

    def __init__(self, reason: str, *, file: str | Path | None = None, field: str | None = None):
        self.reason = reason
        self.file = str(file) if file is not None else None
        self.field = field
        super().__init__(self.one_line())

    def one_line(self) -> str:
        parts = [_printable(p) for p in (self.file, self.field) if p]
        text = " ".join(_printable(self.reason).split())
        return ": ".join([*parts, text])


def _printable(text: str) -> str:
    """``text`` with every control character (a newline in a file name or a key) written as its escape."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)
