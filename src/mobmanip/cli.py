"""The ``mobmanip`` command.

Each subcommand lives in :mod:`mobmanip.commands` and registers itself. Every error caused by
bad input prints one line ``mobmanip: error: ...`` on standard error and exits with code 2.
"""

from __future__ import annotations

import argparse
import sys

from . import __version__
from .commands import COMMANDS
from .errors import MobmanipError


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors (exit code 2)."""

    def error(self, message):  # noqa: D401 - argparse API
        self.exit(2, f"mobmanip: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="mobmanip", description="What a wheeled mobile manipulator can do at the end effector.")
    parser.add_argument("--version", action="version", version=f"mobmanip {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)

    for module in COMMANDS:
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except MobmanipError as exc:
        print(f"mobmanip: error: {exc}", file=sys.stderr)
        return 2
    except BrokenPipeError:  # output piped into e.g. `head`
        sys.stderr.close()
        return 0
    except KeyboardInterrupt:
        print("mobmanip: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":
    raise SystemExit(main())
