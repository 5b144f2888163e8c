"""What long work reports as it goes, without knowing who listens (issue #17): a stage starts with its
description and total, then advances step by step. The command line draws a bar on a terminal and a line
every ~10 s elsewhere (:mod:`radioslam.cli.output`); the core never imports it."""

from __future__ import annotations

from typing import Protocol


class Progress(Protocol):
    def start(self, description: str, total: int, completed: int = 0) -> None:
        """A new stage of ``total`` steps, ``completed`` of them done already (a resumed run's)."""
        ...

    def advance(self, steps: int = 1) -> None:
        ...


class Silent:
    """Progress nobody listens to."""

    def start(self, description: str, total: int, completed: int = 0) -> None:
        return None

    def advance(self, steps: int = 1) -> None:
        return None


SILENT = Silent()
