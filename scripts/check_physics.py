"""Replay a robot's grounded capacity in MuJoCo: ``mobmanip referee`` with 97 % of each maximum.

The referee is part of the installed package now (``pip install 'mobmanip[referee]'``); this
script runs the command, replaying 97 % of each maximum unless ``--fraction`` says otherwise (its
old default; the command's is the maximum itself)::

    python scripts/check_physics.py tiago_dual --posture hold --object-mass 2 --task spatial --mu 0.5
    python scripts/check_physics.py tiago_dual --posture hold --object-mass 2 --task spatial --held

Every option is the command's (``mobmanip referee --help``); so are the exit codes: 0 when every
axis agrees with MuJoCo at t = 0 and holds, 1 when one does not, 2 for bad input.
"""

from __future__ import annotations

import sys

#: The share of each maximum replayed when --fraction is not given.
FRACTION = "0.97"


def main(argv: list[str] | None = None) -> int:
    from mobmanip.cli import main as mobmanip

    args = list(sys.argv[1:] if argv is None else argv)
    if not any(a == "--fraction" or a.startswith("--fraction=") for a in args):
        args += ["--fraction", FRACTION]
    return mobmanip(["referee", *args])


if __name__ == "__main__":
    sys.exit(main())
