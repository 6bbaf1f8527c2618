"""Announce a Numba compile before it runs: one line on standard error with how long it may take,
a line that counts the seconds while it runs (on a terminal), then the time it took.

A kernel compiled with ``cache=True`` is kept in Numba's on-disk cache (``NUMBA_CACHE_DIR``
moves it); only a process that finds it missing there compiles, and only that process prints.
Whether the cache holds a dispatcher's code is read from Numba's cache index, a private layout:
where it cannot be read, the compile is announced (a needless line is better than a silent
pause).

How long a compile may take is stated as an upper bound, ``up to N s`` (:data:`UP_TO`), from
the slowest compiles measured on the project's 2-core machine while other work shared it
(:data:`MEASURED`): an idle machine takes half of that or less, and an estimate of the idle time
("about 2 s") read as a promise on a busy one (it took 18.9 s) is worse than none.
``mobmanip warmup`` compiles every kernel once, ahead of the first real run.
"""

from __future__ import annotations

import contextlib
import sys
import threading
import time
from collections.abc import Callable, Hashable, Iterable, Iterator
from contextlib import AbstractContextManager
from typing import Any, TextIO

#: Compiles of each kernel measured on the project's 2-core machine (s), with an empty Numba cache
#: while four other jobs shared it (loads 4 to 7): ``mobmanip warmup`` compiling every kernel in
#: one process, then each kernel alone in a fresh process (``warmup --only``), then first runs of
#: the commands (``view --ground``'s 3-D face kernel; ``place``'s tree loops and ``carry``'s
#: kinematic chain as issue 39 recorded them). A kernel compiled alone pays Numba's start-up and
#: the helpers it shares with others. The batch kernel's by its number of end effectors (the task
#: dimension barely matters).
MEASURED: dict[str, tuple[float, ...]] = {
    "faces 2-D": (9.3, 9.5),
    "faces 3-D": (6.2, 10.8, 15.9),
    "planar sweep": (8.7, 10.6),
    "3-D sweep": (2.3, 16.1),
    "world_inertias": (0.5, 1.1, 3.0),
    "mass_and_gravity": (3.1, 5.1, 18.9),
    "bilinear_rows": (2.5, 2.2, 9.0),
    "kinematic chain": (12.5, 18.2, 27.5),
    "batch, 1 end effector": (26.4, 24.4, 22.3),
    "batch, 2 end effectors": (32.0, 20.4, 27.7),
}
#: What a first compile is announced to take at most (s): the slowest measured with half again,
#: rounded up to 5 s.
UP_TO: dict[str, float] = {
    "faces 2-D": 15.0,
    "faces 3-D": 25.0,
    "planar sweep": 20.0,
    "3-D sweep": 25.0,
    "world_inertias": 5.0,
    "mass_and_gravity": 30.0,
    "bilinear_rows": 15.0,
    "kinematic chain": 45.0,
    "batch, 1 end effector": 40.0,
    "batch, 2 end effectors": 50.0,
}
#: How often the line that counts a compile's seconds is redrawn on a terminal (s).
TICK = 1.0


def up_to(kernel: str) -> float:
    """The announced upper bound of a first compile of ``kernel`` (a key of :data:`UP_TO`), s."""
    return UP_TO[kernel]


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


def _on_terminal(stream: TextIO) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):  # no isatty, or closed
        return False


@contextlib.contextmanager
def compiling(what: str, seconds: float, stream: TextIO | None = None, tick: float = TICK) -> Iterator[None]:
    """Run the block (a compile) with its notice: a line before it (what compiles, up to how long),
    on a terminal a line redrawn every ``tick`` s with the seconds so far, and a line after it
    with the time it took.

    Args:
        what: the kernel, in words ("the polytope kernel for 3-D sets").
        seconds: the most it may take (s; :data:`UP_TO`), printed.
        stream: where to print (default standard error).
        tick: seconds between two redraws of the counting line.
    """
    stream = sys.stderr if stream is None else stream
    print(
        f"mobmanip: compiling {what}, once (up to {seconds:.0f} s on a busy 2-core machine; "
        "kept in Numba's disk cache after; `mobmanip warmup` compiles every kernel ahead)...",
        file=stream,
        flush=True,
    )
    started = time.perf_counter()
    done = threading.Event()
    counter = None
    if _on_terminal(stream):

        def count() -> None:
            while not done.wait(tick):
                stream.write(f"\r  compiling: {time.perf_counter() - started:.0f} s of up to {seconds:.0f} s ")
                stream.flush()

        counter = threading.Thread(target=count, name="mobmanip-compile-progress", daemon=True)
        counter.start()
    try:
        yield
    finally:
        done.set()
        if counter is not None:
            counter.join()
            stream.write("\r\033[K")  # clear the counting line
    print(f"mobmanip: {what} compiled in {time.perf_counter() - started:.1f} s", file=stream, flush=True)


@contextlib.contextmanager
def announced_compile(what: str, seconds: float, dispatchers: Iterable[Any], stream=None) -> Iterator[None]:
    """Run the block (the first call of ``dispatchers``) announcing a compile of ``what`` first
    when Numba's disk cache does not hold them (:func:`compiling`).

    Args:
        what: the kernel, in words ("the polytope kernel for 3-D sets").
        seconds: the most it may take (s), printed.
        dispatchers: the Numba dispatchers the block calls first.
        stream: where to print (default standard error).
    """
    dispatchers = list(dispatchers)
    if numba_cached(dispatchers):
        yield
        return
    with compiling(what, seconds, stream):
        yield


def first_call_notice(
    called: set, key: Hashable, what: str, seconds: float, dispatchers: Callable[[], Iterable[Any]]
) -> AbstractContextManager[None]:
    """:func:`announced_compile` around the first call for ``key`` (then noted in ``called``), and
    a context that does nothing around every later one; ``dispatchers`` gives the dispatchers
    the first call runs."""
    if key in called:
        return contextlib.nullcontext()
    called.add(key)
    return announced_compile(what, seconds, dispatchers())
