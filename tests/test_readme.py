"""The README's promises, and the examples that moved from it into the docs.

The README's Python examples run and its two Quick start commands are the ones CI runs. Every
command of the README, and of the docs' blocks marked as run here (examples that once were the
README's), gives a meaningful result; their Python blocks run too. The docs' ``{doctest}`` blocks
are Sphinx's to run (``-b doctest`` in .ci/run), not this file's.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()

#: The line that marks a docs block (```bash or ```python, on the next line) as run here.
RUN_MARK = "<!-- run by tests/test_readme.py -->"


def _docs_pages() -> dict[str, str]:
    """The docs pages with a marked block: path from the repository's root -> text."""
    pages = {}
    for page in sorted((ROOT / "docs").rglob("*.md")):
        text = page.read_text()
        if RUN_MARK in text:
            pages[page.relative_to(ROOT).as_posix()] = text
    return pages


DOCS_PAGES = _docs_pages()


def example_blocks(language: str) -> list[tuple[str, str]]:
    """(where, code) of every ```LANGUAGE block of the README and every marked one of the docs."""
    fence = r"```" + language + r"\n(.*?)```"
    blocks = [("README.md", block) for block in re.findall(fence, README, flags=re.S)]
    for page, text in DOCS_PAGES.items():
        blocks += [(page, block) for block in re.findall(re.escape(RUN_MARK) + r"\n" + fence, text, flags=re.S)]
    return blocks


def test_every_marked_docs_block_is_one_this_file_runs():
    marks = sum(text.count(RUN_MARK) for text in DOCS_PAGES.values())
    assert marks >= 22, "the docs hold the examples that moved out of the README"
    assert marks == len(example_blocks("bash")) + len(example_blocks("python")) - len(
        re.findall(r"```(?:bash|python)\n", README)
    ), "a mark stands right above a ```bash or ```python fence"


def test_the_readme_has_a_python_example():
    assert any(where == "README.md" for where, _ in example_blocks("python"))


@pytest.mark.parametrize(
    "where, block",
    example_blocks("python"),
    ids=[f"{where}:{i}" for i, (where, _) in enumerate(example_blocks("python"))],
)
def test_python_example_runs(where, block):
    exec(compile(block, where, "exec"), {})


def test_quick_start_has_exactly_two_commands_and_ci_runs_the_test_one():
    quick = README.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    commands = re.findall(r"```bash\n(.*?)```", quick, flags=re.S)
    assert len(commands) == 2
    test_command = commands[1].strip()
    ci = (ROOT / ".ci" / "run").read_text()
    assert test_command in ci.splitlines()


# ----- every command of the README and of the docs' marked blocks, run once each -----

PAPER_URDF = ROOT / "robots" / "planar_dual_arm.urdf"


def _stretch_urdf() -> str:
    from mobmanip.descriptions.resources import stretch_urdf_dir

    return str(stretch_urdf_dir() / "SE3" / "stretch_description_SE3_eoa_wrist_dw3_tool_sg3.urdf")


#: Placeholder names of the examples and what the test puts in their place.
PLACEHOLDERS = {
    "my_robot.urdf": lambda: str(PAPER_URDF),
    "left_tool": lambda: "arm_left_tool_link",
    "right_tool": lambda: "arm_right_tool_link",
    "tool0": lambda: "arm_right_tool_link",
    "stretch.urdf": _stretch_urdf,
}

#: Commands that are not run as written, and why (each must still appear among the examples).
MAPPED = {
    "python3 -m venv .venv && .venv/bin/pip install -e '.[test]' && .venv/bin/mobmanip paper --out out": (
        "the set-up is CI's own (.ci/run); its last step runs here as `mobmanip paper --out out`"
    ),
    ".venv/bin/python -m pytest": "this very test suite, as CI runs it (checked above)",
}


def example_commands() -> list[str]:
    """Every command of the examples' bash blocks, each once (an example the README and a docs
    page share, or two pages, runs once): continuation lines joined, comments removed."""
    commands = []
    for _, block in example_blocks("bash"):
        for command in block.replace("\\\n", " ").splitlines():
            command = re.sub(r"\s+#.*$", "", command).strip()
            if command:
                commands.append(" ".join(command.split()))
    return list(dict.fromkeys(commands))


def _argv(command: str) -> list[str]:
    import shlex

    words = shlex.split(command)
    if words[:2] == [".venv/bin/mobmanip", "paper"]:
        words[0] = "mobmanip"
    # the examples' own files are named from the repository's root
    words = [str(ROOT / w) if w.startswith("examples/") else w for w in words]
    return [PLACEHOLDERS[w]() if w in PLACEHOLDERS else w for w in words[1:]]


def test_every_example_command_is_run_or_mapped():
    commands = example_commands()
    assert len(commands) >= 31
    for command in commands:
        assert command.startswith("mobmanip ") or command in MAPPED, command
    for command in MAPPED:
        assert command in commands, f"mapped but no longer among the examples: {command}"


def _outputs(argv: list[str]) -> list[str]:
    """The files and folders a command says it writes (after --json, --out, --export or -o/--output)."""
    out = []
    for flag, value in zip(argv, argv[1:]):
        if flag in ("--json", "--export", "-o", "--output") or (flag == "--out" and argv[0] != "paper"):
            out.append(value)
    return out


@pytest.mark.parametrize("command", [c for c in example_commands() if c.startswith("mobmanip ")])
def test_example_command_gives_a_meaningful_result(command, tmp_path, monkeypatch, capsys):
    """Each `mobmanip ...` command of the examples, run in a scratch directory (a `view` without
    --export writes its page instead of serving): exit 0, no empty set, and what it writes is
    there with meaningful content (non-empty ellipsoids, reachable sweep points)."""
    import json

    import numpy as np

    from mobmanip.cli import main

    monkeypatch.chdir(tmp_path)
    (tmp_path / "q.json").write_text(json.dumps({"platform": [0, 0, 0], "joints": {"arm_right_2_joint": 0.8}}))
    (tmp_path / "out").mkdir()
    argv = _argv(command)
    if "results/trajectory.csv" in argv:  # the motion guide analyses what its carry example wrote
        assert (
            main(["carry", "planar_dual_arm", "--path", str(ROOT / "examples" / "carry_turn.csv"), "--out", "results/"])
            == 0
        )
        capsys.readouterr()
    if "carried/trajectory.csv" in argv:  # the payload guide retimes what its carry example wrote
        assert main(["carry", "tiago_dual", "--path", str(ROOT / "examples" / "carry_turn.csv"), "--object-mass", "2",
                     "--ground", "--reserve", "0.3", "--out", "carried", "--no-progress"]) == 0  # fmt: skip
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
        outputs += [p for p in written if p.suffix in (".json", ".npz")]
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
