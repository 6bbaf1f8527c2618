"""The package's architecture, held: layers that import only downwards, no import circles, and no
private name taken from another subpackage (tests and scripts included).

The layer order is written once, in :data:`LAYERS`, bottom to top. A module's layer is that of its
subpackage (``mobmanip.sets.hull`` is in ``sets``) or, for the few top-level modules, its own
name. An import may go to the importer's own layer only inside the same subpackage: two
subpackages on one level (``sweep``, ``team``, ``motion``) do not import each other. Imports
are read from the source, at module level and inside functions alike (``TYPE_CHECKING`` imports
included: an annotation is a dependency too).
"""

from __future__ import annotations

import ast
from collections.abc import Iterable, Mapping
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "mobmanip"

#: Bottom to top; one tuple per level. Names are subpackages or top-level modules of mobmanip.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("errors", "old_paths"),
    ("support",),
    ("sets",),
    ("descriptions",),
    ("platforms",),
    ("robot",),
    ("postures",),
    ("terms",),
    ("engine",),
    ("batch",),  # the engine's public face, kept under its old name
    ("measures",),
    ("gradients",),
    ("analysis",),
    ("sweep", "team", "motion", "casestudy", "referee"),  # referee: MuJoCo replays the grounded sets
    ("coordination",),  # teams that move: the team's terms with carry's machinery
    ("placement",),
    ("viz",),
    ("commands",),
    ("cli",),
    ("__main__",),
    ("",),  # the package itself: its public API re-exports every layer
)
LEVEL = {name: k for k, names in enumerate(LAYERS) for name in names}


def module_name(path: Path, package: Path = PACKAGE) -> str:
    parts = list(path.relative_to(package.parent).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def group(module: str) -> str:
    """The layer entry a module belongs to: its subpackage, or itself at the top level."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else ""


def imports_of(path: Path, module: str, known: set[str]) -> Iterable[tuple[str, str | None, int]]:
    """(imported module, imported name or None, line) for each mobmanip import in a file."""
    is_package = path.name == "__init__.py"
    for node in ast.walk(ast.parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.split(".")[0] == "mobmanip":
                    yield alias.name, None, node.lineno
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                if not is_package:
                    base = base[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join(base + ([node.module] if node.module else []))
            else:
                target = node.module or ""
            if target.split(".")[0] != "mobmanip":
                continue
            for alias in node.names:
                full = f"{target}.{alias.name}"
                if full in known:  # `from . import module`
                    yield full, None, node.lineno
                else:
                    yield target, alias.name, node.lineno


def package_graph(package: Path = PACKAGE) -> tuple[dict[str, set[str]], list[tuple[str, str, str, int]]]:
    """The import graph of the package's modules, and every imported name as (importer, module,
    name, line)."""
    files = {module_name(p, package): p for p in package.rglob("*.py")}
    known = set(files)
    graph: dict[str, set[str]] = {m: set() for m in files}
    names = []
    for module, path in files.items():
        for target, name, line in imports_of(path, module, known):
            while target not in known and "." in target:
                target = target.rsplit(".", 1)[0]
            if target != module:
                graph[module].add(target)
            if name is not None:
                names.append((module, target, name, line))
    return graph, names


def layer_violations(graph: Mapping[str, set[str]]) -> list[str]:
    out = []
    for importer, targets in sorted(graph.items()):
        a = group(importer)
        for target in sorted(targets):
            b = group(target)
            if a == b:
                continue
            if a not in LEVEL or b not in LEVEL:
                out.append(f"{importer} -> {target}: {a or b!r} has no place in LAYERS")
            elif LEVEL[b] > LEVEL[a]:
                out.append(f"{importer} -> {target}: imports upwards ({b} is above {a})")
            elif LEVEL[b] == LEVEL[a]:
                out.append(f"{importer} -> {target}: {a} and {b} share a level and must not import each other")
    return out


def circles(graph: Mapping[str, set[str]]) -> list[list[str]]:
    """The strongly connected components with more than one module (Tarjan), each sorted. A
    package's ``__init__`` re-exporting its submodules is not a circle by itself: only edges that
    do not run from a package to its own submodule are followed back up."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    found: list[list[str]] = []
    counter = [0]

    def strong(v: str) -> None:
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                strong(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            strong(v)
    return found


def private_crossings(names: Iterable[tuple[str, str, str, int]]) -> list[str]:
    out = []
    for importer, target, name, line in names:
        private = name.startswith("_") and not name.startswith("__")
        if private and group(importer) != group(target):
            out.append(f"{importer} line {line} takes the private {name} of {target}")
    return out


def test_layers_import_only_downwards():
    graph, _ = package_graph()
    assert layer_violations(graph) == []


def test_no_import_circles():
    graph, _ = package_graph()
    assert circles(graph) == []


def test_every_subpackage_has_a_layer():
    graph, _ = package_graph()
    assert sorted({group(m) for m in graph} - set(LEVEL)) == []


def test_no_private_name_crosses_a_subpackage():
    _, names = package_graph()
    assert private_crossings(names) == []


@pytest.mark.parametrize("folder", ["tests", "scripts"])
def test_tests_and_scripts_use_public_names_only(folder):
    found = []
    for path in sorted((ROOT / folder).glob("*.py")):
        for target, name, line in imports_of(path, path.stem, set()):
            if any(part.startswith("_") and not part.startswith("__") for part in target.split(".")):
                found.append(f"{path.name} line {line} imports the private module {target}")
            elif name is not None and name.startswith("_") and not name.startswith("__"):
                found.append(f"{path.name} line {line} takes the private {name} of {target}")
    assert found == []


# ------------------------------------------------------------------------------------------------
# the checks themselves fail for what they name


def _package_with(tmp_path: Path, module: str, addition: str) -> Path:
    """A copy of the package with ``addition`` appended to its ``module`` (a path inside it)."""
    import shutil

    target = tmp_path / "mobmanip"
    shutil.copytree(PACKAGE, target, ignore=shutil.ignore_patterns("__pycache__", "*.js", "*.typed"))
    path = target / module
    path.write_text(path.read_text() + addition)
    return target


def test_an_upward_import_is_caught(tmp_path):
    package = _package_with(
        tmp_path, "sets/hull.py", "\n\ndef _late():\n    from ..analysis import analyze\n\n    return analyze\n"
    )
    graph, _ = package_graph(package)
    found = layer_violations(graph)
    print("\n".join(found))
    assert found == ["mobmanip.sets.hull -> mobmanip.analysis: imports upwards (analysis is above sets)"]


def test_a_circle_is_caught(tmp_path):
    package = _package_with(
        tmp_path, "robot/tasks.py", "\n\ndef _late():\n    from .spec import load_spec\n\n    return load_spec\n"
    )
    graph, _ = package_graph(package)
    found = circles(graph)
    print(found)
    assert found == [["mobmanip.robot.spec", "mobmanip.robot.tasks"]]


def test_a_private_crossing_is_caught(tmp_path):
    package = _package_with(tmp_path, "sweep/runner.py", "\n\nfrom ..robot.model import _build_model  # noqa: E402\n")
    _, names = package_graph(package)
    assert any("takes the private _build_model of mobmanip.robot.model" in m for m in private_crossings(names))
