"""Write the C3D15 heat decks ``wedge_heat*.inp`` of docs/method.md §39.

``make_block.py``'s block (16 curved C3D15 wedges on [0, 2] x [0, 1] x [0, 1]) with its bottom
held at temperatures that vary over the face (``100 + 20 x + 10 y``, dof 11):

- ``wedge_heat_steady``: ``*HEAT TRANSFER, STEADY STATE``, the top held at 0, in ccx's
  increments (0.25, 0.5, 0.875, 1: the prescribed temperatures ramp from 0);
- ``wedge_heat_transient``: a transient ``*HEAT TRANSFER`` from 20 everywhere
  (``*INITIAL CONDITIONS, TYPE=TEMPERATURE``), fixed increments (``DIRECT``);

both with ``*NODE PRINT NT`` and ``*EL PRINT HFL``;

- ``wedge_coupled``: ``*COUPLED TEMPERATURE-DISPLACEMENT, STEADY STATE`` in two increments from
  20 everywhere, the top held at 0, ``*EXPANSION`` (``ZERO`` not given: the strain is measured
  from the initial temperature), the bottom clamped; ``NT, U, RF`` and ``HFL, S``;
- ``wedge_coupled_nlgeom``: the same with ``NLGEOM``, ``*EXPANSION 4e-4`` (thermal strains up to
  5e-2) and tight ``*CONTROLS`` in both codes (converged solutions compared).

- ``wedge_cflux_steady``, ``wedge_cflux_transient``: the two heat decks with ``*CFLUX`` heat
  flows into a bottom node and every top node (the top not held), one top node listed twice;
  ``wedge_cflux_steps``: the steady one followed by a second steady step that changes the flow of
  one node (``OP=MOD``: the others stay);
- ``wedge_dflux_steady``, ``wedge_dflux_transient``: the two heat decks with ``*DFLUX`` fluxes
  into the curved top triangles and the curved quadrilaterals at x = 2 (one value per element;
  the top not held);
- ``wedge_film_steady``, ``wedge_film_transient``: the same faces with ``*FILM`` (sink 40 and
  coefficient 0.5 on the top triangles, sink -10 and coefficient 1.5 on the quadrilaterals).

Run: ``python make_heat.py`` (deterministic).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from make_block import FACES, LX, LZ, _grid


def _model(x: np.ndarray, wedges: list, expansion: float = 0.0) -> list[str]:
    """Nodes, elements, the bottom and top sets and the material."""
    lines = ["*HEADING", "C3D15 block, curved edges, heat conduction (dolfinx_ntf method §39)"]
    lines.append("*NODE, NSET=NALL")
    lines += [f"{n + 1}, {p[0]:.12g}, {p[1]:.12g}, {p[2]:.12g}" for n, p in enumerate(x)]
    lines.append("*ELEMENT, TYPE=C3D15, ELSET=EALL")
    for e, w in enumerate(wedges):
        lines.append(f"{e + 1}, " + ", ".join(map(str, w[:10])) + ",")
        lines.append(", ".join(map(str, w[10:])))
    for name, z in (("BOTTOM", 0.0), ("TOP", LZ)):
        ids = np.flatnonzero(np.isclose(x[:, 2], z)) + 1
        lines.append(f"*NSET, NSET={name}")
        lines += [", ".join(map(str, ids[i : i + 8])) for i in range(0, ids.size, 8)]
    lines += ["*MATERIAL, NAME=M", "*ELASTIC", "1000., 0.3", "*CONDUCTIVITY", "2.5"]
    if expansion:
        lines += ["*EXPANSION", f"{expansion:g}"]
    lines += ["*DENSITY", "1.5", "*SPECIFIC HEAT", "0.8"]
    lines += ["*SOLID SECTION, ELSET=EALL, MATERIAL=M"]
    return lines


def _bottom(x: np.ndarray) -> list[str]:
    """``*BOUNDARY`` dof 11 on the bottom nodes: ``100 + 20 x + 10 y``."""
    ids = np.flatnonzero(np.isclose(x[:, 2], 0.0))
    return [f"{n + 1}, 11, 11, {100.0 + 20.0 * x[n, 0] + 10.0 * x[n, 1]:.12g}" for n in ids]


#: ``*CFLUX`` lines: a bottom node, every top node, one top node again (its flows add up).
CFLUX = ["*CFLUX", "4, 11, 50.", "TOP, 11, 2.5", "60, 11, 7."]


def _dflux(x: np.ndarray, wedges: list) -> list[str]:
    """``*DFLUX`` on the top triangles (z = LZ) and the quadrilaterals at x = LX."""
    lines = ["*DFLUX"]
    for e, w in enumerate(wedges):
        for f, corners in enumerate(FACES):
            p = x[[w[c] - 1 for c in corners]]
            top, side = np.allclose(p[:, 2], LZ), np.allclose(p[:, 0], LX)
            if top or side:
                lines.append(f"{e + 1}, S{f + 1}, {(-20.0 if top else 30.0) + 2.0 * e:.12g}")
    return lines


def _film(x: np.ndarray, wedges: list) -> list[str]:
    """``*FILM`` on the faces of :func:`_dflux`."""
    lines = ["*FILM"]
    for line in _dflux(x, wedges)[1:]:
        element, label, value = (t.strip() for t in line.split(","))
        top = float(value) < 0.0
        lines.append(f"{element}, F{label[1]}, {40.0 if top else -10.0}, {0.5 if top else 1.5}")
    return lines


def write(
    path: Path,
    transient: bool,
    cflux: bool = False,
    steps: bool = False,
    dflux: bool = False,
    film: bool = False,
) -> None:
    points, wedges = _grid()
    x = np.array(points)
    lines = _model(x, wedges)
    if transient:
        lines += ["*INITIAL CONDITIONS, TYPE=TEMPERATURE", "NALL, 20."]
        lines += ["*STEP", "*HEAT TRANSFER, DIRECT", "0.05, 0.2"]
    else:
        lines += ["*STEP", "*HEAT TRANSFER, STEADY STATE", "0.25, 1."]
    lines += ["*BOUNDARY", *_bottom(x)]
    if not transient and not (cflux or dflux or film):
        lines += ["TOP, 11, 11, 0."]
    lines += CFLUX if cflux else []
    lines += _dflux(x, wedges) if dflux else []
    lines += _film(x, wedges) if film else []
    lines += ["*NODE PRINT, NSET=NALL", "NT", "*EL PRINT, ELSET=EALL", "HFL", "*END STEP"]
    if steps:
        lines += ["*STEP", "*HEAT TRANSFER, STEADY STATE", "0.5, 1.", "*CFLUX", "4, 11, -30."]
        lines += ["*NODE PRINT, NSET=NALL", "NT", "*EL PRINT, ELSET=EALL", "HFL", "*END STEP"]
    path.write_text("\n".join(lines) + "\n")


def write_coupled(path: Path, nlgeom: bool = False) -> None:
    points, wedges = _grid()
    x = np.array(points)
    lines = _model(x, wedges, expansion=4e-4 if nlgeom else 1e-3)
    lines += ["*INITIAL CONDITIONS, TYPE=TEMPERATURE", "NALL, 20."]
    lines += ["*STEP" + (", NLGEOM" if nlgeom else "")]
    lines += ["*COUPLED TEMPERATURE-DISPLACEMENT, STEADY STATE", "0.5, 1."]
    if nlgeom:  # both codes to round-off (the default stops at 0.5 %)
        lines += ["*CONTROLS, PARAMETERS=FIELD", "1e-10, 1e-08, , , 1e-10, 1e-05, 1e-08, 1e-12"]
    lines += ["*BOUNDARY", "BOTTOM, 1, 3", *_bottom(x), "TOP, 11, 11, 0."]
    lines += ["*NODE PRINT, NSET=NALL", "NT, U, RF", "*EL PRINT, ELSET=EALL", "HFL, S"]
    lines += ["*END STEP"]
    path.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    here = Path(__file__).parent
    write(here / "wedge_heat_steady.inp", transient=False)
    write(here / "wedge_heat_transient.inp", transient=True)
    write_coupled(here / "wedge_coupled.inp")
    write_coupled(here / "wedge_coupled_nlgeom.inp", nlgeom=True)
    write(here / "wedge_cflux_steady.inp", transient=False, cflux=True)
    write(here / "wedge_cflux_transient.inp", transient=True, cflux=True)
    write(here / "wedge_cflux_steps.inp", transient=False, cflux=True, steps=True)
    write(here / "wedge_dflux_steady.inp", transient=False, dflux=True)
    write(here / "wedge_dflux_transient.inp", transient=True, dflux=True)
    write(here / "wedge_film_steady.inp", transient=False, film=True)
    write(here / "wedge_film_transient.inp", transient=True, film=True)
