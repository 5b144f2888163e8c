"""The simulator's two worker threads, kept for the life of the process.

A pool per call would start two threads per pose and give their numpy temporaries fresh memory
arenas each time, so every block's buffers would be faulted in anew (about a fifth of a pose's
time on the development machine). A child process made by ``fork`` does not inherit the threads:
it starts its own pool on first use.
"""

from __future__ import annotations

import os
from concurrent.futures import ThreadPoolExecutor

WORKERS = 2
_pool: ThreadPoolExecutor | None = None


def worker_pool() -> ThreadPoolExecutor:
    """The process's pool of ``WORKERS`` threads (started on first use)."""
    global _pool
    if _pool is None:
        _pool = ThreadPoolExecutor(max_workers=WORKERS, thread_name_prefix="radioslam-sim")
    return _pool


def _forget_after_fork() -> None:
    global _pool
    _pool = None


os.register_at_fork(after_in_child=_forget_after_fork)
