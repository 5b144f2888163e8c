"""``radioslam`` run as a user runs it, in a fresh process with its output captured (the command line's tests)."""

import os
import subprocess
import sys


def cli(*args, env: dict | None = None, cwd=None, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python -m radioslam.cli ARGS`` (each argument as text), ``env`` added to this process's environment."""
    return subprocess.run([sys.executable, "-m", "radioslam.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout, env={**os.environ, **(env or {})})


def cli_argv(*args, prelude: str = "") -> list[str]:
    """The argv of ``python -m radioslam.cli ARGS`` with ``prelude`` (Python) run first in the child.

    Instead of ``subprocess``'s ``preexec_fn``, which runs Python between fork and exec and is unsafe in
    a parent with threads (pytest-xdist's workers have them): the child may deadlock or abort there."""
    return [sys.executable, "-c", f"{prelude}\nimport runpy\nrunpy.run_module('radioslam.cli', run_name='__main__', "
            "alter_sys=True)", *map(str, args)]
