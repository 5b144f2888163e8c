"""``radioslam`` run as a user runs it, in a fresh process with its output captured (the command line's tests)."""

import os
import subprocess
import sys


def cli(*args, env: dict | None = None, cwd=None, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python -m radioslam.cli ARGS`` (each argument as text), ``env`` added to this process's environment."""
    return subprocess.run([sys.executable, "-m", "radioslam.cli", *map(str, args)], capture_output=True, text=True,
                          cwd=cwd, timeout=timeout, env={**os.environ, **(env or {})})
