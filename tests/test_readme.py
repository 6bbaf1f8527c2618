"""The README's promises: its Python example runs, its two commands are the ones CI runs."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()


def test_python_example_runs():
    blocks = re.findall(r"```python\n(.*?)```", README, flags=re.S)
    assert blocks, "the README has a Python example"
    for block in blocks:
        exec(compile(block, "README.md", "exec"), {})


def test_quick_start_has_exactly_two_commands_and_ci_runs_the_test_one():
    quick = README.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)```", quick, flags=re.S)
    assert len(commands) == 2
    test_command = commands[1].strip()
    ci = (ROOT / ".ci" / "run").read_text()
    assert test_command in ci.splitlines()


# ----- every command of the README, run -----

PAPER_URDF = ROOT / "robots" / "planar_dual_arm.urdf"


def _stretch_urdf() -> str:
    from mobmanip.descriptions.resources import stretch_urdf_dir

    return str(stretch_urdf_dir() / "SE3" / "stretch_description_SE3_eoa_wrist_dw3_tool_sg3.urdf")


#: Placeholder names of the README's examples and what the test puts in their place.
PLACEHOLDERS = {
    "my_robot.urdf": lambda: str(PAPER_URDF),
    "left_tool": lambda: "arm_left_tool_link",
    "right_tool": lambda: "arm_right_tool_link",
    "tool0": lambda: "arm_right_tool_link",
    "stretch.urdf": _stretch_urdf,
}

#: Commands that are not run as written, and why (each must still appear in the README).
MAPPED = {
    "python3 -m venv .venv && .venv/bin/pip install -e '.[test]' && .venv/bin/mobmanip paper --out out": (
        "the set-up is CI's own (.ci/run); its last step runs here as `mobmanip paper --out out`"
    ),
    ".venv/bin/python -m pytest": "this very test suite, as CI runs it (checked above)",
}


def readme_commands() -> list[str]:
    """Every command of the README's bash blocks: continuation lines joined, comments removed."""
    commands = []
    for block in re.findall(r"```bash\n(.*?)```", README, flags=re.S):
        for command in block.replace("\\\n", " ").splitlines():
            command = re.sub(r"\s+#.*$", "", command).strip()
            if command:
                commands.append(" ".join(command.split()))
    return commands


def _argv(command: str) -> list[str]:
    import shlex

    words = shlex.split(command)
    if words[:2] == [".venv/bin/mobmanip", "paper"]:
        words[0] = "mobmanip"
    # the README's own example files are named from the repository's root
    words = [str(ROOT / w) if w.startswith("examples/") else w for w in words]
    return [PLACEHOLDERS[w]() if w in PLACEHOLDERS else w for w in words[1:]]


def test_every_readme_command_is_run_or_mapped():
    commands = readme_commands()
    assert len(commands) >= 15
    for command in commands:
        assert command.startswith("mobmanip ") or command in MAPPED, command
    for command in MAPPED:
        assert command in commands, f"mapped but no longer in the README: {command}"


def _outputs(argv: list[str]) -> list[str]:
    """The files a command says it writes (after --json, --out, --export, or -o/--output PREFIX)."""
    out = []
    for flag, value in zip(argv, argv[1:]):
        if flag in ("--json", "--export") or (flag == "--out" and argv[0] != "paper"):
            out.append(value)
        elif flag in ("-o", "--output"):
            out.append(value + ".npz")
    return out


@pytest.mark.parametrize("command", [c for c in readme_commands() if c.startswith("mobmanip ")])
def test_readme_command_gives_a_meaningful_result(command, tmp_path, monkeypatch, capsys):
    """Each `mobmanip ...` command of the README, run in a scratch directory (a `view` without
    --export writes its page instead of serving): exit 0, no empty set, and what it writes is
    there with meaningful content (non-empty ellipsoids, reachable sweep points)."""
    import json

    import numpy as np

    from mobmanip.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "q.json").write_text(json.dumps({"platform": [0, 0, 0], "joints": {"arm_right_2_joint": 0.8}}))
    (tmp_path / "out").mkdir()
    argv = _argv(command)
    if "results/trajectory.csv" in argv:  # the README analyses what its carry example wrote
        assert (
            main(["carry", "planar_dual_arm", "--path", str(ROOT / "examples" / "carry_turn.csv"), "--out", "results/"])
            == 0
        )
        capsys.readouterr()
    if argv[0] == "view" and "--export" not in argv:
        argv += ["--export", "view.html"]
    if argv[0] == "paper":
        argv = ["paper", "--out", "out"]
    code = main(argv)
    printed = capsys.readouterr()
    assert code == 0, printed.err
    assert printed.out.strip()
    assert "EMPTY" not in printed.out  # every example shows a set that exists
    outputs = [tmp_path / name for name in _outputs(argv)]
    for directory in [p for p in outputs if p.is_dir()]:  # an --out DIR: what it holds instead
        written = sorted(directory.iterdir())
        assert written and all(p.stat().st_size > 0 for p in written), directory
        outputs += [p for p in written if p.suffix == ".json"]
    for path in [p for p in outputs if not p.is_dir()]:
        assert path.is_file() and path.stat().st_size > 0, path.name
        if path.suffix == ".json":
            document = json.loads(path.read_text())
            document = document.get("analysis", document)
            for key in ("kinematic_ellipsoid", "dynamic_ellipsoid"):
                if key in document:
                    assert document[key]["empty"] is False and min(document[key]["semi_axes"]) > 0.0
        elif path.suffix == ".npz":
            with np.load(path) as data:
                assert data["reachable"].any()
                volumes = [data[k] for k in data.files if k.endswith("volume")]
                assert volumes and all(np.isfinite(v[data["reachable"]]).all() for v in volumes if v.shape)
        elif path.suffix == ".html":
            assert path.stat().st_size > 10_000
    if argv[0] == "paper":
        for figure in ("fig3_kinematic.png", "fig4_dynamic.png", "case_study.json"):
            assert (tmp_path / "out" / figure).stat().st_size > 0
