"""One home for errors: every exception mobmanip defines lives in ``mobmanip.errors`` under
``MobmanipError``, and library code raises neither the command line's ``UsageError`` nor bare
built-in exceptions for bad input."""

from __future__ import annotations

import ast
import inspect
from pathlib import Path

import mobmanip
import mobmanip.errors

PACKAGE = Path(mobmanip.__file__).resolve().parent
COMMAND_LINE = {PACKAGE / "cli.py", *(PACKAGE / "commands").glob("*.py")}
BUILTINS = {"ValueError", "TypeError", "RuntimeError", "KeyError", "IndexError", "Exception"}


def _sources():
    return sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


#: Not errors but signals: classes derived from BaseException to pass through a library's own
#: ``except Exception`` (xacro wraps every Exception it meets) and caught in the same module, where
#: they become one of ``mobmanip.errors``'. Each named with its module.
SIGNALS = {"descriptions/xacro.py _Refused"}


def test_every_exception_class_is_defined_in_the_errors_module():
    outside = []
    for path in _sources():
        if path == PACKAGE / "errors.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ClassDef):
                bases = {getattr(b, "id", getattr(b, "attr", "")) for b in node.bases}
                where = f"{path.relative_to(PACKAGE)} {node.name}"
                if bases == {"BaseException"} and where in SIGNALS:
                    continue
                if any(b.endswith(("Error", "Exception")) for b in bases):
                    outside.append(f"{path.relative_to(PACKAGE)}:{node.lineno} {node.name}")
    assert outside == []


def test_every_error_derives_from_mobmanip_error():
    classes = [c for _, c in inspect.getmembers(mobmanip.errors, inspect.isclass) if issubclass(c, BaseException)]
    assert len(classes) > 15
    assert all(issubclass(c, mobmanip.errors.MobmanipError) for c in classes)


def test_library_code_raises_neither_usage_errors_nor_bare_builtins():
    found = []
    for path in _sources():
        if path in COMMAND_LINE:
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Raise) and isinstance(node.exc, ast.Call):
                name = getattr(node.exc.func, "id", getattr(node.exc.func, "attr", ""))
                if name == "UsageError" or name in BUILTINS:
                    found.append(f"{path.relative_to(PACKAGE)}:{node.lineno} raise {name}")
    assert found == []
