"""Files in and out: inputs a command must not overwrite, and results written atomically, all or none."""

from __future__ import annotations

import contextlib
import contextvars
import json
import math
import os
import stat
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO, Any

from ..errors import NumericalError, OutputError

#: Files read by the command running now (``(st_dev, st_ino)``), which no output may replace;
#: ``None`` outside :func:`protect_inputs`.
_INPUTS: contextvars.ContextVar[set | None] = contextvars.ContextVar("mobmanip_inputs", default=None)
#: The outputs of :func:`publish_together` waiting to be published: ``[(temporary, final)]``.
_PENDING: contextvars.ContextVar[list | None] = contextvars.ContextVar("mobmanip_pending", default=None)


@contextlib.contextmanager
def protect_inputs() -> Iterator[None]:
    """While active, every file read through :func:`note_input` is protected: an output that
    would replace it is refused (``mobmanip analyze --q q.json --json q.json``)."""
    token = _INPUTS.set(set())
    try:
        yield
    finally:
        _INPUTS.reset(token)


def note_input(path: str | Path) -> None:
    """Record that ``path`` was read (no effect outside :func:`protect_inputs`)."""
    inputs = _INPUTS.get()
    if inputs is None:
        return
    with contextlib.suppress(OSError):
        info = os.stat(path)
        inputs.add((info.st_dev, info.st_ino))


@contextlib.contextmanager
def publish_together() -> Iterator[None]:
    """Publish every file written through :func:`atomic_output` inside the block at its end, all
    of them or none.

    Each file is written completely to a temporary file first; if anything fails before the end
    of the block (an unwritable output, an error midway), no output replaces an existing file.
    At the end the files are renamed into place; if one rename fails, the files already
    replaced are restored from links kept beside them.

    Raises:
        OutputError: a file could not be published (none of them was).
    """
    pending: list[tuple[str, Path]] = []
    token = _PENDING.set(pending)
    try:
        yield
    except BaseException:
        _PENDING.reset(token)
        for tmp, _ in pending:
            with contextlib.suppress(OSError):
                os.unlink(tmp)
        raise
    _PENDING.reset(token)
    _publish_all(pending)


def _publish_all(pending: list[tuple[str, Path]]) -> None:
    done: list[tuple[Path, str | None]] = []  # (published path, link to the file it replaced)
    try:
        for tmp, path in pending:
            backup = None
            if path.exists():
                backup = f"{tmp}.previous"
                os.link(path, backup)
            os.replace(tmp, path)
            done.append((path, backup))
    except OSError as exc:
        for path, backup in reversed(done):
            with contextlib.suppress(OSError):
                if backup is None:
                    os.unlink(path)
                else:
                    os.replace(backup, path)
        for tmp, _ in pending:
            for leftover in (tmp, f"{tmp}.previous"):
                with contextlib.suppress(OSError):
                    os.unlink(leftover)
        raise OutputError(f"cannot publish {path}: {exc.strerror or exc}; no output was changed") from exc
    for _, backup in done:
        if backup is not None:
            with contextlib.suppress(OSError):
                os.unlink(backup)


def output_directory(path: str | Path, option: str = "--out") -> Path:
    """Create an output directory (with its parents) if it is missing, before any work is done.

    Raises:
        OutputError: the path names a file, or the directory cannot be created.
    """
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except FileExistsError as exc:
        raise OutputError(f"{option} {out}: a file of that name exists, not a directory") from exc
    except OSError as exc:
        raise OutputError(f"{option} {out}: cannot create the directory ({exc.strerror or exc})") from exc
    return out


def check_output(path: str | Path) -> None:
    """Refuse, before any work, an output path that :func:`atomic_output` would refuse later
    (an input of the command, a directory, FIFO, device or socket).

    Raises:
        OutputError: naming the path and why.
    """
    _check_target(Path(path))


def _check_target(path: Path) -> tuple[Path, int | None]:
    """The file to replace (a symlink's target) and its permission bits, or ``None`` if absent.

    Raises:
        OutputError: the path is an input of the command, or not a regular file (a directory,
            a FIFO, a device such as /dev/null, a socket, or a symlink to one of them).
    """
    try:
        info = os.stat(path)
    except FileNotFoundError:
        if path.is_symlink():  # a dangling link: write where it points
            return Path(os.path.realpath(path)), None
        return path, None
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc.strerror or exc}") from exc
    if not stat.S_ISREG(info.st_mode):
        kind = next((name for test, name in _KINDS if test(info.st_mode)), "not a regular file")
        raise OutputError(f"cannot write {path}: it is {kind}; give the path of a regular file")
    inputs = _INPUTS.get()
    if inputs is not None and (info.st_dev, info.st_ino) in inputs:
        raise OutputError(f"refusing to write {path}: it is an input of this command; choose another output path")
    return Path(os.path.realpath(path)), stat.S_IMODE(info.st_mode)


_KINDS = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


@contextlib.contextmanager
def atomic_output(path: str | Path, mode: str = "w", **open_options: Any) -> Iterator[IO]:
    """Open a temporary file beside ``path`` that replaces it only once written completely.

    Every file mobmanip writes goes through here, so an error or an interruption midway never
    leaves a truncated file in place of a good one, nor a temporary file behind. An existing
    file keeps its permissions (a new one gets the usual ``0666 & ~umask``); a symlink is
    followed and its target replaced. Inside :func:`publish_together` the file is published
    with the others at the end of the block.

    Args:
        path: the file to write.
        mode: ``"w"`` (text) or ``"wb"`` (binary).
        **open_options: passed to :func:`open` (e.g. ``newline=""`` for CSV).

    Raises:
        OutputError: the directory does not exist or is not writable; ``path`` is a directory,
            FIFO, device or socket; or it is an input of the running command (see
            :func:`protect_inputs`).
    """
    path = Path(path)
    target, permissions = _check_target(path)
    pending = _PENDING.get()
    tmp = None
    try:
        directory = target.parent if str(target.parent) else Path(".")
        fd, tmp = tempfile.mkstemp(dir=directory, prefix=f".{target.name}.", suffix=".tmp")
        with os.fdopen(fd, mode, **open_options) as handle:
            yield handle
        # mkstemp creates 0600: give the file the permissions of the one it replaces, else the usual ones
        os.chmod(tmp, permissions if permissions is not None else 0o666 & ~_umask())
        if pending is not None:
            pending.append((tmp, target))
        else:
            os.replace(tmp, target)
        tmp = None
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc.strerror or exc}") from exc
    finally:
        if tmp is not None:
            with contextlib.suppress(OSError):
                os.unlink(tmp)


def write_text(path: str | Path, text: str) -> None:
    """Write a text file atomically (see :func:`atomic_output`)."""
    with atomic_output(path, "w", encoding="utf-8") as handle:
        handle.write(text)


def write_json(path: str | Path, document: object) -> None:
    """Write JSON atomically: a partial file never replaces an existing one.

    Raises:
        OutputError: the directory does not exist or is not writable.
    """
    try:
        text = json.dumps(document, indent=2, allow_nan=False)
    except ValueError:  # json's only complaint with allow_nan=False: a NaN or an infinity
        raise NumericalError(f"not writing {path}: {_first_non_finite(document)} is not finite") from None
    write_text(path, text + "\n")


def _first_non_finite(document: object, where: str = "the result") -> str:
    """Where the first NaN or infinity of a JSON-ready document is, as ``key.key[i]``."""
    if isinstance(document, float) and not math.isfinite(document):
        return where
    if isinstance(document, dict):
        items = ((f"{where}.{k}", v) for k, v in document.items())
    elif isinstance(document, (list, tuple)):
        items = ((f"{where}[{i}]", v) for i, v in enumerate(document))
    else:
        return ""
    for key, value in items:
        found = _first_non_finite(value, key)
        if found:
            return found
    return ""


def require_finite(document: object, what: str = "the result") -> None:
    """Raise :class:`NumericalError` naming the first NaN or infinity in a JSON-ready document.

    Commands call it before printing a result, so no NaN or inf reaches the user as a number.
    """
    found = _first_non_finite(document, what)
    if found:
        raise NumericalError(f"{found} is not finite; the inputs lie outside the range where results are certified")


def save_figure(figure: Any, path: str | Path, **options: Any) -> Path:
    """Save a matplotlib figure atomically, in the format named by the file's suffix (PNG by default)."""
    path = Path(path)
    with atomic_output(path, "wb") as handle:
        figure.savefig(handle, format=path.suffix.lstrip(".").lower() or "png", **options)
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
