"""Run the hostile-input fuzzers long: more cases, other seeds, a time budget per command.

The test suite runs each fuzzer on a few fixed cases (``tests/test_hostile_fuzz.py`` for
``analyze``: mutated URDFs, specs and configurations; ``tests/test_hostile_fuzz_commands.py`` for
``carry``, ``trajectory``, ``place``, ``team``, ``team-carry``, ``collision-matrix`` and ``site``,
and for the robot-file readers: ``xacro`` and ``mjcf``, analysed). This runs the same tests with
``MOBMANIP_FUZZ_CASES`` cases per command from ``MOBMANIP_FUZZ_SEED``, goes on past a broken case,
and prints per command the cases run, how they ended (one error line or a finite result) and
every case that broke the promise, with its command line. Exit code 1 when any did.

    python scripts/fuzz.py --cases 1000 --seed 7
    python scripts/fuzz.py --cases 100000 --seconds 600 --commands carry,team,xacro

Each case runs in this process (a tenth to half a second each); ``--seconds`` bounds each
command's share. Run it from the repository's root, with mobmanip importable.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = ("analyze", "carry", "trajectory", "place", "team", "team-carry", "collision-matrix", "site",
            "xacro", "mjcf")  # fmt: skip


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=300, help="cases per command (analyze: per kind of file)")
    parser.add_argument("--seed", type=int, default=1, help="seed of the mutations (0: the test suite's own cases)")
    parser.add_argument("--seconds", type=float, help="stop starting cases of a command after this long")
    parser.add_argument(
        "--commands", default=",".join(COMMANDS), help="comma-separated subset of " + ", ".join(COMMANDS)
    )
    args = parser.parse_args(argv)
    commands = [c.strip() for c in args.commands.split(",") if c.strip()]
    unknown = sorted(set(commands) - set(COMMANDS))
    if unknown:
        parser.error(f"unknown commands {unknown}; known: {', '.join(COMMANDS)}")

    with tempfile.TemporaryDirectory(prefix="mobmanip-fuzz-") as folder:
        report = Path(folder) / "report.jsonl"
        env = {**os.environ, "MOBMANIP_FUZZ_CASES": str(args.cases), "MOBMANIP_FUZZ_SEED": str(args.seed),
               "MOBMANIP_FUZZ_REPORT": str(report)}  # fmt: skip
        env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(ROOT / "src"), os.environ.get("PYTHONPATH")]))
        if args.seconds is not None:
            env["MOBMANIP_FUZZ_SECONDS"] = str(args.seconds)
        tests = []
        if "analyze" in commands:
            tests.append("tests/test_hostile_fuzz.py")
        others = [c for c in commands if c != "analyze"]
        if others:
            tests += [f"tests/test_hostile_fuzz_commands.py::test_mutated_inputs_give_one_line_or_a_finite_result[{c}]"
                      for c in others]  # fmt: skip
        command = [sys.executable, "-m", "pytest", "-n", "0", "-q", "-p", "no:cacheprovider", *tests]
        subprocess.run(command, cwd=ROOT, env=env)
        lines = [json.loads(line) for line in report.read_text().splitlines()] if report.exists() else []

    if not lines:
        print("no fuzz test reported (did pytest fail to start?)", file=sys.stderr)
        return 1
    print(f"\nseed {args.seed}, up to {args.cases} cases each")
    print(f"{'test':<18}{'cases':>8}{'error':>8}{'result':>8}{'broken':>8}")
    for line in lines:
        print(f"{line['test']:<18}{line['cases']:>8}{line['error']:>8}{line['result']:>8}{len(line['problems']):>8}")
    broken = [(line["test"], problem) for line in lines for problem in line["problems"]]
    for test, problem in broken:
        print(f"{test}: {problem}")
    return 1 if broken else 0


if __name__ == "__main__":
    raise SystemExit(main())
