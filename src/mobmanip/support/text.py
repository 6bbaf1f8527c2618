"""User-provided text shown to people: on a terminal and in HTML pages.

Names come from files others wrote (a robot's name in its spec, a team member's name): a name
holding ESC or BEL bytes printed raw can retitle, recolour or clear the user's terminal, and
one holding ``</script>`` can run code in a page. Everything mobmanip prints goes through
:func:`escape_terminal` (the command wraps standard output and error in
:class:`EscapingStream`), and text put into HTML through :func:`escape_html`.
"""

from __future__ import annotations

import html
import re
from typing import Any, TextIO

#: C0 controls but tab, newline and carriage return; DEL; C1 controls (U+0080-U+009F, among
#: them the 8-bit CSI); and the bidirectional overrides that reorder what is shown.
_CONTROL = re.compile("[\x00-\x08\x0b\x0c\x0e-\x1f\x7f-\x9f\u202a-\u202e\u2066-\u2069]")


def _escape_one(match: re.Match) -> str:
    code = ord(match.group(0))
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def escape_terminal(text: str) -> str:
    """``text`` with every control character that a terminal acts on written as ``\\xNN``
    (``\\uNNNN``); tabs, newlines and carriage returns (progress lines) are kept."""
    return _CONTROL.sub(_escape_one, text)


def escape_html(text: str) -> str:
    """``text`` safe inside HTML (element content or a quoted attribute), its control characters
    escaped as on a terminal."""
    return html.escape(escape_terminal(text), quote=True)


class EscapingStream:
    """A text stream that writes everything through :func:`escape_terminal` to ``stream``."""

    def __init__(self, stream: TextIO):
        self._stream = stream

    def write(self, text: str) -> int:
        self._stream.write(escape_terminal(text))
        return len(text)

    def writelines(self, lines) -> None:
        for line in lines:
            self.write(line)

    def __getattr__(self, name: str) -> Any:  # flush, fileno, isatty, encoding, ...
        return getattr(self._stream, name)
