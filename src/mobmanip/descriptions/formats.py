"""The robot-description formats: which reader turns a file of which suffix into a description.

A format is a name, the file suffixes it claims and a function that reads one file into a
:class:`~mobmanip.descriptions.description.RobotDescription`. :func:`read_description` picks the
format by the file's suffix (the longest registered one that matches, so ``.urdf.xacro`` may
go to another reader than ``.xacro``); every caller that reads a robot file (specs, ``--urdf``,
``init-spec``) goes through it. A new format is one module and one registration line::

    from mobmanip.descriptions import DescriptionFormat, register_format

    register_format(DescriptionFormat("urdfz", (".urdfz",), read_urdfz))

URDF (:mod:`mobmanip.descriptions.urdf`) registers itself when :mod:`mobmanip.descriptions` is
imported.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..errors import ArgumentError, UnknownFormatError
from .description import NameMap, RobotDescription

#: ``read(path, **options) -> RobotDescription``: reads one file (see :class:`DescriptionFormat`).
DescriptionReader = Callable[..., RobotDescription]


@dataclass(frozen=True)
class DescriptionFormat:
    """A robot-description format.

    Attributes:
        name: the format's name, recorded in each description it reads (e.g. ``"urdf"``).
        suffixes: the file suffixes it reads, lower case with their dot (e.g. ``(".urdf",)``);
            several dots are allowed (``".urdf.xacro"``).
        read: ``read(path, **options) -> RobotDescription``; ``options`` are those given to
            :func:`read_description` (``package_dirs``: where ``package://`` URIs resolve).
            It raises a :class:`~mobmanip.errors.DescriptionError` for a file it cannot read.
        options: the options ``read`` takes (every reader takes ``package_dirs``); e.g. xacro
            also takes ``xacro_args`` and ``package_paths``.
    """

    name: str
    suffixes: tuple[str, ...]
    read: DescriptionReader
    options: tuple[str, ...] = ("package_dirs",)

    def __post_init__(self) -> None:
        suffixes = tuple(self.suffixes)
        if not self.name or not suffixes:
            raise ArgumentError(f"a description format needs a name and at least one suffix, got {self!r}")
        for suffix in suffixes:
            if not isinstance(suffix, str) or not suffix.startswith(".") or suffix != suffix.lower() or len(suffix) < 2:
                raise ArgumentError(f"format {self.name!r}: a suffix is lower case and starts with '.', got {suffix!r}")
        object.__setattr__(self, "suffixes", suffixes)


_FORMATS: dict[str, DescriptionFormat] = {}


def register_format(description_format: DescriptionFormat, *, replace: bool = False) -> DescriptionFormat:
    """Add a format to the registry (registering the same one again does nothing).

    Args:
        description_format: the format.
        replace: let it take over names and suffixes another format holds.

    Returns:
        The format, so that a module can keep it: ``FORMAT = register_format(...)``.

    Raises:
        ArgumentError: its name or a suffix is taken by another format (and not ``replace``).
    """
    for other in list(_FORMATS.values()):
        if other == description_format:
            continue
        clash = other.name == description_format.name or set(other.suffixes) & set(description_format.suffixes)
        if clash and not replace:
            raise ArgumentError(
                f"format {description_format.name!r} ({', '.join(description_format.suffixes)}) clashes with "
                f"registered format {other.name!r} ({', '.join(other.suffixes)}); pass replace=True to take over"
            )
        if clash:
            unregister_format(other.name)
    _FORMATS[description_format.name] = description_format
    return description_format


def unregister_format(name: str) -> None:
    """Remove the format registered as ``name`` (nothing if there is none)."""
    _FORMATS.pop(name, None)


def formats() -> Mapping[str, DescriptionFormat]:
    """The registered formats by name, in registration order (a read-only snapshot)."""
    return NameMap(_FORMATS.items())


def known_suffixes() -> tuple[str, ...]:
    """Every registered suffix, in registration order."""
    return tuple(suffix for f in _FORMATS.values() for suffix in f.suffixes)


def format_for(path: str | Path) -> DescriptionFormat:
    """The format that reads ``path``, by its suffix (case-insensitive; the longest match wins).

    Raises:
        UnknownFormatError: no registered format claims the suffix (the message lists those known).
    """
    name = Path(path).name.lower()
    best: tuple[int, DescriptionFormat] | None = None
    for candidate in _FORMATS.values():
        for suffix in candidate.suffixes:
            if name.endswith(suffix) and len(name) > len(suffix) and (best is None or len(suffix) > best[0]):
                best = (len(suffix), candidate)
    if best is None:
        raise UnknownFormatError(str(path), Path(path).suffix, known_suffixes())
    return best[1]


def read_description(path: str | Path, **options: Any) -> RobotDescription:
    """Read a robot file into its neutral description, with the format its suffix names.

    Args:
        path: the file.
        **options: handed to the format's reader; every reader takes ``package_dirs``, the
            directories where ``package://`` URIs resolve (default: the file's folder). An
            option the format does not take (:attr:`DescriptionFormat.options`) is dropped when
            empty (``None``, ``{}``, ``()``) and refused otherwise.

    Raises:
        ArgumentError: a non-empty option the format does not take (``xacro_args`` for a URDF).
        UnknownFormatError: no registered format reads the suffix.
        DescriptionError: the file is missing, unreadable, malformed or describes no physical
            robot (the format's own subclass, e.g. :class:`~mobmanip.errors.UrdfError`).
    """
    from ..support.files import note_input

    path = Path(path)
    reader = format_for(path)
    taken = {}
    for key, value in options.items():
        if key in reader.options:
            taken[key] = value
        elif value is not None and (not hasattr(value, "__len__") or len(value)):
            raise ArgumentError(
                f"{path.name}: {key} applies to {_formats_taking(key)} files, not to a {reader.name} file"
            )
    note_input(path)
    return reader.read(path, **taken)


def _formats_taking(option: str) -> str:
    names = [f.name for f in _FORMATS.values() if option in f.options]
    return " or ".join(names) or "no registered"
