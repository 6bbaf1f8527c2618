"""The installed version of mobmanip (pyproject.toml is its one source)."""

from __future__ import annotations


def installed_version() -> str:
    """The version of the installed distribution; ``0+unknown`` from a source tree never installed."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("mobmanip")
    except PackageNotFoundError:
        return "0+unknown"
