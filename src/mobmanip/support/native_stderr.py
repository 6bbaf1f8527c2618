"""Catch what native code (urdfdom inside Pinocchio) prints on file descriptor 2.

urdfdom reports a malformed URDF with several ``Error: ... at line N in .../link.cpp`` lines
written straight to the process's standard error, below Python. mobmanip reports every failure
as one line of its own, so those messages are captured here and folded into the error raised.
"""

from __future__ import annotations

import contextlib
import os
import re
import sys
import tempfile
import threading
from collections.abc import Iterator
from dataclasses import dataclass, field


@dataclass
class NativeOutput:
    """What native code wrote on standard error inside :func:`captured_native_stderr`."""

    text: str = field(default="")

    def first_error(self) -> str:
        """The first message of urdfdom's, without its ``Error:`` prefix and source location."""
        for line in self.text.splitlines():
            line = line.strip()
            if not line or re.match(r"at line \d+ in ", line):
                continue
            return re.sub(r"^(Error|Warning):\s*", "", line)
        return ""


@contextlib.contextmanager
def captured_native_stderr() -> Iterator[NativeOutput]:
    """Send file descriptor 2 to a temporary file for the duration; the text is in the result.

    When descriptor 2 cannot be redirected (no such descriptor), nothing is captured.
    """
    out = NativeOutput()
    try:
        saved = os.dup(2)
    except OSError:
        yield out
        return
    with tempfile.TemporaryFile(mode="w+b") as sink:
        with contextlib.suppress(AttributeError, ValueError, OSError):
            sys.stderr.flush()
        os.dup2(sink.fileno(), 2)
        try:
            yield out
        finally:
            os.dup2(saved, 2)
            os.close(saved)
            sink.seek(0)
            out.text = sink.read().decode("utf-8", "replace")


#: Stack (bytes) of the thread that runs Pinocchio's URDF parser: it recurses once per joint
#: and link, and a chain of 5,000 links overflows the main thread's usual 8 MB.
PARSER_STACK = 512 * 1024 * 1024


def call_with_large_stack(function, *args, **kwargs):
    """``function(*args, **kwargs)`` in a thread with a :data:`PARSER_STACK` stack; its result,
    or its exception raised here."""
    result: dict = {}

    def run():
        try:
            result["value"] = function(*args, **kwargs)
        except BaseException as exc:  # handed to the calling thread
            result["error"] = exc

    previous = threading.stack_size()
    try:
        threading.stack_size(PARSER_STACK)
        worker = threading.Thread(target=run, name="mobmanip-urdf-parser")
        worker.start()
    except (ValueError, RuntimeError):  # the platform refuses such a stack: parse here
        return function(*args, **kwargs)
    finally:
        threading.stack_size(previous)
    worker.join()
    if "error" in result:
        raise result["error"]
    return result["value"]
