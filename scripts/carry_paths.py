"""Write the object paths of ``mobmanip carry``'s examples: 2 m along a straight line and 2 m along
a quarter circle to the left, each with a smooth start and stop (quintic time law), 12 s.

Run: ``python scripts/carry_paths.py`` (writes examples/carry_line.csv and examples/carry_turn.csv).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

LENGTH = 2.0  # m
DURATION = 12.0  # s
STEP = 0.1  # s


def arc_length(t: np.ndarray) -> np.ndarray:
    """Distance along the path at times t: a quintic from rest to rest (m)."""
    s = t / DURATION
    return LENGTH * (10 * s**3 - 15 * s**4 + 6 * s**5)


def main() -> None:
    out = Path(__file__).resolve().parents[1] / "examples"
    out.mkdir(exist_ok=True)
    t = np.round(np.arange(0.0, DURATION + STEP / 2, STEP), 10)
    s = arc_length(t)
    radius = LENGTH / (math.pi / 2)
    paths = {
        "carry_line.csv": np.column_stack([t, s, np.zeros_like(s)]),
        "carry_turn.csv": np.column_stack([t, radius * np.sin(s / radius), radius * (1 - np.cos(s / radius))]),
    }
    for name, rows in paths.items():
        lines = ["t,x,y"] + [f"{a:.2f},{b:.9f},{c:.9f}" for a, b, c in rows]
        (out / name).write_text("\n".join(lines) + "\n")
        print(f"wrote {out / name}")


if __name__ == "__main__":
    main()
