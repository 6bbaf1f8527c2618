"""The module paths and names from before the layers still work for one release, each with a
DeprecationWarning that names where it lives now (the CHANGELOG's table)."""

from __future__ import annotations

import importlib
import sys

import pytest

import mobmanip  # noqa: F401  # installs the finder of the old paths
from mobmanip.old_paths import MOVED


@pytest.mark.parametrize("old", sorted(MOVED))
def test_an_old_module_path_imports_with_a_warning_naming_the_new_one(old):
    sys.modules.pop(old, None)
    with pytest.warns(DeprecationWarning, match=MOVED[old][0].replace(".", r"\.")):
        module = importlib.import_module(old)
    targets = [importlib.import_module(t) for t in MOVED[old]]
    if len(targets) == 1:
        assert module is targets[0]
    else:  # a module that was split: the names of all its successors
        for target in targets:
            public = [n for n in vars(target) if not n.startswith("_")]
            assert public and all(getattr(module, n) is getattr(target, n) for n in public)


def test_the_old_sweep_module_names_resolve_with_a_warning():
    import mobmanip.sweep as sweep
    from mobmanip.errors import GridError
    from mobmanip.postures.planar import planar_arm
    from mobmanip.sweep.results import AXES, index_names

    for name, where, value in (
        ("AXES", "mobmanip.sweep.results", AXES),
        ("index_names", "mobmanip.sweep.results", index_names),
        ("planar_arm", "mobmanip.postures.planar", planar_arm),
        ("GridError", "mobmanip.errors", GridError),
    ):
        with pytest.warns(DeprecationWarning, match=rf"mobmanip\.sweep\.{name} moved to {where}\.{name}"):
            assert getattr(sweep, name) is value
    with pytest.raises(AttributeError, match=r"mobmanip\.viz\.sweep_plot\.plot_sweep"):
        sweep.plot_sweep  # noqa: B018
    with pytest.raises(AttributeError, match="no attribute 'not_a_name'"):
        sweep.not_a_name  # noqa: B018


def test_an_old_module_path_reached_as_an_attribute_gives_its_names_with_a_warning():
    """``mobmanip.grasp.HeldObject`` worked in the last release without importing the submodule."""
    code = (
        "import warnings; warnings.simplefilter('error', DeprecationWarning)\n"
        "import mobmanip\n"
        "from mobmanip.terms.grasp import HeldObject\n"
        "try:\n"
        "    mobmanip.grasp\n"
        "except DeprecationWarning as exc:\n"
        "    print('warned:', exc)\n"
        "warnings.simplefilter('ignore', DeprecationWarning)\n"
        "print(mobmanip.grasp.HeldObject is HeldObject, mobmanip.io.read_configuration is not None)\n"
    )
    import subprocess

    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("warned: mobmanip.grasp moved to mobmanip.terms.grasp")
    assert lines[1] == "True True"
    with pytest.raises(AttributeError, match="no attribute 'not_a_module'"):
        mobmanip.not_a_module  # noqa: B018
