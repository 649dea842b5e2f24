"""Write the C3D15 contact decks ``wedge_punch_*.inp`` of docs/method.md §38.

A punch of C3D15 wedges pressed onto a block of C3D15 wedges (node-to-surface contact, LINEAR
law, the punch's top moved down in two increments, the block's bottom clamped). Each body is a
grid of hexahedra, each split into two wedges along a diagonal; the wedges' axis decides which
faces meet: along y the block's top and the punch's bottom are 8-node quadrilaterals (ccx faces
S3..S5), along z 6-node triangles (S1, S2). The grids do not match across the interface and
no slave node lies above a master edge. Decks:

- ``wedge_punch_quad``: quadrilateral slave faces on quadrilateral master faces;
- ``wedge_punch_tri``: triangular slave faces on triangular master faces;
- ``wedge_punch_quad_on_tri``: quadrilateral slave faces on triangular master faces;
- ``wedge_punch_quad_curved``, ``wedge_punch_tri_curved``: the first two with the punch's midside
  nodes moved in x and y by a smooth field of amplitude 0.03 (curved edges; the contact faces
  stay in the plane z = 1): the spring areas depend on ccx's face-area rule there;
- ``wedge_tie_quad``, ``wedge_tie_tri``: the punch tied to the block (``*TIE``, quadrilaterals
  or triangles; the punch's top also moved sideways);
- ``wedge_punch_mixed``, ``wedge_tie_mixed``: a punch whose first column of cells has its
  wedges along y, the second along z: its bottom is a slave surface of quadrilaterals and
  triangles (in contact with, or tied to, the block's quadrilaterals);
- ``wedge_node_quad``, ``wedge_node_mixed``: the slave surface is the node set of the punch's
  bottom (``TYPE=NODE``, corner and midside nodes), whose faces are every exterior face with a
  corner in it: the bottom's and the sides' (triangles and quadrilaterals);
- ``wedge_adjust_set``, ``wedge_adjust_distance``: ``wedge_punch_quad`` with the punch 0.002
  above the block and ``ADJUST`` on the pair: the node set of the bottom's corner nodes, or the
  distance 0.005 (every slave node; docs/method.md §38.6);
- ``wedge_heat_punch``: ``wedge_punch_quad`` as a ``*HEAT TRANSFER, STEADY STATE`` step: the
  block's bottom at 0, the punch's top at 100, heat across the contact springs by a ``*GAP
  CONDUCTANCE`` of 30 (docs/method.md §38.7);
- ``wedge_master_mixed``, ``wedge_master_mixed_tri``: a block whose columns of cells along x
  alternate their wedges' axis (y, z, y, z): its top, the master surface, is quadrilaterals at
  0 < x < 0.5 and 1 < x < 1.5 and triangles at 0.5 < x < 1 and 1.5 < x < 2; the punch (wedges
  along y: quadrilaterals, along z: triangles) spans x = 0.52..1.47, so its nodes land on both
  kinds of master face (docs/method.md §38.8); ``wedge_master_mixed_slide``: the first with
  friction and a second step sliding the punch 0.15 in x, so that slave nodes move from the
  triangles onto the quadrilaterals.

Run ``python make_contact.py`` (deterministic: no random numbers).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

#: ccx's C3D15 faces by their corners (manual): S1 1-2-3, S2 4-5-6, S3 1-2-5-4, S4 2-3-6-5,
#: S5 3-1-4-6 (0-based).
FACES = ((0, 1, 2), (3, 4, 5), (0, 1, 4, 3), (1, 2, 5, 4), (2, 0, 3, 5))
#: ccx C3D15 midside nodes 7..15 on these corner pairs.
EDGES = ((0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5))


def wedge_body(
    origin: tuple, size: tuple, divisions: tuple, axis: int | tuple, first_node: int
) -> tuple[np.ndarray, list[list[int]]]:
    """Points and C3D15 connectivities (1-based, from ``first_node``) of a box of wedges.

    Every hexahedron of the grid becomes two wedges whose triangles are normal to ``axis``
    (0, 1, 2; a tuple: ``axis[i % len(axis)]`` for the cells of the i-th column along x, y or z
    only, which keeps the mesh conforming), the diagonal alternating from cell to cell.
    """
    h = np.array(size, float) / np.array(divisions)
    points: list[np.ndarray] = []
    index: dict[tuple, int] = {}

    def node(p: np.ndarray) -> int:
        key = tuple(np.round(p, 9))
        if key not in index:
            index[key] = first_node + len(points)
            points.append(p)
        return index[key]

    wedges = []
    for cell in np.ndindex(*divisions):
        axis_here = axis if isinstance(axis, int) else axis[cell[0] % len(axis)]
        u, v = [a for a in range(3) if a != axis_here]
        o = np.array(origin, float) + np.array(cell) * h
        square = []
        for a, b in ((0, 0), (1, 0), (1, 1), (0, 1)):
            p = o.copy()
            p[u] += a * h[u]
            p[v] += b * h[v]
            square.append(p)
        up = np.zeros(3)
        up[axis_here] = h[axis_here]
        # the diagonal alternates across the triangles' plane only: conforming along the axis
        split = ((0, 1, 2), (0, 2, 3)) if (cell[u] + cell[v]) % 2 == 0 else ((0, 1, 3), (1, 2, 3))
        for tri in split:
            bottom = [square[t] for t in tri]
            if np.dot(np.cross(bottom[1] - bottom[0], bottom[2] - bottom[0]), up) < 0:
                bottom = [bottom[0], bottom[2], bottom[1]]  # 1-2-3 counter-clockwise from 4-5-6
            corners = bottom + [p + up for p in bottom]
            nodes = [node(p) for p in corners]
            nodes += [node((corners[a] + corners[b]) / 2) for a, b in EDGES]
            wedges.append(nodes)
    return np.array(points), wedges


def _faces_on(x: np.ndarray, wedges: list, first_element: int, coordinate: int, value: float):
    """``(element, face)`` of the faces whose corners all lie on the plane ``x_c = value``."""
    out = []
    for e, w in enumerate(wedges):
        for f, corners in enumerate(FACES):
            if np.allclose(x[[w[c] - 1 for c in corners], coordinate], value):
                out.append((first_element + e, f + 1))
    return out


def _curve(x: np.ndarray, wedges: list, first_node: int) -> np.ndarray:
    """``x`` with the midside nodes of ``wedges`` moved in x and y (smooth, amplitude 0.03)."""
    mids = np.unique(np.array(wedges)[:, 6:]) - first_node
    x = x.copy()
    p = x[mids]
    x[mids, 0] += 0.03 * np.sin(3 * p[:, 1] + 2 * p[:, 0])
    x[mids, 1] += 0.03 * np.cos(2 * p[:, 0] + p[:, 1])
    return x


def write(
    path: Path,
    slave_axis: int | tuple,
    master_axis: int | tuple,
    curved: bool = False,
    tie: bool = False,
    nodes: bool = False,
    adjust: str | None = None,
    heat: bool = False,
    slide: float = 0.0,
) -> None:
    """The punch (wedges along ``slave_axis``) on the block (along ``master_axis``).

    ``curved``: the punch's edges curved in x and y (:func:`_curve`); ``tie``: the punch tied
    to the block instead of in contact, its top also moved by 0.01 in x; ``nodes``: the slave
    surface is the node set of the punch's bottom (``TYPE=NODE``); ``adjust``: the punch 0.002
    higher and the pair's ``ADJUST`` (``"set"``: the bottom's corner nodes, else a distance);
    ``heat``: a steady heat transfer step instead (conductivities, a gap conductance);
    ``slide``: Coulomb friction (mu 0.2, stick slope 5000) and a second step moving the punch's
    top by ``slide`` in x in increments of 0.1.
    """
    lift = 0.0 if adjust is None else 0.002
    block_x, block_w = wedge_body((0, 0, 0), (2, 1, 1), (4, 2, 2), master_axis, 1)
    n0 = block_x.shape[0] + 1
    punch_x, punch_w = wedge_body(
        (0.52, 0.13, 1 + lift), (0.95, 0.68, 0.5), (2, 2, 1), slave_axis, n0
    )
    if curved:
        punch_x = _curve(punch_x, punch_w, n0)
    x = np.vstack([block_x, punch_x])
    e0 = len(block_w) + 1
    shape = "curved punch" if curved else "punch"
    axes = "".join("xyz"[a] for a in np.atleast_1d(slave_axis))
    block_axes = "".join("xyz"[a] for a in np.atleast_1d(master_axis))
    heading = f"C3D15 {shape} (wedge axis {axes}) on a C3D15 block (axis "
    lines = ["*HEADING", heading + f"{block_axes}), dolfinx_ntf method §38"]
    lines.append("*NODE, NSET=NALL")
    lines += [f"{n + 1}, {p[0]:.12g}, {p[1]:.12g}, {p[2]:.12g}" for n, p in enumerate(x)]
    for name, wedges, first in (("BLOCK", block_w, 1), ("PUNCH", punch_w, e0)):
        lines.append(f"*ELEMENT, TYPE=C3D15, ELSET={name}")
        for e, w in enumerate(wedges):
            lines.append(f"{first + e}, " + ", ".join(map(str, w[:10])) + ",")
            lines.append(", ".join(map(str, w[10:])))
    lines += ["*ELSET, ELSET=EALL", "BLOCK, PUNCH"]
    base = np.flatnonzero(np.isclose(x[:, 2], 0.0)) + 1
    top = np.flatnonzero(np.isclose(x[:, 2], 1.5 + lift)) + 1
    bottom = n0 + np.flatnonzero(np.isclose(punch_x[:, 2], 1.0 + lift))
    corners = np.intersect1d(bottom, np.array(punch_w)[:, :6])
    sets = [("BASE", base), ("TOP", top)] + ([("BOTTOM", bottom)] if nodes else [])
    sets += [("ADJ", corners)] if adjust == "set" else []
    for name, members in sets:
        lines.append(f"*NSET, NSET={name}")
        lines += [", ".join(map(str, members[i : i + 8])) for i in range(0, members.size, 8)]
    for name, e, nu, elset in (("SOFT", 1000.0, 0.3, "BLOCK"), ("HARD", 2000.0, 0.25, "PUNCH")):
        lines += [f"*MATERIAL, NAME={name}", "*ELASTIC", f"{e}, {nu}"]
        lines += ["*CONDUCTIVITY", "50." if name == "SOFT" else "20."] if heat else []
        lines.append(f"*SOLID SECTION, ELSET={elset}, MATERIAL={name}")
    slave = _faces_on(x, punch_w, e0, 2, 1.0 + lift)
    master = _faces_on(x, block_w, 1, 2, 1.0)
    for name, faces in (("SLAVE", slave), ("MASTER", master)):
        if name == "SLAVE" and nodes:
            lines += ["*SURFACE, NAME=SLAVE, TYPE=NODE", "BOTTOM"]
            continue
        lines.append(f"*SURFACE, NAME={name}")
        lines += [f"{e}, S{f}" for e, f in faces]
    if tie:
        lines += ["*TIE, NAME=T", "SLAVE, MASTER"]
    else:
        lines += [
            "*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE"
            + ("" if adjust is None else f", ADJUST={'ADJ' if adjust == 'set' else adjust}"),
            "SLAVE, MASTER",
            "*SURFACE INTERACTION, NAME=SI",
            "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
            "50000.0, 0.014285714285714285, 0.001",
            *(["*GAP CONDUCTANCE", "30., 0.", "30., 1e6"] if heat else []),
            *(["*FRICTION", "0.2, 5000."] if slide else []),
        ]
    if heat:
        lines += ["*BOUNDARY", "BASE, 1, 3, 0.0", "TOP, 1, 2, 0.0"]
        lines += ["*INITIAL CONDITIONS, TYPE=TEMPERATURE", "NALL, 20."]
        lines += ["*STEP, INC=100", "*HEAT TRANSFER, STEADY STATE", "0.5, 1.0"]
        lines += ["*BOUNDARY", "BASE, 11, 11, 0.", "TOP, 11, 11, 100."]
        lines += ["*NODE PRINT, NSET=NALL", "NT", "*EL PRINT, ELSET=EALL", "HFL", "*END STEP"]
        path.write_text("\n".join(lines) + "\n")
        return
    lines += [
        "*BOUNDARY",
        "BASE, 1, 3, 0.0",
        "TOP, 1, 2, 0.0",
        "*STEP, INC=100",
        "*STATIC, DIRECT",
        "0.5, 1.0",
        "*CONTROLS, PARAMETERS=FIELD",
        "1e-10, 1e-08, , , 1e-10, 1e-05, 1e-08, 1e-12",
        "*BOUNDARY",
        "TOP, 3, 3, -0.02",
        *(["TOP, 1, 1, 0.01"] if tie else []),
        "*NODE PRINT, NSET=NALL",
        "U, RF",
        *([] if tie else ["*CONTACT PRINT", "CDIS, CSTR, CELS, CNUM"]),
        "*END STEP",
    ]
    if slide:
        lines += [
            "*STEP, INC=100",
            "*STATIC, DIRECT",
            "0.1, 1.0",
            "*CONTROLS, PARAMETERS=FIELD",
            "1e-10, 1e-08, , , 1e-10, 1e-05, 1e-08, 1e-12",
            "*BOUNDARY",
            f"TOP, 1, 1, {slide}",
            "*NODE PRINT, NSET=NALL",
            "U, RF",
            "*CONTACT PRINT",
            "CDIS, CSTR, CELS, CNUM",
            "*END STEP",
        ]
    path.write_text("\n".join(lines) + "\n")


if __name__ == "__main__":
    here = Path(__file__).parent
    write(here / "wedge_punch_quad.inp", slave_axis=1, master_axis=1)
    write(here / "wedge_punch_tri.inp", slave_axis=2, master_axis=2)
    write(here / "wedge_punch_quad_on_tri.inp", slave_axis=1, master_axis=2)
    write(here / "wedge_punch_quad_curved.inp", slave_axis=1, master_axis=1, curved=True)
    write(here / "wedge_punch_tri_curved.inp", slave_axis=2, master_axis=2, curved=True)
    write(here / "wedge_tie_quad.inp", slave_axis=1, master_axis=1, tie=True)
    write(here / "wedge_tie_tri.inp", slave_axis=2, master_axis=2, tie=True)
    write(here / "wedge_punch_mixed.inp", slave_axis=(1, 2), master_axis=1)
    write(here / "wedge_tie_mixed.inp", slave_axis=(1, 2), master_axis=1, tie=True)
    write(here / "wedge_node_quad.inp", slave_axis=1, master_axis=1, nodes=True)
    write(here / "wedge_node_mixed.inp", slave_axis=(1, 2), master_axis=1, nodes=True)
    write(here / "wedge_adjust_set.inp", slave_axis=1, master_axis=1, adjust="set")
    write(here / "wedge_adjust_distance.inp", slave_axis=1, master_axis=1, adjust="0.005")
    write(here / "wedge_heat_punch.inp", slave_axis=1, master_axis=1, heat=True)

    write(here / "wedge_master_mixed.inp", slave_axis=1, master_axis=(1, 2))
    write(here / "wedge_master_mixed_tri.inp", slave_axis=2, master_axis=(1, 2))
    write(here / "wedge_master_mixed_slide.inp", slave_axis=1, master_axis=(1, 2), slide=0.15)
