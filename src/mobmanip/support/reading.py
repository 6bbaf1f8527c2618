"""Reading the user's files: one bounded reader for every file a command is given.

Files come from others (a team file from a colleague, a path exported by another tool): a
device such as ``/dev/zero`` named as a robot file, a FIFO, a file of gigabytes or a CSV field
of megabytes must end in one clear line, quickly, not in memory exhaustion or an internal error.
Paths written inside a file resolve against that file's folder, never the current directory.
Numbers read from a table are checked against a stated range with the file, line and column
named.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
import stat
from collections.abc import Callable
from pathlib import Path
from typing import Any

from ..errors import ArgumentError, MobmanipError, NotDecimalError
from .files import note_input

#: Largest user text file read (bytes): specs, team files, configurations, CSV paths and
#: trajectories (a 10^5-sample trajectory of a 30-joint robot is about 60 MB).
MAX_TEXT_BYTES = 256 * 1024 * 1024
#: Longest CSV field (characters): a number never needs more than a few dozen.
MAX_CSV_FIELD = 1024
#: Longest number written as text (characters): ``-1.2345678901234567e-308`` has 24.
MAX_NUMBER_TEXT = 64
#: Time stamps of a path or trajectory (s): their magnitude, and the smallest step between two.
TIME_STAMP = 1e9
MIN_TIME_STEP = 1e-6

#: Largest robot file read (bytes): a URDF, xacro or MJCF file, and all the files it includes
#: together (the largest vendor URDFs are a few megabytes).
MAX_ROBOT_FILE_BYTES = 64 * 1024 * 1024
#: Largest recording read (bytes): a ROS bag, or all the files of a ROS 2 bag folder together.
#: A bag is read message by message, never whole; cameras fill a bag far faster than joint states.
MAX_RECORDING_BYTES = 64 * 1024**3

ErrorFactory = Callable[[str], MobmanipError]
#: A CSV file's rows as (line number, cells).
CsvBody = list[tuple[int, list[str]]]

#: A number in decimal notation (ASCII digits, optional sign, point and exponent), or a
#: not-a-number or infinity word (left for the caller to refuse with its own message).
_DECIMAL = re.compile(r"\s*[+-]?(?:(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:[eE][+-]?[0-9]+)?|nan|inf|infinity)\s*", re.I)


def decimal(text: str) -> float:
    """``float(text)`` for a number written in decimal notation only. Python's ``float`` also
    reads ``"1_0"`` as 10 and digits of other scripts (``"١"``); a command line or a table that
    says ``1_0`` holds a typing error, not ten, so those raise ValueError here.

    Raises:
        NotDecimalError: not a decimal number (a ValueError: argparse reports it as ``invalid
            decimal value``).
    """
    if not isinstance(text, str) or _DECIMAL.fullmatch(text) is None:
        raise NotDecimalError(f"not a decimal number: {text!r}")
    return float(text)


def file_refusal(path: str | Path, *, limit: int) -> str | None:
    """Why a user file is not read, or ``None`` when it is a regular file of at most ``limit``
    bytes. Only the file's status is looked at (never its content), so a FIFO or ``/dev/zero``
    is refused at once, and a huge file without being read.

    Returns:
        ``"file not found"``, another reason it cannot be read, ``"it is a directory"``,
        ``"it is not a regular file (a device, FIFO or socket)"`` or ``"it is N bytes, more
        than the LIMIT this reads"``; ``None`` when the file is fine.
    """
    try:
        info = os.stat(path)
    except FileNotFoundError:
        return "file not found"
    except OSError as exc:
        return f"cannot read it: {exc.strerror or exc}"
    if stat.S_ISDIR(info.st_mode):
        return "it is a directory"
    if not stat.S_ISREG(info.st_mode):
        return "it is not a regular file (a device, FIFO or socket)"
    if info.st_size > limit:
        return f"it is {info.st_size} bytes, more than the {limit} this reads"
    return None


def read_bounded(path: str | Path, *, limit: int, refuse: ErrorFactory) -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes (see :func:`file_refusal`).

    Args:
        path: the file.
        limit: the largest size accepted (bytes).
        refuse: builds the exception raised from the reason (``"it is a directory"``).
    """
    reason = file_refusal(path, limit=limit)
    if reason is not None:
        raise refuse(reason)
    try:
        with open(path, "rb") as handle:
            data = handle.read(limit + 1)
    except OSError as exc:
        raise refuse(f"cannot read it: {exc.strerror or exc}") from None
    if len(data) > limit:  # grew while being read
        raise refuse(f"it grew to more than the {limit} bytes this reads")
    return data


def read_user_bytes(path: str | Path, what: str, *, limit: int = MAX_TEXT_BYTES,
                    error: ErrorFactory = ArgumentError) -> bytes:  # fmt: skip
    """The bytes of a user file: a regular file of at most ``limit`` bytes, noted as an input
    of the running command (:func:`mobmanip.support.files.note_input`).

    Args:
        path: the file.
        what: what the file is, for messages (``"object path"``, ``"team robot file"``).
        limit: the largest size accepted (bytes).
        error: builds the exception raised (a :class:`MobmanipError` subclass taking a message).

    Raises:
        MobmanipError: (from ``error``) the file is missing, unreadable, not a regular file (a
            device, FIFO, directory or socket: never read, so ``/dev/zero`` is refused at once), or
            larger than ``limit``.
    """
    path = Path(path)
    reason = file_refusal(path, limit=limit)
    if reason is not None:
        raise error(f"cannot read {what} {path}: {reason}")
    note_input(path)
    return read_bounded(path, limit=limit, refuse=lambda reason: error(f"cannot read {what} {path}: {reason}"))


def read_user_text(path: str | Path, what: str, *, limit: int = MAX_TEXT_BYTES,
                   error: ErrorFactory = ArgumentError) -> str:  # fmt: skip
    """A user file as UTF-8 text (see :func:`read_user_bytes`; a leading byte-order mark is dropped).

    Raises:
        MobmanipError: (from ``error``) as :func:`read_user_bytes`, or the file is not UTF-8.
    """
    data = read_user_bytes(path, what, limit=limit, error=error)
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise error(f"{what} {path} is not UTF-8 text (byte {exc.start})") from None


def read_user_toml(path: str | Path, what: str, *, limit: int = MAX_TEXT_BYTES,
                   error: ErrorFactory = ArgumentError) -> dict:  # fmt: skip
    """A user TOML file, parsed: read as :func:`read_user_text`, its numbers checked by
    :func:`check_toml_numbers` (messages name ``path`` as given).

    Raises:
        MobmanipError: (from ``error``) as :func:`read_user_text`; the text is not TOML
            (``"<what> <path> is not valid TOML: <reason>"``); a number is out of range.
    """
    import tomllib

    text = read_user_text(path, what, limit=limit, error=error)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise error(f"{what} {path} is not valid TOML: {exc}") from exc
    check_toml_numbers(data, str(path), error=error)
    return data


def read_csv_rows(path: str | Path, what: str, *, error: ErrorFactory = ArgumentError,
                  max_field: int = MAX_CSV_FIELD) -> list[tuple[int, list[str]]]:  # fmt: skip
    """The non-blank rows of a user CSV file as ``(line number, cells)``.

    Raises:
        MobmanipError: (from ``error``) as :func:`read_user_text`, a field longer than
            ``max_field`` characters or malformed CSV (naming the line).
    """
    text = read_user_text(path, what, error=error)
    reader = csv.reader(io.StringIO(text, newline=""))
    rows: list[tuple[int, list[str]]] = []
    limit = csv.field_size_limit()
    csv.field_size_limit(max(max_field + 1, 1))
    try:
        for row in reader:
            if any(len(cell) > max_field for cell in row):
                raise error(f"{what} {path} line {reader.line_num}: a field longer than {max_field} characters")
            if row and any(cell.strip() for cell in row):
                rows.append((reader.line_num, row))
    except csv.Error as exc:
        line = reader.line_num
        if "field larger than field limit" in str(exc):
            raise error(f"{what} {path} line {line}: a field longer than {max_field} characters") from None
        raise error(f"{what} {path} line {line}: not valid CSV ({exc})") from None
    finally:
        csv.field_size_limit(limit)
    return rows


def read_csv_header(path: Path, what: str, *, error: ErrorFactory = ArgumentError) -> tuple[list[str], CsvBody]:
    """A user CSV table's header (its cells stripped) and the rows below it as :func:`read_csv_rows`
    gives them (``what`` names the file in messages: ``"trajectory"``).

    Raises:
        MobmanipError: (from ``error``) as :func:`read_csv_rows`, or a file with no row at all.
    """
    numbered = read_csv_rows(path, what, error=error)
    if not numbered:
        raise error(f"{what} {path} is empty")
    return [cell.strip() for cell in numbered[0][1]], numbered[1:]


def parse_csv_body(path: Path, what: str, header: list[str], body: CsvBody,
                   bound_of: Callable[[str], tuple[float, str]], *,
                   error: ErrorFactory = ArgumentError) -> Any:  # fmt: skip
    """The numbers of a table's rows below its header, (rows, columns) as a NumPy array; each
    cell by :func:`parse_cell` with the bound and unit ``bound_of`` gives for its column's name.

    Raises:
        MobmanipError: (from ``error``) a row with another number of cells than the header, or
            a cell :func:`parse_cell` refuses (naming the line and column).
    """
    import numpy as np

    values = np.zeros((len(body), len(header)))
    for k, (i, row) in enumerate(body):
        if len(row) != len(header):
            raise error(f"{what} {path} line {i}: {len(row)} cells, the header has {len(header)}")
        for j, cell in enumerate(row):
            bound, unit = bound_of(header[j])
            where = f"{what} {path} line {i}, column {header[j]!r}"
            values[k, j] = parse_cell(cell, where, bound=bound, unit=unit, error=error)
    return values


def parse_cell(cell: str, where: str, *, bound: float = math.inf, unit: str = "",
               error: ErrorFactory = ArgumentError) -> float:  # fmt: skip
    """A finite number from a table cell, ``|value| <= bound``.

    Args:
        cell: the text.
        where: the file, line and column (``"object path p.csv line 3, column 'x'"``).
        bound: the largest magnitude accepted.
        unit: the unit, for the message.

    Raises:
        MobmanipError: (from ``error``) naming ``where`` and the text (shortened): not a number,
            not finite, or out of range.
    """
    shown = repr(cell if len(cell) <= 40 else cell[:37] + "...")
    text = cell.strip()
    if len(text) > MAX_NUMBER_TEXT:
        raise error(f"{where}: {shown} is not a number of at most {MAX_NUMBER_TEXT} characters")
    try:
        value = decimal(text)
    except ValueError:
        raise error(f"{where}: not a number: {shown}") from None
    if not math.isfinite(value):
        raise error(f"{where}: not a finite number: {shown}")
    if abs(value) > bound:
        units = f" {unit}" if unit else ""
        raise error(f"{where}: {shown} is outside the supported range [-{bound:g}, {bound:g}]{units}")
    return value


def check_time_stamps(t, what: str, lines, *, error: ErrorFactory = ArgumentError) -> None:
    """Time stamps that increase by at least :data:`MIN_TIME_STEP` (naming the lines).

    Args:
        t: the time stamps (s), in file order.
        what: the file, for messages (``"trajectory m.csv"``).
        lines: the file line of each stamp.
    """
    for k in range(1, len(t)):
        if not t[k] - t[k - 1] >= MIN_TIME_STEP:
            raise error(
                f"{what} line {lines[k]}, column 't': {float(t[k])!r} s follows {float(t[k - 1])!r} s "
                f"(line {lines[k - 1]}); time stamps must increase by at least {MIN_TIME_STEP:g} s"
            )


def resolve_beside(reference: str, named_in: str | Path) -> Path:
    """A path written inside a file, resolved against that file's folder (absolute paths and
    ``~`` as given): ``robot = "r.toml"`` in ``sub/team.toml`` is ``sub/r.toml``, never
    ``./r.toml``."""
    path = Path(reference).expanduser()
    if path.is_absolute():
        return path
    return Path(named_in).parent / path


def looks_like_path(reference: str) -> bool:
    """Whether a reference that may be a name (a built-in robot) or a path is a path: it has a
    folder separator or a file suffix."""
    return "/" in reference or os.sep in reference or Path(reference).suffix != ""


#: Largest integer read from a TOML file: larger ones are not quantities (a mass written with
#: 400 digits would overflow a float).
MAX_TOML_INTEGER = 10**15


def check_toml_numbers(data: object, where: str, *, error: ErrorFactory = ArgumentError) -> None:
    """Refuse integers above :data:`MAX_TOML_INTEGER` and non-finite floats anywhere in a parsed
    TOML document, naming the key (``team.toml: object.mass``)."""
    stack: list[tuple[object, str]] = [(data, "")]
    while stack:
        value, key = stack.pop()
        if isinstance(value, dict):
            stack.extend((v, f"{key}.{k}" if key else str(k)) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, f"{key}[{i}]") for i, v in enumerate(value))
        elif isinstance(value, bool):
            continue
        elif isinstance(value, int) and abs(value) > MAX_TOML_INTEGER:
            digits = len(str(abs(value)))
            raise error(f"{where}: {key} is an integer of {digits} digits, larger than {MAX_TOML_INTEGER:g}")
