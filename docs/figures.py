"""The documentation's pictures, made by the project's own commands when the docs are built.

Each entry of :data:`FIGURES` is a ``mobmanip`` command line as a how-to gives it, run in a scratch
folder, and the file it writes that the pages show; :data:`SCREENSHOTS` are exported viewer pages
photographed by headless Chromium. :func:`generate` writes them into ``docs/_generated/`` (never
committed: ``.gitignore``), again only when a source of the package, a robot or an example is newer
than the picture. ``docs/conf.py`` calls it when a build starts.

Run by hand: ``python docs/figures.py`` (``--force`` makes every picture again).
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = Path(__file__).resolve().parent / "_generated"
EXAMPLES = ROOT / "examples"

#: name in _generated -> (mobmanip arguments, the file the command writes, relative to its folder).
FIGURES: dict[str, tuple[list[str], str]] = {
    "fig3_kinematic.png": (["paper", "--out", "out"], "out/fig3_kinematic.png"),
    "fig4_dynamic.png": (["paper", "--out", "out"], "out/fig4_dynamic.png"),
    "sweep.png": (
        ["sweep", "planar_dual_arm", "--angle", "0:360:37", "--distance", "0.6:1.4:9", "--plot", "-o", "sweep"],
        "sweep/sweep.png",
    ),
    "floor_sweep.png": (
        [
            "sweep",
            "planar_dual_arm",
            "--angle",
            "0:360:13",
            "--measure",
            "dynamic_polytope",
            "--mu",
            "0.5",
            "-o",
            "grounded",
            "--plot",
        ],
        "grounded/sweep.png",
    ),  # fmt: skip
    "place_tiago_dual.png": (
        [
            "place",
            "tiago_dual",
            "--object",
            "2,1,0.9",
            "--mass",
            "3",
            "--objective",
            "dynamic:capacity:+z",
            "--figure",
            "place.png",
        ],
        "place.png",
    ),  # fmt: skip
    "site_planar.png": (["site", str(EXAMPLES / "site_planar.toml"), "-o", "site"], "site/site.png"),
    "carry_capacity.png": (
        ["carry", "planar_dual_arm", "--path", str(EXAMPLES / "carry_turn.csv"), "--out", "results"],
        "results/capacity.png",
    ),
    "team_beam.png": (
        ["team", str(EXAMPLES / "beam_team.toml"), "--polytope", "--json", "beam.json", "--plot", "beam.png"],
        "beam.png",
    ),
}

#: name in _generated -> the `mobmanip view` arguments whose exported page is photographed.
SCREENSHOTS: dict[str, list[str]] = {
    "view_tiago_dual.png": ["tiago_dual", "--posture", "hold", "--object-mass", "2", "--task", "translational"],
}

VIEWPORT = {"width": 1000, "height": 640}


def _newest_source() -> float:
    newest = 0.0
    for folder in (ROOT / "src" / "mobmanip", ROOT / "robots", EXAMPLES):
        for path in folder.rglob("*"):
            if path.is_file() and path.suffix in (".py", ".js", ".toml", ".urdf", ".csv", ".json"):
                newest = max(newest, path.stat().st_mtime)
    return newest


def _mobmanip(arguments: list[str], folder: Path) -> None:
    env = dict(
        os.environ, MPLBACKEND="Agg", PYTHONPATH=os.pathsep.join([str(ROOT / "src"), os.environ.get("PYTHONPATH", "")])
    )
    run = subprocess.run(
        [sys.executable, "-m", "mobmanip", *arguments], cwd=folder, env=env, capture_output=True, text=True
    )
    if run.returncode != 0:
        raise RuntimeError(f"docs figure: `mobmanip {' '.join(arguments)}` failed: {run.stderr.strip()[-2000:]}")


def chromium_path() -> str | None:
    """A Chromium (or Chrome) binary, from ``MOBMANIP_CHROMIUM`` or the PATH."""
    given = os.environ.get("MOBMANIP_CHROMIUM")
    if given:
        return given
    for name in ("chromium", "chromium-browser", "google-chrome", "google-chrome-stable"):
        found = shutil.which(name)
        if found:
            return found
    return None


def _photograph(page: Path, target: Path) -> str | None:
    """Screenshot of an exported viewer page once its scene has settled; the reason when it cannot."""
    binary = chromium_path()
    try:
        from playwright.sync_api import sync_playwright
    except ImportError:
        return "playwright is not installed"
    if binary is None:
        return "no Chromium found (set MOBMANIP_CHROMIUM)"
    state = """() => { let n = 0; viewer.scene.traverse(() => { n += 1; });
      return [n, viewer.num_messages_received, document.getElementById('mobmanip-legend') !== null]; }"""
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=binary, args=["--no-sandbox", "--disable-gpu"])
        try:
            tab = browser.new_page(viewport=VIEWPORT)
            tab.goto(page.as_uri())
            tab.wait_for_function("() => typeof viewer !== 'undefined' && viewer.scene !== undefined", timeout=60_000)
            last, since, start = None, time.monotonic(), time.monotonic()
            while time.monotonic() - start < 120:
                now_state = tab.evaluate(state)
                if now_state != last or not now_state[2]:
                    last, since = now_state, time.monotonic()
                elif time.monotonic() - since > 1.5:
                    break
                time.sleep(0.2)
            tab.wait_for_timeout(500)
            tab.screenshot(path=str(target))
        finally:
            browser.close()
    return None


def _placeholder(target: Path, reason: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(6, 1.2))
    fig.text(0.5, 0.5, f"viewer screenshot not made: {reason}", ha="center", va="center")
    fig.savefig(target, dpi=100)
    plt.close(fig)


def generate(force: bool = False, log=print) -> list[Path]:
    """Make the pictures that are missing or older than the sources; returns those made."""
    OUT.mkdir(exist_ok=True)
    newest = _newest_source()
    stale = lambda name: force or not (OUT / name).exists() or (OUT / name).stat().st_mtime < newest  # noqa: E731
    made: list[Path] = []
    with tempfile.TemporaryDirectory(prefix="mobmanip-docs-") as tmp:
        done: dict[tuple[str, ...], Path] = {}
        for name, (arguments, produced) in FIGURES.items():
            if not stale(name):
                continue
            key = tuple(arguments)
            if key not in done:  # one run for the figures of one command
                folder = Path(tmp) / f"run{len(done)}"
                folder.mkdir()
                log(f"docs figure: mobmanip {' '.join(arguments)}")
                _mobmanip(arguments, folder)
                done[key] = folder
            shutil.copyfile(done[key] / produced, OUT / name)
            made.append(OUT / name)
        for name, arguments in SCREENSHOTS.items():
            if not stale(name):
                continue
            folder = Path(tmp) / name
            folder.mkdir()
            log(f"docs figure: mobmanip view {' '.join(arguments)} --export, photographed in Chromium")
            _mobmanip(["view", *arguments, "--export", "page.html"], folder)
            reason = _photograph(folder / "page.html", OUT / name)
            if reason is not None:
                log(f"docs figure: {name}: {reason}; a placeholder instead")
                _placeholder(OUT / name, reason)
            made.append(OUT / name)
    return made


if __name__ == "__main__":
    for path in generate(force="--force" in sys.argv):
        print(f"wrote {path}")
