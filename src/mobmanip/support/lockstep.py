"""Independent iterative runs served in batches: many optimiser starts, or the cells of a map,
each asking for one evaluation at a time, answered together by one batched call.

SciPy's optimisers call back for one point at a time. To evaluate many runs' points in one
batched call (where a batch of 15 configurations costs about what 1.5 single ones do), each
run is a thread whose evaluation callback hands its point to :class:`Lockstep` and waits; once
every run is waiting (or finished), the batch is evaluated and every run gets its answer.

The runs never execute at the same time: the scheduler lets one run go at a time, until it asks
again or finishes. So the runs may share objects that are not thread-safe (a Pinocchio
``Data``, a cache), and each run's arithmetic, hence its result, is the same as when the runs
are executed one after the other with one-point batches: the batch kernels compute every row
on its own (tests/test_lockstep.py checks that the batched rows equal single calls bit for bit).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Sequence
from typing import Any, Generic, TypeVar

T = TypeVar("T")
Request = Any
Reply = Any


class _Abandoned(GeneratorExit):
    """Raised inside a waiting run when the lockstep ends early (another run or the batch failed,
    or the caller was interrupted): the run's thread unwinds and ends. Like a generator's
    ``close()``, a ``BaseException``, so a run's ``except Exception`` does not stop it."""


class Lockstep(Generic[T]):
    """Runs callables that call :meth:`ask`, serving their requests in batches.

    Args:
        evaluate: answers a list of requests with a list of replies, in the same order.
    """

    def __init__(self, evaluate: Callable[[list[Request]], Sequence[Reply]]):
        self.evaluate = evaluate
        self._local = threading.local()
        #: Number of batched calls made and requests served (for benchmarks and logs).
        self.batches = 0
        self.requests = 0

    def ask(self, request: Request) -> Reply:
        """The reply to ``request``: batched with the other runs' inside :meth:`run`, else at once."""
        slot = getattr(self._local, "slot", None)
        if slot is None:
            self.batches += 1
            self.requests += 1
            return self.evaluate([request])[0]
        return slot.ask(request)

    def run(self, runs: Sequence[Callable[[], T]]) -> list[T]:
        """Every run's return value, in order. The first exception a run raises (in run order) is
        raised here once every run has ended."""
        slots = [_Slot(self, run) for run in runs]
        try:
            for slot in slots:
                slot.start()  # runs until its first request or its end
            while True:
                waiting = [slot for slot in slots if slot.state == "waiting"]
                if not waiting:
                    break
                replies = self.evaluate([slot.request for slot in waiting])
                self.batches += 1
                self.requests += len(waiting)
                for slot, reply in zip(waiting, replies):
                    slot.resume(reply)  # runs until its next request or its end
        finally:
            for slot in slots:
                slot.abandon()
        for slot in slots:
            if slot.error is not None:
                raise slot.error
        return [slot.result for slot in slots]


def _closed() -> threading.Lock:
    """A lock held from the start, used as a binary semaphore: ``release`` (from any thread)
    lets one ``acquire`` through. Cheaper than ``threading.Semaphore`` (a condition variable
    allocating a lock per wait), which the hand-over paid twice per request."""
    lock = threading.Lock()
    lock.acquire()
    return lock


class _Slot:
    """One run: its thread, its pending request, and the two semaphores of the hand-over."""

    def __init__(self, lockstep: Lockstep, run: Callable[[], Any]):
        self.lockstep = lockstep
        self.run = run
        self.state = "new"  # new, running, waiting, done
        self.request: Request = None
        self.reply: Reply = None
        self.result: Any = None
        self.error: BaseException | None = None
        self._go = _closed()  # the scheduler lets the run go
        self._back = _closed()  # the run has asked or ended
        self._abandoned = False
        self._thread = threading.Thread(target=self._main, name="mobmanip-lockstep", daemon=True)

    def start(self) -> None:
        self.state = "running"
        self._thread.start()
        self._back.acquire()

    def resume(self, reply: Reply) -> None:
        self.reply, self.request, self.state = reply, None, "running"
        self._go.release()
        self._back.acquire()

    def abandon(self) -> None:
        """End a run that has not finished (after an error or an interrupt): let it reach its
        next request or its end, then unwind it there; wait for its thread (also a finished
        run's, which has only to return)."""
        if self.state == "new":
            return
        if self.state == "done":
            self._thread.join()  # it has only to return
            return
        self._abandoned = True
        if self.state == "running":  # interrupted while the run went on
            self._back.acquire()
        if self.state == "waiting":
            self._go.release()
        self._thread.join()

    def ask(self, request: Request) -> Reply:
        if self._abandoned:
            raise _Abandoned()
        self.request, self.state = request, "waiting"
        self._back.release()
        self._go.acquire()
        if self._abandoned:
            raise _Abandoned()
        return self.reply

    def _main(self) -> None:
        self.lockstep._local.slot = self
        try:
            self.result = self.run()
        except _Abandoned:
            pass
        except BaseException as exc:  # handed to the scheduler, raised in the caller's thread
            self.error = exc
        finally:
            self.state = "done"
            self._back.release()
