"""The documentation's equations render from a local build opened without internet (issue 28,
item 10): MathJax is bundled with the built site (``sphinx-mathjax-offline``), not loaded from a
CDN. A one-page site built with the project's own ``docs/conf.py`` is opened in Chromium with
every http(s) request refused, and its equations come out typeset."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import pytest

from browser_util import chromium, missing_browser

ROOT = Path(__file__).resolve().parents[1]
PAGE = """# Math

Inline $\\dot{x} = S(q)\\,\\eta$ and displayed:

$$
\\Lambda_o = Q^{-1} P J^{+} W^{T} + Q^{-1} J^{T} W^{+} M_o
$$

```{math}
\\left\\| Z \\left( \\Lambda_o a_o + \\mu_o \\right) \\right\\| \\le 1
```
"""


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    source = tmp_path_factory.mktemp("src")
    (source / "index.md").write_text(PAGE)
    out = tmp_path_factory.mktemp("html")
    run = subprocess.run(
        [sys.executable, "-m", "sphinx", "-q", "-b", "html", "-c", str(ROOT / "docs"), str(source), str(out)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert run.returncode == 0, run.stderr
    return out


def test_the_built_site_loads_mathjax_from_itself(site):
    html = (site / "index.html").read_text()
    scripts = re.findall(r'<script[^>]*\bsrc="([^"]+)"', html)
    assert not [s for s in scripts if re.match(r"(https?:)?//", s)], scripts
    (mathjax,) = [s for s in scripts if "mathjax" in s.lower()]
    assert (site / mathjax).is_file()
    assert (site / "_static" / "mathjax" / "output" / "chtml" / "fonts" / "woff-v2").is_dir()
    assert not re.search(r"https?://[^\"' ]*mathjax", html, re.I)


def test_equations_render_offline_in_a_browser(site):
    reason = missing_browser()
    if reason is not None:
        pytest.skip(f"needs Chromium and Playwright: {reason}")
    with chromium() as browser:
        page = browser.new_page()
        refused, failed = [], []
        page.route(re.compile(r"^https?://"), lambda route: (refused.append(route.request.url), route.abort()))
        page.on("requestfailed", lambda request: failed.append(request.url))
        page.goto((site / "index.html").as_uri())
        page.wait_for_function("() => document.querySelectorAll('mjx-container').length >= 3", timeout=30_000)
        page.wait_for_timeout(500)
        containers = page.evaluate(
            """() => Array.from(document.querySelectorAll('mjx-container')).map(
                   (e) => [e.getAttribute('display') === 'true', e.getBoundingClientRect().width])"""
        )
        text = page.evaluate("() => document.querySelector('article').innerText")
        assert sorted(d for d, _ in containers) == [False, True, True], containers
        assert all(width > 20 for _, width in containers), containers
        assert "\\Lambda" not in text and "\\dot" not in text  # no raw TeX left
        assert refused == [] and failed == [], (refused, failed)
