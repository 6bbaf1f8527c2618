"""Announce a Numba compile before it runs: one line on standard error with its expected
duration, then the time it took.

A kernel compiled with ``cache=True`` is kept in Numba's on-disk cache (``NUMBA_CACHE_DIR``
moves it); only a process that finds it missing there compiles, and only that process prints.
Whether the cache holds a dispatcher's code is read from Numba's cache index, a private layout:
where it cannot be read, the compile is announced (a needless line is better than a silent
pause).
"""

from __future__ import annotations

import contextlib
import sys
import time
from collections.abc import Iterable, Iterator
from typing import Any


def numba_cached(dispatchers: Iterable[Any]) -> bool | None:
    """Whether Numba's disk cache holds compiled code for every dispatcher (any signature).

    Returns:
        True or False; ``None`` where it cannot tell (no cache, or a Numba whose cache is laid
        out differently).
    """
    try:
        for dispatcher in dispatchers:
            if not dispatcher._cache._cache_file._load_index():
                return False
    except Exception:  # noqa: BLE001 - a private layout: any change means "cannot tell"
        return None
    return True


@contextlib.contextmanager
def announced_compile(what: str, seconds: float, dispatchers: Iterable[Any], stream=None) -> Iterator[None]:
    """Run the block (the first call of ``dispatchers``) announcing a compile of ``what`` first
    when Numba's disk cache does not hold them, then the time it took.

    Args:
        what: the kernel, in words ("the polytope kernel for 3-D sets").
        seconds: the expected compile time (s), printed.
        dispatchers: the Numba dispatchers the block calls first.
        stream: where to print (default standard error).
    """
    dispatchers = list(dispatchers)
    if numba_cached(dispatchers):
        yield
        return
    stream = sys.stderr if stream is None else stream
    print(
        f"mobmanip: compiling {what}, once (about {seconds:.0f} s on 2 cores; kept in Numba's disk cache after)...",
        file=stream,
        flush=True,
    )
    started = time.perf_counter()
    yield
    print(f"mobmanip: {what} compiled in {time.perf_counter() - started:.1f} s", file=stream, flush=True)
