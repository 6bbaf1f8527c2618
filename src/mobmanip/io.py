"""Reading configuration files and writing results without losing data."""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import IO

import numpy as np

from .errors import ConfigurationError, NumericalError, OutputError
from .model import Robot


def configuration_from_dict(robot: Robot, data: object, where: str = "configuration") -> np.ndarray:
    """q from ``{"platform": [x, y, yaw], "joints": {NAME: value}}`` (both keys optional).

    Raises:
        ConfigurationError: malformed document or NaN value; JointNotFoundError: unknown joint.
    """
    if not isinstance(data, dict):
        raise ConfigurationError(f"{where}: expected an object with 'platform' and 'joints', got {type(data).__name__}")
    unknown = sorted(set(data) - {"platform", "joints"})
    if unknown:
        raise ConfigurationError(f"{where}: unknown keys {unknown}; expected 'platform' and 'joints'")
    platform = data.get("platform", [0.0, 0.0, 0.0])
    joints = data.get("joints", {})
    if not isinstance(platform, list) or len(platform) != 3:
        raise ConfigurationError(f"{where}: 'platform' must be [x, y, yaw], got {platform!r}")
    for value in platform:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not _finite(value):
            raise ConfigurationError(f"{where}: platform pose entries must be finite numbers, got {value!r}")
    if not isinstance(joints, dict):
        raise ConfigurationError(f"{where}: 'joints' must map joint names to values, got {joints!r}")
    return robot.configuration(tuple(platform), joints)


def _finite(value: float) -> bool:
    """math.isfinite that treats an integer too large for a float as infinite."""
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _reject_constant(token: str):
    raise ConfigurationError(f"non-finite number {token} in JSON")


def read_configuration(robot: Robot, path: str | Path) -> np.ndarray:
    """Read a Q.json file (see :func:`configuration_from_dict`)."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as exc:
        raise ConfigurationError(f"cannot read configuration {path}: {exc.strerror or exc}") from exc
    except UnicodeDecodeError as exc:
        raise ConfigurationError(f"configuration {path} is not UTF-8 text: {exc.reason} at byte {exc.start}") from None
    try:
        # Integers are read as floats: a huge integer becomes inf and is rejected as non-finite.
        data = json.loads(text, parse_constant=_reject_constant, parse_int=float)
    except json.JSONDecodeError as exc:
        raise ConfigurationError(f"configuration {path} is not valid JSON: {exc}") from exc
    except ConfigurationError as exc:
        raise ConfigurationError(f"configuration {path}: {exc}") from None
    return configuration_from_dict(robot, data, where=str(path))


@contextlib.contextmanager
def atomic_output(path: str | Path, mode: str = "w", **open_options) -> Iterator[IO]:
    """Open a temporary file beside ``path`` that replaces it only once written completely.

    Every file mobmanip writes goes through here, so an error or an interruption midway never
    leaves a truncated file in place of a good one, nor a temporary file behind.

    Args:
        path: the file to write.
        mode: ``"w"`` (text) or ``"wb"`` (binary).
        **open_options: passed to :func:`open` (e.g. ``newline=""`` for CSV).

    Raises:
        OutputError: the directory does not exist or is not writable.
    """
    path = Path(path)
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent if str(path.parent) else ".", prefix=f".{path.name}.", suffix=".tmp")
        with os.fdopen(fd, mode, **open_options) as handle:
            yield handle
        os.chmod(tmp, 0o666 & ~_umask())  # mkstemp creates 0600; give the file the usual permissions
        os.replace(tmp, path)
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


def save_figure(figure, path: str | Path, **options) -> Path:
    """Save a matplotlib figure atomically, in the format named by the file's suffix (PNG by default)."""
    path = Path(path)
    with atomic_output(path, "wb") as handle:
        figure.savefig(handle, format=path.suffix.lstrip(".").lower() or "png", **options)
    return path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
