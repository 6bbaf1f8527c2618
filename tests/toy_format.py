"""A toy robot-description format for the tests: a URDF compressed with gzip, suffix ``.urdfz``.

It is the whole of a new format: one reader and the one registration line at the bottom.
Nothing else in mobmanip changes for specs (``urdf = "robot.urdfz"``), ``--urdf robot.urdfz``
and ``init-spec`` to read it (see ``tests/test_description_formats.py``).
"""

from __future__ import annotations

import gzip
from collections.abc import Iterable
from pathlib import Path

from mobmanip.descriptions import DescriptionFormat, RobotDescription, register_format, urdf_description
from mobmanip.errors import DescriptionError


def read_urdfz(path: Path, *, package_dirs: Iterable[str | Path] | None = None) -> RobotDescription:
    """The description of a gzip'd URDF (checked like any URDF; format ``"urdfz"``)."""
    try:
        text = gzip.decompress(Path(path).read_bytes()).decode("utf-8")
    except (OSError, EOFError, UnicodeDecodeError) as exc:
        raise DescriptionError(str(path), f"not a gzip'd URDF: {exc}") from None
    return urdf_description(text, path, format="urdfz", package_dirs=package_dirs)


def write_urdfz(urdf: Path, target: Path) -> Path:
    """``urdf`` compressed into ``target`` (a ``.urdfz`` file); returns ``target``."""
    target.write_bytes(gzip.compress(Path(urdf).read_bytes()))
    return target


FORMAT = register_format(DescriptionFormat("urdfz", (".urdfz",), read_urdfz))
