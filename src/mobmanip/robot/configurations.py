"""A configuration from a file or a document: ``{"platform": [x, y, yaw], "joints": {NAME: value}}``."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..errors import ConfigurationError
from ..support.reading import read_user_text
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
    text = read_user_text(path, "configuration", error=ConfigurationError)
    try:
        # Integers are read as floats: a huge integer becomes inf and is rejected as non-finite.
        data = json.loads(text, parse_constant=_reject_constant, parse_int=float)
    except json.JSONDecodeError as exc:
        raise ConfigurationError(f"configuration {path} is not valid JSON: {exc}") from exc
    except RecursionError:
        raise ConfigurationError(f"configuration {path} is nested too deeply to be a configuration") from None
    except ConfigurationError as exc:
        raise ConfigurationError(f"configuration {path}: {exc}") from None
    return configuration_from_dict(robot, data, where=str(path))
