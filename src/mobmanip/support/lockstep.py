"""Independent iterative runs served in batches: many optimiser starts, or the cells of a map,
each asking for one evaluation at a time, answered together by one batched call.

SciPy's optimisers call back for one point at a time. To evaluate many runs' points in one
batched call (where a batch of 15 configurations costs about what 1.5 single ones do), each run
is a greenlet (a coroutine with its own stack, from the ``greenlet`` package) whose evaluation
callback hands its point to :class:`Lockstep` and switches back to the scheduler; once every run
is waiting (or finished), the batch is evaluated and every run gets its answer.

The runs take turns in the caller's thread: one run goes at a time, until it asks again or
finishes. So the runs may share objects that are not thread-safe (a Pinocchio ``Data``, a
cache), and each run's arithmetic, hence its result, is the same as when the runs are executed
one after the other with one-point batches: the batch kernels compute every row on its own
(tests/test_lockstep.py checks that the batched rows equal single calls bit for bit). Switching
between greenlets costs about a microsecond; the threads this used before paid tens of
microseconds per hand-over, more when the two threads sat on different cores.

An interrupt (``KeyboardInterrupt``, or any exception that is not an ``Exception``) raised inside
a run ends every run at once and is raised in the caller; so does an ``Exception``, raised once
the other runs have been unwound where they wait. No batch is evaluated after either.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Generic, TypeVar

import greenlet

T = TypeVar("T")
Request = Any
Reply = Any


class _Abandoned(GeneratorExit):
    """Thrown into a waiting run when the lockstep ends early (another run or the batch failed,
    or the caller was interrupted): the run unwinds and ends. Like a generator's ``close()``, a
    ``BaseException``, so a run's ``except Exception`` does not stop it."""


class Lockstep(Generic[T]):
    """Runs callables that call :meth:`ask`, serving their requests in batches.

    Args:
        evaluate: answers a list of requests with a list of replies, in the same order.
    """

    def __init__(self, evaluate: Callable[[list[Request]], Sequence[Reply]]):
        self.evaluate = evaluate
        self._slots: dict[greenlet.greenlet, _Slot] = {}
        #: Number of batched calls made and requests served (for benchmarks and logs).
        self.batches = 0
        self.requests = 0

    def ask(self, request: Request) -> Reply:
        """The reply to ``request``: batched with the other runs' inside :meth:`run`, else at once."""
        slot = self._slots.get(greenlet.getcurrent())
        if slot is None:
            self.batches += 1
            self.requests += 1
            return self.evaluate([request])[0]
        return slot.ask(request)

    def run(self, runs: Sequence[Callable[[], T]]) -> list[T]:
        """Every run's return value, in order. An exception in a run (or in the batched
        evaluation) ends every run: it is raised here once the others have been unwound."""
        slots = [_Slot(self, run) for run in runs]
        try:
            for slot in slots:
                slot.resume(None)  # runs until its first request or its end
                if slot.error is not None:
                    break
            while not any(slot.error is not None for slot in slots):
                waiting = [slot for slot in slots if slot.state == "waiting"]
                if not waiting:
                    break
                replies = self.evaluate([slot.request for slot in waiting])
                self.batches += 1
                self.requests += len(waiting)
                for slot, reply in zip(waiting, replies):
                    slot.resume(reply)  # runs until its next request or its end
                    if slot.error is not None:
                        break
        finally:
            for slot in slots:
                slot.abandon()
        for slot in slots:
            if slot.error is not None:
                raise slot.error
        return [slot.result for slot in slots]


class _Slot:
    """One run: its greenlet and its pending request."""

    def __init__(self, lockstep: Lockstep, run: Callable[[], Any]):
        self.lockstep = lockstep
        self.run = run
        self.state = "new"  # new, waiting, done
        self.request: Request = None
        self.result: Any = None
        self.error: Exception | None = None
        self._scheduler = greenlet.getcurrent()
        self._greenlet = greenlet.greenlet(self._main, parent=self._scheduler)
        lockstep._slots[self._greenlet] = self

    def resume(self, reply: Reply) -> None:
        """Let the run go with ``reply`` until it asks again or ends. An interrupt inside the run
        comes out here (the greenlet's parent is the scheduler)."""
        self.request = None
        self._greenlet.switch(reply)

    def abandon(self) -> None:
        """End a run that has not finished (after an error or an interrupt): unwind it where it
        waits."""
        try:
            if self.state == "waiting":
                self._greenlet.throw(_Abandoned())
        finally:
            self.state = "done"
            self.lockstep._slots.pop(self._greenlet, None)

    def ask(self, request: Request) -> Reply:
        self.request, self.state = request, "waiting"
        reply = self._scheduler.switch()
        self.state = "running"
        return reply

    def _main(self, _: Reply) -> None:
        self.state = "running"
        try:
            self.result = self.run()
        except _Abandoned:
            pass
        except Exception as exc:  # handed to the scheduler, raised in the caller
            self.error = exc
        finally:
            self.state = "done"
