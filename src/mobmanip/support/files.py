"""Files in and out: inputs a command must not overwrite, and results written atomically, all or none."""

from __future__ import annotations

import contextlib
import contextvars
import json
import math
import os
import signal
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
#: Directories :func:`output_directory` created inside :func:`publish_together`, removed again
#: (when still empty) if the block fails.
_CREATED: contextvars.ContextVar[list | None] = contextvars.ContextVar("mobmanip_created", default=None)

#: The longest file name most file systems accept (bytes); temporary names beside an output fit it.
NAME_MAX = 255
#: The signals during which a temporary file is created or the outputs are renamed into place:
#: held back for that moment, so an interruption never leaves a temporary file or half the outputs.
_HELD_SIGNALS = {signal.SIGINT, signal.SIGTERM}
#: Paths that are not files on a disk: ``--json /dev/stdout`` is refused like any other device
#: (the results are printed on standard output anyway; ``--json`` names a file to keep).
_SPECIAL_ROOTS = ("/dev/", "/proc/", "/sys/")


@contextlib.contextmanager
def _signals_held() -> Iterator[None]:
    """Hold back SIGINT and SIGTERM for the block (delivered at its end)."""
    if not hasattr(signal, "pthread_sigmask"):
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, _HELD_SIGNALS)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)


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

    SIGINT and SIGTERM are held back while the files are renamed, so an interruption comes
    before (nothing published, temporaries removed) or after (all published). Directories created
    by :func:`output_directory` inside the block are removed again, when still empty, if it fails.

    Raises:
        OutputError: a file could not be published (none of them was).
    """
    pending: list[tuple[str, Path]] = []
    created: list[Path] = []
    token, created_token = _PENDING.set(pending), _CREATED.set(created)
    try:
        try:
            yield
        except BaseException:
            _discard(pending, created)
            raise
        finally:
            _PENDING.reset(token)
        try:
            with _signals_held():
                _publish_all(pending)
        except BaseException:
            _remove_created(created)
            raise
    finally:
        _CREATED.reset(created_token)


def _discard(pending: list[tuple[str, Path]], created: list[Path]) -> None:
    """Remove the temporary files of a failed block and the directories it created."""
    for tmp, _ in pending:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
    _remove_created(created)


def _remove_created(created: list[Path]) -> None:
    for directory in reversed(created):  # deepest first
        with contextlib.suppress(OSError):
            directory.rmdir()  # only if still empty: never a file of the user's


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
    _refuse_special_path(out, option)
    missing = [p for p in (out, *out.parents) if not p.exists() and not p.is_symlink()]
    try:
        out.mkdir(parents=True, exist_ok=True)
        created = _CREATED.get()
        if created is not None:
            created.extend(reversed(missing))  # outermost first: removed deepest first
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
        _refuse_special_path(path)
        if path.is_symlink():  # a dangling link: write where it points
            return Path(os.path.realpath(path)), None
        return path, None
    except OSError as exc:
        raise OutputError(f"cannot write {path}: {exc.strerror or exc}") from exc
    if not stat.S_ISREG(info.st_mode):
        kind = next((name for test, name in _KINDS if test(info.st_mode)), "not a regular file")
        raise OutputError(f"cannot write {path}: it is {kind}; give the path of a regular file")
    _refuse_special_path(path)
    inputs = _INPUTS.get()
    if inputs is not None and (info.st_dev, info.st_ino) in inputs:
        raise OutputError(f"refusing to write {path}: it is an input of this command; choose another output path")
    return Path(os.path.realpath(path)), stat.S_IMODE(info.st_mode)


def _refuse_special_path(path: Path, option: str = "") -> None:
    """Refuse a path in /dev, /proc or /sys (itself or where its links lead): ``/dev/stdout``
    leads to whatever standard output is (a terminal, a pipe, or a file that a rename would
    replace under the shell's redirection)."""
    literal = os.path.abspath(path)
    resolved = os.path.realpath(path)
    for candidate in (literal, resolved):
        if any(candidate == root.rstrip("/") or candidate.startswith(root) for root in _SPECIAL_ROOTS):
            where = (option + " " if option else "") + str(path)
            raise OutputError(
                f"cannot write {where}: it is a special file (under /{candidate.split('/')[1]}), not a file on a "
                "disk; give the path of a regular file (results are printed on standard output anyway)"
            )


def temporary_prefix(name: str) -> str:
    """The prefix of a temporary file beside ``name``: ``.NAME.`` shortened so that the
    temporary name and its backup (``.NAME.XXXXXXXX.tmp.previous``) fit :data:`NAME_MAX` bytes."""
    room = NAME_MAX - len(".") - len(".") - 8 - len(".tmp") - len(".previous")
    encoded = name.encode("utf-8", "surrogateescape")
    if len(encoded) > room:
        name = encoded[:room].decode("utf-8", "ignore")
    return f".{name}."


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
        with _signals_held():  # no interruption between creating the file and knowing its name
            fd, tmp = tempfile.mkstemp(dir=directory, prefix=temporary_prefix(target.name), suffix=".tmp")
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


def figure_formats() -> tuple[str, ...]:
    """The figure formats matplotlib writes (file suffixes without the dot)."""
    from matplotlib.backend_bases import FigureCanvasBase

    return tuple(sorted(FigureCanvasBase.get_supported_filetypes()))


def check_figure_output(path: str | Path, option: str = "--figure") -> None:
    """Refuse, before any work, a figure path whose suffix names no format matplotlib writes, or
    that :func:`check_output` refuses.

    Raises:
        OutputError: naming the option, the path and the formats there are.
    """
    path = Path(path)
    check_output(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    formats = figure_formats()
    if fmt not in formats:
        raise OutputError(f"{option} {path}: unknown figure format {fmt!r}; use one of {', '.join(formats)}")


def save_figure(figure: Any, path: str | Path, **options: Any) -> Path:
    """Save a matplotlib figure atomically, in the format named by the file's suffix (PNG by default).

    Raises:
        OutputError: the suffix names no figure format (see :func:`check_figure_output`), or the
            file cannot be written.
    """
    path = Path(path)
    fmt = path.suffix.lstrip(".").lower() or "png"
    if fmt not in figure_formats():
        check_figure_output(path, "figure")
    with atomic_output(path, "wb") as handle:
        figure.savefig(handle, format=fmt, **options)
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
