"""Write the tie deck ``tie_grid.inp``; with ``--ccx``, run ccx 2.20 on it for ``tie_grid.cel``.

A 4 x 4 C3D8 master block (spacing 1, top face at z = 0) under a 4 x 4 C3D8 slave block whose
bottom nodes (spacing 0.5) lie exactly above the master's nodes, edge midpoints and face centres:
21 slave nodes are equidistant from triangle centroids of two master faces. The whole deck is
shifted by (100.3, 7.1, -3.7), so that CalculiX's floating-point centroid distances decide every
one of these ties (docs/method.md §3.6), here unlike the position order. The slave top is pushed
down by 1e-3; LINEAR law K = 1e7, sigma_inf = 3; contact elements written to ``tie_grid.cel``.
``tie_grid_rotated.inp`` is the same deck turned by 0.65 rad about (-0.5, 0.08, -2.0) and shifted
by (41.2, 82.4, 51.6): no tie is exact in floating point there either, and adding the corners of
the sub-triangles in another order would give 6 or 8 of its 21 ties another face than ccx.

    python tests/data/calculix/ties/make_tie_deck.py [--ccx]
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
DECKS = {  # name: (rotation axis, angle, shift)
    "tie_grid": ((0.0, 0.0, 1.0), 0.0, (100.3, 7.1, -3.7)),
    "tie_grid_rotated": ((-0.5, 0.08, -2.0), 0.65, (41.2, 82.4, 51.6)),
}


def _rotation(axis: tuple[float, float, float], angle: float) -> np.ndarray:
    """Rotation matrix by ``angle`` about ``axis`` (Rodrigues)."""
    a = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    k = np.array([[0.0, -a[2], a[1]], [a[2], 0.0, -a[0]], [-a[1], a[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * k @ k


def _grid(lo: float, hi: float, n: int, z: tuple[float, float], first: int) -> tuple:
    """Nodes (number -> coordinates) and C3D8 connectivity of an n x n x 1 block."""
    t = np.linspace(lo, hi, n + 1)
    number = {}
    coords = []
    for k, zk in enumerate(z):
        for j in range(n + 1):
            for i in range(n + 1):
                number[i, j, k] = first + len(coords)
                coords.append((t[i], t[j], zk))
    cells = [
        [number[i + a, j + b, k] for k in (0, 1) for a, b in ((0, 0), (1, 0), (1, 1), (0, 1))]
        for j in range(n)
        for i in range(n)
    ]
    return number, np.array(coords), cells


def deck_text(name: str = "tie_grid") -> str:
    """The deck ``name`` of `DECKS` (see the module docstring)."""
    axis, angle, shift = DECKS[name]
    rotation = _rotation(axis, angle)
    master, xm, mcells = _grid(0.0, 4.0, 4, (-1.0, 0.0), 1)
    slave, xs, scells = _grid(1.0, 3.0, 4, (0.0, 1.0), 1 + xm.shape[0])
    x = np.vstack([xm, xs]) @ rotation.T + np.asarray(shift)
    x[np.abs(x) < 1e-12] = 0.0
    push = rotation @ np.array([0.0, 0.0, -1e-3])
    push[np.abs(push) < 1e-15] = 0.0
    lines = ["*HEADING", f"{name}: make_tie_deck.py (docs/method.md 3.6)", "*NODE, NSET=NALL"]
    for k, xk in enumerate(x, start=1):
        lines.append(f"{k}, {xk[0]:.17g}, {xk[1]:.17g}, {xk[2]:.17g}")
    lines.append("*ELEMENT, TYPE=C3D8, ELSET=EALL")
    for e, cell in enumerate(mcells + scells, start=1):
        lines.append(f"{e}, " + ", ".join(map(str, cell)))
    lines += ["*NSET, NSET=BASE", *(f"{v}," for (i, j, k), v in master.items() if k == 0)]
    lines += ["*NSET, NSET=TOP", *(f"{v}," for (i, j, k), v in slave.items() if k == 1)]
    lines += [
        "*MATERIAL, NAME=STEEL", "*ELASTIC", "210000., 0.3",
        "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL",
        "*SURFACE, NAME=MASTER", *(f"{e}, S2" for e in range(1, len(mcells) + 1)),
        "*SURFACE, NAME=SLAVE",
        *(f"{e}, S1" for e in range(len(mcells) + 1, len(mcells) + len(scells) + 1)),
        "*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE", "SLAVE, MASTER",
        "*SURFACE INTERACTION, NAME=SI", "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
        "1.0e7, 3.0", "*STEP", "*STATIC", "1.0, 1.0", "*BOUNDARY", "BASE, 1, 3",
        *(f"TOP, {i + 1}, {i + 1}, {push[i]:.12e}" for i in range(3)),  # ccx: <= 20 characters
        "*NODE FILE, CONTACT ELEMENTS", "U", "*END STEP",
    ]  # fmt: skip
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    for job in DECKS:
        (HERE / f"{job}.inp").write_text(deck_text(job))
        if "--ccx" in sys.argv[1:]:
            subprocess.run(["ccx", "-i", job], cwd=HERE, check=True, capture_output=True)
            for suffix in ("dat", "frd", "sta", "cvg", "12d"):
                (HERE / f"{job}.{suffix}").unlink(missing_ok=True)
    (HERE / "spooles.out").unlink(missing_ok=True)
