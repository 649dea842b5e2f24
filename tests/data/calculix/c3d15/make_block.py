"""Write the C3D15 blocks ``wedge_block*.inp`` of docs/method.md §34.

A 2 x 2 x 2 grid of hexahedra on [0, 2] x [0, 1] x [0, 1], each split into two wedges along a
diagonal, with all midside nodes moved off the straight edges (curved edges: the geometric map
is C3D15's, not an affine one) and the top nodes loaded unevenly; the bottom is clamped.
``wedge_block_pressure*.inp`` add pressures on the curved top triangles and the curved
quadrilaterals at x = 2, one value per element (NLGEOM: 5 times the values, and tight
``*CONTROLS`` so that both codes converge to round-off); ``wedge_block_frd.inp`` is the NLGEOM
block with ``*EL PRINT`` and ``*EL FILE`` S, E, ME and ENER. Run:
``python make_block.py`` (deterministic: no random numbers).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

NX, NY, NZ = 2, 2, 2
LX, LY, LZ = 2.0, 1.0, 1.0


def _grid() -> tuple[dict, list]:
    coords: dict[tuple, int] = {}
    points: list[np.ndarray] = []

    def node(p: np.ndarray) -> int:
        key = tuple(np.round(p, 9))
        if key not in coords:
            coords[key] = len(points) + 1
            points.append(p)
        return coords[key]

    wedges = []
    h = np.array([LX / NX, LY / NY, LZ / NZ])
    for k in range(NZ):
        for j in range(NY):
            for i in range(NX):
                o = np.array([i, j, k]) * h
                c = [o + np.array([a, b, 0.0]) * h for a, b in ((0, 0), (1, 0), (1, 1), (0, 1))]
                up = np.array([0.0, 0.0, h[2]])
                for tri in ((0, 1, 2), (0, 2, 3)) if (i + j) % 2 == 0 else ((0, 1, 3), (1, 2, 3)):
                    bottom = [c[t] for t in tri]
                    top = [p + up for p in bottom]
                    corners = bottom + top
                    edges = [(0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5)]
                    nodes = [node(p) for p in corners]
                    for a, b in edges:
                        mid = (corners[a] + corners[b]) / 2
                        # curved edges: a smooth displacement of the midside nodes
                        mid = mid + 0.03 * np.array(
                            [
                                np.sin(2 * mid[1] + mid[2]),
                                np.cos(mid[0] + 3 * mid[2]),
                                np.sin(mid[0] * mid[1]),
                            ]
                        )
                        nodes.append(node(mid))
                    wedges.append(nodes)
    return points, wedges


#: ccx's C3D15 faces by their corners (manual): S1 1-2-3, S2 4-5-6, S3 1-2-5-4, S4 2-3-6-5,
#: S5 3-1-4-6 (0-based).
FACES = ((0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5))


def _pressure_lines(x: np.ndarray, wedges: list, scale: float) -> list[str]:
    """``*DLOAD`` on the top triangles (z = LZ) and the quadrilaterals at x = LX (curved faces)."""
    lines = ["*DLOAD"]
    for e, w in enumerate(wedges):
        for f, corners in enumerate(FACES):
            p = x[[w[c] - 1 for c in corners]]
            top = np.allclose(p[:, 2], LZ)
            side = np.allclose(p[:, 0], LX)
            if top or side:
                value = ((10.0 if top else 40.0) + e) * scale
                lines.append(f"{e + 1}, P{f + 1}, {value:.12g}")
    return lines


def write(path: Path, nlgeom: bool, pressure: bool = False, frd: bool = False) -> None:
    points, wedges = _grid()
    x = np.array(points)
    lines = ["*HEADING", "C3D15 block, curved edges, uneven top load (dolfinx_ntf method §34)"]
    lines.append("*NODE, NSET=NALL")
    lines += [f"{n + 1}, {p[0]:.12g}, {p[1]:.12g}, {p[2]:.12g}" for n, p in enumerate(x)]
    lines.append("*ELEMENT, TYPE=C3D15, ELSET=EALL")
    for e, w in enumerate(wedges):
        lines.append(f"{e + 1}, " + ", ".join(map(str, w[:10])) + ",")
        lines.append(", ".join(map(str, w[10:])))
    bottom = np.flatnonzero(np.isclose(x[:, 2], 0.0)) + 1
    top = np.flatnonzero(np.isclose(x[:, 2], LZ)) + 1
    lines.append("*NSET, NSET=BOTTOM")
    lines += [", ".join(map(str, bottom[i : i + 8])) for i in range(0, bottom.size, 8)]
    lines += ["*MATERIAL, NAME=STEEL", "*ELASTIC", "210000., 0.3"]
    lines += ["*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL"]
    lines.append("*STEP" + (", NLGEOM" if nlgeom else ""))
    lines += ["*STATIC", "0.25, 1.0" if nlgeom else ""]
    if nlgeom and pressure:  # both codes to round-off (the default stops at 0.5 %)
        lines += ["*CONTROLS, PARAMETERS=FIELD", "1e-10, 1e-08, , , 1e-10, 1e-05, 1e-08, 1e-12"]
    lines += ["*BOUNDARY", "BOTTOM, 1, 3"]
    lines.append("*CLOAD")
    scale = 500.0 if nlgeom else 100.0
    for n in top:
        p = x[n - 1]
        lines.append(f"{n}, 1, {scale * (0.5 + p[1]):.12g}")
        lines.append(f"{n}, 2, {scale * 0.3 * p[0]:.12g}")
        lines.append(f"{n}, 3, {-scale * (1.0 + p[0] * p[1]):.12g}")
    if pressure:
        lines += _pressure_lines(x, wedges, 5.0 if nlgeom else 1.0)
    prints = "S, E, ME, ENER" if frd else ("S, E" if nlgeom else "S")
    if frd:
        lines += ["*EL FILE", "S, E, ME, ENER"]
    lines += [
        "*NODE PRINT, NSET=NALL",
        "U, RF",
        "*EL PRINT, ELSET=EALL",
        prints,
        "*END STEP",
    ]
    path.write_text("\n".join(line for line in lines if line != "") + "\n")


def write_dynamics(here: Path) -> None:
    """``wedge_block_dynamic.inp`` (*DYNAMIC), ``wedge_block_frequency.inp`` (*FREQUENCY, 6
    modes) and ``wedge_block_modal.inp`` (*MODAL DYNAMIC on them, Rayleigh damping): the
    small-strain block with a density (steel, N-mm-s)."""
    deck = (here / "wedge_block.inp").read_text()
    deck = deck.replace("210000., 0.3\n", "210000., 0.3\n*DENSITY\n7.8e-9\n")
    (here / "wedge_block_dynamic.inp").write_text(
        deck.replace("*STATIC\n", "*DYNAMIC\n1e-7, 5e-7\n")
    )
    model = deck.split("*STEP")[0]
    steps = "*BOUNDARY\nBOTTOM, 1, 3\n*STEP\n*FREQUENCY\n6\n*END STEP\n"
    (here / "wedge_block_frequency.inp").write_text(model + steps)
    loads = deck.split("*CLOAD\n")[1].split("*NODE PRINT")[0]
    steps = (
        "*BOUNDARY\nBOTTOM, 1, 3\n*STEP\n*FREQUENCY, STORAGE=YES\n6\n*END STEP\n*STEP\n"
        "*MODAL DYNAMIC\n1e-7, 5e-7\n*MODAL DAMPING, RAYLEIGH\n, , 0., 1e-7\n*CLOAD\n"
        + loads
        + "*NODE PRINT, NSET=NALL\nU\n*END STEP\n"
    )
    (here / "wedge_block_modal.inp").write_text(model + steps)


if __name__ == "__main__":
    here = Path(__file__).parent
    write(here / "wedge_block.inp", nlgeom=False)
    write(here / "wedge_block_nlgeom.inp", nlgeom=True)
    write(here / "wedge_block_pressure.inp", nlgeom=False, pressure=True)
    write(here / "wedge_block_pressure_nlgeom.inp", nlgeom=True, pressure=True)
    write(here / "wedge_block_frd.inp", nlgeom=True, frd=True)
    write_dynamics(here)
