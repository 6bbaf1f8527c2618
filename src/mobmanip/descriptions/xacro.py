"""xacro: a ROS robot description with macros, expanded to URDF without ROS.

:func:`read_xacro` (registered as the ``xacro`` format, suffixes ``.xacro`` and ``.urdf.xacro``)
expands the file with the ``xacro`` package from PyPI (no ROS install needed) and reads the URDF
it gives like any other (:func:`mobmanip.descriptions.urdf.urdf_description`): the description
keeps the ``.xacro`` file as its source.

- ``$(arg NAME)``: the values given as ``xacro_args`` (``--xacro-arg NAME=VALUE``, a spec's
  ``[xacro_args]`` table); an argument the file declares with ``<xacro:arg default=...>`` needs
  none. One that is used but has no value is an error naming it and the option that gives it.
- ``$(find PKG)`` (and ``find('PKG')`` in expressions): the package's folder, looked up in
  ``package_paths`` (``--package-path DIR``, a spec's ``package_paths``), then in the
  ``ROS_PACKAGE_PATH`` folders, then under ``share/`` of the ``AMENT_PREFIX_PATH`` prefixes. A
  folder in those lists may be the package itself (named like it, or with a ``package.xml``
  that names it) or hold it, up to :data:`SEARCH_DEPTH` levels down (a workspace's ``src/``).
  A package found nowhere is one error naming it and every folder searched.
- ``package://PKG/...`` mesh URIs of the expanded URDF resolve in the same folders.

xacro keeps its state in module globals, so expansions are serialised (a lock); what it prints
is captured and folded into the error message when the expansion fails.
"""

from __future__ import annotations

import contextlib
import errno
import io
import os
import threading
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

from ..errors import XacroError
from ..support.reading import MAX_ROBOT_FILE_BYTES, file_refusal
from .description import RobotDescription
from .formats import DescriptionFormat, register_format
from .urdf import urdf_description

#: How deep below a package path a ``package.xml`` is looked for (a workspace: ``ws/src/repo/pkg``).
SEARCH_DEPTH = 4

_LOCK = threading.Lock()


def split_paths(text: str | None) -> list[Path]:
    """The folders of a ``:``-separated list (``ROS_PACKAGE_PATH``), empty entries dropped."""
    return [Path(part) for part in (text or "").split(os.pathsep) if part.strip()]


def search_roots(package_paths: Iterable[str | Path] = ()) -> list[Path]:
    """Where packages are looked for, in order: ``package_paths``, ``ROS_PACKAGE_PATH``, then
    ``share/`` of each ``AMENT_PREFIX_PATH`` prefix."""
    roots = [Path(p) for p in package_paths]
    roots += split_paths(os.environ.get("ROS_PACKAGE_PATH"))
    roots += [prefix / "share" for prefix in split_paths(os.environ.get("AMENT_PREFIX_PATH"))]
    return list(dict.fromkeys(roots))


def _package_name(folder: Path) -> str | None:
    """The ``<name>`` of the ``package.xml`` in ``folder`` (``None`` without a readable one)."""
    file = folder / "package.xml"
    if file_refusal(file, limit=MAX_ROBOT_FILE_BYTES) is not None:  # a FIFO or device: skipped, not read
        return None
    try:
        name = ElementTree.parse(file).getroot().findtext("name")
    except (OSError, ElementTree.ParseError):
        return None
    return name.strip() if name else None


class _BoundedOpen:
    """xacro's ``open`` while it expands a file: what it reads (the file, its includes, the YAML
    files it loads) must be regular files, of at most :data:`MAX_ROBOT_FILE_BYTES` together, so
    a FIFO or ``/dev/zero`` included is refused at once, not read forever."""

    def __init__(self) -> None:
        self.read = 0
        self.refused: str | None = None

    def __call__(self, file, mode="r", *args, **kwargs):
        if not any(flag in mode for flag in "wax+"):
            reason = file_refusal(file, limit=MAX_ROBOT_FILE_BYTES)
            if reason is None:
                self.read += os.stat(file).st_size
                if self.read > MAX_ROBOT_FILE_BYTES:
                    reason = f"the file and its includes come to more than the {MAX_ROBOT_FILE_BYTES} bytes this reads"
            if reason is not None:
                self.refused = f"{file}: {reason}"
                raise OSError(errno.EINVAL, reason, str(file))
        return open(file, mode, *args, **kwargs)


def find_package(name: str, roots: Iterable[Path]) -> Path | None:
    """The folder of package ``name`` under ``roots`` (see the module docstring), or ``None``."""
    for root in roots:
        if not root.is_dir():
            continue
        if _package_name(root) == name or (root.name == name and _package_name(root) is None):
            return root
        direct = root / name
        if direct.is_dir() and _package_name(direct) in (name, None):
            return direct
        level = [root]
        for _ in range(SEARCH_DEPTH):
            below = []
            for folder in level:
                with contextlib.suppress(OSError):
                    below += sorted(p for p in folder.iterdir() if p.is_dir() and not p.name.startswith("."))
            for folder in below:
                if (folder / "package.xml").is_file() and _package_name(folder) == name:
                    return folder
            level = below
    return None


class _Packages:
    """``$(find PKG)`` for one expansion: each package resolved once, the misses remembered."""

    def __init__(self, roots: list[Path]) -> None:
        self.roots = roots
        self.found: dict[str, Path] = {}
        self.missing: list[str] = []

    def __call__(self, name: str) -> str:
        name = str(name).strip()
        if name not in self.found:
            folder = find_package(name, self.roots)
            if folder is None:
                self.missing.append(name)
                raise LookupError(name)
            self.found[name] = folder.resolve()
        return str(self.found[name])


def expand_xacro(
    path: str | Path,
    xacro_args: Mapping[str, str] | None = None,
    package_paths: Iterable[str | Path] = (),
) -> tuple[str, list[Path]]:
    """The URDF text of a xacro file, and the folders of the packages it found.

    Args:
        path: the ``.xacro`` file.
        xacro_args: values of ``$(arg NAME)``.
        package_paths: folders searched first for ``$(find PKG)``.

    Raises:
        XacroError: the file is missing or malformed, an argument has no value, a package is
            found nowhere, or xacro fails otherwise (its message in one line).
    """
    try:
        import xacro
        from xacro import substitution_args
    except ImportError as exc:  # pragma: no cover - xacro is a dependency
        raise XacroError(str(path), "reading xacro needs the xacro package (pip install xacro)") from exc
    path = Path(path)
    reason = file_refusal(path, limit=MAX_ROBOT_FILE_BYTES)
    if reason is not None:
        raise XacroError(str(path), reason)
    roots = search_roots(package_paths)
    packages = _Packages(roots)
    mappings = {str(k): str(v) for k, v in (xacro_args or {}).items()}
    printed = io.StringIO()
    with _LOCK, contextlib.redirect_stderr(printed), contextlib.redirect_stdout(printed):
        saved = substitution_args._eval_find, substitution_args._eval_dict.get("find")
        substitution_args._eval_find = packages
        substitution_args._eval_dict["find"] = packages
        bounded = _BoundedOpen()
        xacro.open = bounded  # found before the built-in by xacro's own calls to open()
        try:
            document = xacro.process_file(str(path.resolve()), mappings=mappings, verbosity=0)
            text = document.toxml()
        except Exception as exc:  # xacro raises its own and Python's exceptions alike
            if bounded.refused is not None:
                raise XacroError(str(path), bounded.refused) from None
            raise _failure(path, exc, packages, roots, mappings, printed.getvalue()) from None
        finally:
            del xacro.open
            substitution_args._eval_find, substitution_args._eval_dict["find"] = saved
            xacro.all_includes.clear()
    return text, list(packages.found.values())


def _failure(path: Path, exc: Exception, packages: _Packages, roots: list[Path], mappings, printed: str) -> XacroError:
    """One XacroError saying what went wrong and what supplies the missing piece."""
    from xacro.substitution_args import ArgException

    if packages.missing:
        where = ", ".join(str(r) for r in roots) or "no folder (none given, ROS_PACKAGE_PATH unset)"
        return XacroError(
            str(path),
            f"$(find {packages.missing[-1]}): package {packages.missing[-1]!r} not found (searched {where}); "
            "give its folder, or a folder holding it, with --package-path DIR (package_paths in a spec, "
            "or ROS_PACKAGE_PATH)",
        )
    cause: Any = exc
    while getattr(cause, "exc", None) is not None and not isinstance(cause, ArgException):
        cause = cause.exc
    if isinstance(cause, ArgException) or "Undefined substitution argument" in str(exc):
        name = str(cause).strip() or str(exc)
        given = ", ".join(sorted(mappings)) or "none"
        return XacroError(
            str(path),
            f"$(arg {name}) has no value and no default: give it with --xacro-arg {name}=VALUE "
            f"([xacro_args] in a spec; given: {given})",
        )
    message = " ".join(str(exc).split()) or type(exc).__name__
    detail = " ".join(line.strip() for line in printed.splitlines() if "when processing file" in line)
    return XacroError(str(path), f"xacro cannot expand it: {message}" + (f" ({detail})" if detail else ""))


def read_xacro(
    path: str | Path,
    *,
    package_dirs: Iterable[str | Path] | None = None,
    xacro_args: Mapping[str, str] | None = None,
    package_paths: Iterable[str | Path] = (),
) -> RobotDescription:
    """Expand a xacro file and read the URDF it gives into a checked description.

    Args:
        path: the ``.xacro`` / ``.urdf.xacro`` file.
        package_dirs: where ``package://`` mesh URIs resolve (default: the file's folder); the
            folders holding the packages ``$(find)`` found are added.
        xacro_args: values of ``$(arg NAME)`` (strings).
        package_paths: folders searched first for ``$(find PKG)`` (see the module docstring).

    Raises:
        XacroError: the expansion fails (see :func:`expand_xacro`).
        UrdfError: the expanded URDF is not a valid robot (naming the link or joint).
    """
    from ..support.files import note_input

    path = Path(path)
    note_input(path)
    text, found = expand_xacro(path, xacro_args, package_paths)
    dirs = [Path(p) for p in package_dirs] if package_dirs is not None else [path.parent]
    dirs += [Path(p) for p in package_paths] + [folder.parent for folder in found]
    return urdf_description(text, path, format="xacro", package_dirs=list(dict.fromkeys(dirs)))


def _read(path: Path, **options: Any) -> RobotDescription:
    return read_xacro(path, **options)


#: The xacro format (suffixes ``.xacro``, ``.urdf.xacro``), registered at import.
FORMAT = register_format(
    DescriptionFormat("xacro", (".xacro", ".urdf.xacro"), _read, ("package_dirs", "xacro_args", "package_paths"))
)
