#!/usr/bin/env bash
# The wheel on its own: build the wheel and the sdist, install the wheel into a fresh virtual
# environment OUTSIDE the source tree and run the README's main command, `analyze` on every
# built-in robot and a short `view --export` there; the sdist is checked to hold the robots (the
# wheel is built from it). Fails on the first error.
#
# Usage: scripts/check_wheel.sh [PYTHON]   (default python3; needs the `build` package or
# installs it into a throw-away environment)
set -euo pipefail
src="$(cd "$(dirname "$0")/.." && pwd)"
python="${1:-python3}"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
step() { printf '\n== %s (%ds)\n' "$1" "$SECONDS"; }
# pip, quiet, without the notes some machines' configurations print for every package
pipq() { "$@" --quiet 2> >(grep -v '^WARNING: Location' >&2); }

step "build the sdist and the wheel (the wheel from the sdist)"
"$python" -m venv "$work/build-env"
pipq "$work/build-env/bin/pip" install --upgrade pip build
"$work/build-env/bin/python" -m build --outdir "$work/dist" "$src" >"$work/build.log" 2>&1 || {
    cat "$work/build.log"
    exit 1
}
wheel="$(ls "$work"/dist/mobmanip-*.whl)"
sdist="$(ls "$work"/dist/mobmanip-*.tar.gz)"
ls -l "$work/dist"

step "the wheel carries the built-in robots, the type marker and no tests"
"$work/build-env/bin/python" - "$wheel" <<'PY'
import sys, zipfile
names = set(zipfile.ZipFile(sys.argv[1]).namelist())
for needed in ("mobmanip/py.typed", "mobmanip/robots/planar_dual_arm.urdf", "mobmanip/robots/planar_dual_arm.toml"):
    assert needed in names, f"{needed} is missing from the wheel"
assert not any(n.startswith("tests/") for n in names), "tests are in the wheel"
print(len(names), "files; robots:", sorted(n.split("/")[-1] for n in names if n.startswith("mobmanip/robots/")))
PY

step "install the wheel into a fresh environment"
"$python" -m venv "$work/wheel-env"
pipq "$work/wheel-env/bin/pip" install --upgrade pip
pipq "$work/wheel-env/bin/pip" install "$wheel"

run="$work/run"
mkdir -p "$run"
cd "$run"  # outside the source tree: nothing can come from it
bin="$work/wheel-env/bin"
"$bin/python" - "$src" <<'PY'
import sys
from pathlib import Path
import mobmanip
from mobmanip.descriptions.resources import builtin_robots_dir
source = Path(sys.argv[1]).resolve()
for path in (Path(mobmanip.__file__), builtin_robots_dir()):
    assert source not in path.resolve().parents, f"{path} comes from the source tree"
print("mobmanip", mobmanip.__version__, "from", Path(mobmanip.__file__).parent)
PY
"$bin/mobmanip" --version
"$bin/python" -m mobmanip --version

step "mobmanip paper (the README's main command)"
"$bin/mobmanip" paper --out paper
for f in case_study.json fig3_kinematic.png fig4_dynamic.png fig4_dynamic_coupled.png \
    fig3_kinematic_polytopes.png fig4_dynamic_polytopes.png; do
    test -s "paper/$f" || { echo "paper/$f was not written"; exit 1; }
done

step "mobmanip analyze on every built-in robot"
robots="$("$bin/python" -c 'from mobmanip.descriptions.resources import builtin_robot_names; print(" ".join(builtin_robot_names()))')"
test -n "$robots"
for robot in $robots; do
    "$bin/mobmanip" analyze "$robot" --json "analyze_$robot.json" >/dev/null
    "$bin/python" -c "import json, sys; d = json.load(open(sys.argv[1])); assert d['robot'] == sys.argv[2], d['robot']; print(sys.argv[2], 'ok:', d['platform'], d['task'])" "analyze_$robot.json" "$robot"
done

step "a short view --export"
"$bin/mobmanip" view planar_dual_arm --sweep object-angle --export scene.html
grep -q "<html" scene.html || grep -qi "<!doctype html" scene.html
test "$(stat -c %s scene.html)" -gt 100000  # the scene and meshcat's viewer are inside the page

# The sdist is not installed again: `python -m build` made the wheel from the sdist (above), so
# the wheel just run holds what the sdist holds (installing it too cost 34 s of every CI run).
step "the sdist holds the built-in robots"
"$work/build-env/bin/python" - "$sdist" <<'PY'
import sys, tarfile
names = tarfile.open(sys.argv[1]).getnames()
for needed in ("src/mobmanip/py.typed", "robots/planar_dual_arm.urdf"):
    assert any(n.endswith(needed) for n in names), f"{needed} is missing from the sdist"
print(len(names), "files in the sdist")
PY

step "done"
