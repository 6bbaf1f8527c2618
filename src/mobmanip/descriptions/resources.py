"""Where robot files live: the project's built-in robots, the example-robot-data package and
Hello Robot's hello-robot-stretch-urdf package."""

from __future__ import annotations

from functools import cache
from pathlib import Path
from typing import TYPE_CHECKING

from ..errors import SpecError

if TYPE_CHECKING:
    import importlib.metadata

#: URDF paths in a spec may start with this prefix to point into example-robot-data's robots.
EXAMPLE_ROBOT_DATA_PREFIX = "example-robot-data:"

#: ... or with this one to point into hello-robot-stretch-urdf's ``stretch_urdf`` directory.
STRETCH_URDF_PREFIX = "hello-robot-stretch-urdf:"


def builtin_robots_dir() -> Path:
    """Directory holding the built-in robot specs and URDFs.

    In an installed wheel the robots are packaged inside ``mobmanip/robots``; in a source
    checkout (including editable installs) they are the repository's top-level ``robots/``.
    """
    here = Path(__file__).resolve().parents[1]  # the mobmanip package
    for candidate in (here / "robots", here.parents[1] / "robots"):
        if candidate.is_dir():
            return candidate
    raise SpecError("the built-in robots directory is missing from this installation")


def builtin_robot_names() -> list[str]:
    """Names of the built-in robots (spec files in the robots directory)."""
    return sorted(p.stem for p in builtin_robots_dir().glob("*.toml"))


def _installed(name: str) -> importlib.metadata.Distribution:
    """The installed distribution ``name`` (its metadata: where its files are).

    Raises:
        SpecError: it is not installed (naming the pip command that installs it).
    """
    import importlib.metadata  # here: every command loads a robot, few need an installed distribution's files

    try:
        return importlib.metadata.distribution(name)
    except importlib.metadata.PackageNotFoundError as exc:
        raise SpecError(f"{name} is not installed (pip install {name})") from exc


@cache
def example_robot_data_share() -> Path:
    """The ``share`` directory of the installed example-robot-data distribution.

    Found through the distribution's metadata, never a hard-coded site-packages path. Pass it
    to Pinocchio as a package directory so ``package://`` mesh URIs resolve.
    """
    dist = _installed("example-robot-data")
    for file in dist.files or ():
        parts = Path(str(file)).parts
        if "example-robot-data" in parts and "robots" in parts:
            index = parts.index("example-robot-data")
            share = Path(str(dist.locate_file(Path(*parts[:index]))))
            if (share / "example-robot-data" / "robots").is_dir():
                return share
    raise SpecError("example-robot-data is installed but its robots directory was not found")


@cache
def stretch_urdf_dir() -> Path:
    """The ``stretch_urdf`` directory of the installed hello-robot-stretch-urdf distribution
    (Hello Robot's URDFs of Stretch, one folder per model: RE1V0, RE2V0, SE3), found through
    the distribution's metadata like :func:`example_robot_data_share`."""
    dist = _installed("hello-robot-stretch-urdf")
    for file in dist.files or ():
        parts = Path(str(file)).parts
        if parts and parts[0] == "stretch_urdf" and str(file).endswith(".urdf"):
            folder = Path(str(dist.locate_file("stretch_urdf")))
            if folder.is_dir():
                return folder
    raise SpecError("hello-robot-stretch-urdf is installed but its stretch_urdf directory was not found")


def resolve_urdf_reference(reference: str, base_dir: Path) -> tuple[Path, tuple[Path, ...]]:
    """Turn a spec's ``urdf`` entry into a path and the package directories for its meshes.

    Args:
        reference: a path relative to ``base_dir``, an absolute path,
            ``"example-robot-data:<path under its robots directory>"`` or
            ``"hello-robot-stretch-urdf:<path under stretch_urdf>"``.
        base_dir: directory of the spec file.

    Returns:
        The URDF path and the package directories to hand to Pinocchio.
    """
    if reference.startswith(EXAMPLE_ROBOT_DATA_PREFIX):
        share = example_robot_data_share()
        relative = reference[len(EXAMPLE_ROBOT_DATA_PREFIX) :].lstrip("/")
        return share / "example-robot-data" / "robots" / relative, (share,)
    if reference.startswith(STRETCH_URDF_PREFIX):
        path = stretch_urdf_dir() / reference[len(STRETCH_URDF_PREFIX) :].lstrip("/")
        return path, (path.parent,)  # meshes are "./meshes/..." beside the URDF
    path = Path(reference)
    if not path.is_absolute():
        path = base_dir / path
    return path, (path.parent,)
