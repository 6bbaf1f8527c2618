"""Writing TOML that reads back to the same names, whatever a robot file calls its joints.

TOML (1.0) basic strings may hold any Unicode scalar value, but not every character as itself:
``"`` and ``\\`` must be escaped, and so must the control characters U+0000 to U+001F and U+007F
(DEL). A JSON string is not always a valid TOML string: JSON leaves DEL bare and writes a
character beyond U+FFFF (an emoji) as a surrogate pair, which TOML refuses. :func:`toml_string`
escapes exactly what TOML requires and writes every other character as itself (UTF-8), so a name
with an emoji, a DEL, a quote, a backslash, a newline or a combining mark reads back unchanged.
The one thing TOML cannot hold is a lone surrogate (U+D800 to U+DFFF: not a character; no XML
file can carry one either); it is refused.
"""

from __future__ import annotations

import re

from ..errors import ArgumentError

_BARE_KEY = re.compile(r"^[A-Za-z0-9_-]+$")
_NEEDS_ESCAPE = re.compile(r'["\\\x00-\x1f\x7f]')
_SHORT = {'"': '\\"', "\\": "\\\\", "\b": "\\b", "\t": "\\t", "\n": "\\n", "\f": "\\f", "\r": "\\r"}
_SURROGATE = re.compile("[\ud800-\udfff]")
_CONTROL = re.compile(r"[\x00-\x1f\x7f]")


def _escape(match: re.Match) -> str:
    character = match.group(0)
    return _SHORT.get(character) or f"\\u{ord(character):04X}"


def toml_string(value: str) -> str:
    """``value`` as a TOML basic string that reads back to it exactly.

    Raises:
        ArgumentError: it holds a lone surrogate, which no TOML (nor UTF-8) text can carry.
    """
    value = str(value)
    found = _SURROGATE.search(value)
    if found:
        raise ArgumentError(
            f"the name {value!r} holds a lone surrogate (U+{ord(found.group(0)):04X}), which TOML cannot store; "
            "rename it in the robot file"
        )
    return '"' + _NEEDS_ESCAPE.sub(_escape, value) + '"'


def toml_key(name: str) -> str:
    """``name`` as a TOML key: bare when it may be, quoted otherwise (see :func:`toml_string`)."""
    return name if _BARE_KEY.match(name) else toml_string(name)


def toml_comment(text: str) -> str:
    """``text`` fit for a ``# comment``: control characters (a newline would end the comment and
    make the rest of the line TOML) written as escapes, so the comment stays one line."""
    return _CONTROL.sub(lambda m: f"\\u{ord(m.group(0)):04X}", _SURROGATE.sub("\ufffd", str(text)))


def toml_array(values) -> str:
    """A TOML array of strings."""
    return "[" + ", ".join(toml_string(v) for v in values) + "]"
