"""Generate the decks of ``tests/calculix/test_calculix_model.py``.

Run once: ``python make_decks.py``.

``loads_ccx.dat`` is ccx 2.20's output for ``loads.inp`` (``ccx -i loads``), kept as a reference.

Meshes are structured boxes in ccx node order: C3D8 bricks, C3D4 (six tetrahedra per brick, ccx's
positive orientation) and C3D10 (C3D4 plus midside nodes; midside nodes of interior edges are moved
off the edge so that a wrong midside-node order would show). Faces for ``*SURFACE``/``*DLOAD`` are
chosen by position with the face tables of ``dolfinx_ntf.calculix.elements``. Pure numpy.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

HERE = Path(__file__).parent

# ccx outward face tables (0-based), as in dolfinx_ntf.calculix.elements.ELEMENT_TYPES
FACES = {
    "C3D8": [[3, 2, 1, 0], [4, 5, 6, 7], [0, 1, 5, 4], [1, 2, 6, 5], [2, 3, 7, 6], [3, 0, 4, 7]],
    "C3D4": [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]],
}
FACES["C3D10"] = FACES["C3D4"]
TET_EDGES = [(0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3)]


def box(origin, size, divisions, first_node=1):
    """Nodes ``(ids, xyz)`` and C3D8 connectivity (node ids) of a structured box."""
    axes = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, divisions)]
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    xyz = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    nx, ny, _ = divisions

    def node(i, j, k):
        return (k * (ny + 1) + j) * (nx + 1) + i

    i, j, k = (a.ravel() for a in np.meshgrid(*[np.arange(n) for n in divisions], indexing="ij"))
    hexes = np.column_stack(
        [
            node(i, j, k),
            node(i + 1, j, k),
            node(i + 1, j + 1, k),
            node(i, j + 1, k),
            node(i, j, k + 1),
            node(i + 1, j, k + 1),
            node(i + 1, j + 1, k + 1),
            node(i, j + 1, k + 1),
        ]
    )
    ids = np.arange(first_node, first_node + xyz.shape[0])
    return ids, xyz, ids[hexes]


def tets(hexes, ids, xyz):
    """Six C3D4 per C3D8 around the 1-7 diagonal, oriented with a positive Jacobian."""
    tensor = hexes[:, [0, 1, 3, 2, 4, 5, 7, 6]]
    paths = [(0, 1, 3, 7), (0, 1, 5, 7), (0, 4, 5, 7), (0, 2, 3, 7), (0, 2, 6, 7), (0, 4, 6, 7)]
    cells = np.vstack([tensor[:, p] for p in paths])
    x = xyz[np.searchsorted(ids, cells)]
    det = np.einsum("ij,ij->i", np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), x[:, 3] - x[:, 0])
    cells[det < 0] = cells[det < 0][:, [0, 2, 1, 3]]
    return cells


def quadratic(cells, ids, xyz, rng, boundary):
    """C3D10 from C3D4: midside nodes per unique edge; interior ones moved off the edge."""
    edges = np.sort(cells[:, TET_EDGES], axis=2).reshape(-1, 2)
    unique, inverse = np.unique(edges, axis=0, return_inverse=True)
    points = xyz[np.searchsorted(ids, unique)]
    mid = points.mean(axis=1)
    length = np.linalg.norm(points[:, 1] - points[:, 0], axis=1)
    inside = ~boundary(mid)
    mid[inside] += 0.04 * length[inside, None] * rng.uniform(-1, 1, (int(inside.sum()), 3))
    new_ids = np.arange(ids.max() + 1, ids.max() + 1 + unique.shape[0])
    conn = np.hstack([cells, new_ids[inverse.ravel()].reshape(-1, 6)])
    return np.concatenate([ids, new_ids]), np.vstack([xyz, mid]), conn


def faces_where(etype, conn, ids, xyz, predicate):
    """``(element index, face number)`` of faces whose corner nodes all satisfy ``predicate(x)``."""
    corners = 3 if etype != "C3D8" else 4
    out = []
    for f, face in enumerate(FACES[etype]):
        x = xyz[np.searchsorted(ids, conn[:, face[:corners]])]
        hit = np.all(predicate(x.reshape(-1, 3)).reshape(-1, corners), axis=1)
        out += [(int(e), f + 1) for e in np.flatnonzero(hit)]
    return sorted(out)


def node_lines(ids, xyz):
    return [f"{i}, {float(x)!r}, {float(y)!r}, {float(z)!r}" for i, (x, y, z) in zip(ids, xyz)]


def element_lines(first, conn):
    lines = []
    for k, row in enumerate(conn):
        values = [first + k] + [int(v) for v in row]
        text = ", ".join(str(v) for v in values)
        if len(values) > 16:  # ccx: at most 16 entries per line
            text = (
                ", ".join(str(v) for v in values[:16])
                + ",\n"
                + ", ".join(str(v) for v in values[16:])
            )
        lines.append(text)
    return lines


def id_lines(ids, per_line=12):
    ids = [str(int(i)) for i in ids]
    return [", ".join(ids[k : k + per_line]) for k in range(0, len(ids), per_line)]


def cube(etype, *, nlgeom=False, pressure=10.0, young=1000.0, nu=0.3, curved=False):
    """Unit cube on rollers (symmetry planes x, y, z = 0) under pressure on top: uniaxial stress.

    ``curved`` moves C3D10 midside nodes of interior edges off their edges (a test of the midside
    node order); the answer is then no longer exact (the 4-point rule does not integrate curved
    elements exactly), so the analytical test uses straight ones.
    """
    ids, xyz, conn = box((0, 0, 0), (1, 1, 1), (2, 2, 2))
    if etype != "C3D8":
        conn = tets(conn, ids, xyz)
    if etype == "C3D10":
        on_boundary = (
            (lambda m: np.any(np.isclose(m, 0) | np.isclose(m, 1), axis=1))
            if curved
            else (lambda m: np.ones(m.shape[0], dtype=bool))
        )
        ids, xyz, conn = quadratic(conn, ids, xyz, np.random.default_rng(3), on_boundary)
    top = faces_where(etype, conn, ids, xyz, lambda x: np.isclose(x[:, 2], 1.0))
    lines = [
        f"*HEADING\nUnit cube, {etype}{' curved' if curved else ''}, uniaxial, on rollers "
        "(make_decks.py)",
        "*NODE, NSET=NALL",
        *node_lines(ids, xyz),
    ]
    lines += [f"*ELEMENT, TYPE={etype}, ELSET=EALL", *element_lines(1, conn)]
    for name, axis in (("X0", 0), ("Y0", 1), ("Z0", 2)):
        lines += [f"*NSET, NSET={name}", *id_lines(ids[np.isclose(xyz[:, axis], 0.0)])]
    lines += [
        "*NSET, NSET=CORNER",
        str(int(ids[np.flatnonzero(np.all(np.isclose(xyz, 1.0), axis=1))[0]])),
    ]
    lines += [
        "*MATERIAL, NAME=STEEL",
        "*ELASTIC",
        f"{young!r}, {nu!r}",
        "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL",
    ]
    lines += [
        "*STEP" + (", NLGEOM" if nlgeom else ""),
        "*STATIC",
        "0.5, 1.0" if nlgeom else "",
        "*BOUNDARY",
        "X0, 1, 1",
        "Y0, 2, 2",
        "Z0, 3, 3",
        "*DLOAD",
    ]
    lines += [f"{e + 1}, P{f}, {pressure!r}" for e, f in top]
    lines += [
        "*NODE PRINT, NSET=NALL",
        "U",
        "*NODE PRINT, NSET=Z0, TOTALS=ONLY",
        "RF",
        "*EL PRINT, ELSET=EALL",
        "S",
        "*END STEP",
    ]
    return "\n".join(line for line in lines if line != "") + "\n"


def blocks():
    """Two C3D8 blocks: an upper block (node-based slave bottom) pressed on a lower block.

    Step 1 pushes the upper block's top down with an amplitude; step 2 keeps it and adds a
    sideways-free concentrated load; the lower block's bottom is fixed, the upper top is guided in x
    and y.
    """
    ids1, xyz1, conn1 = box((0, 0, 0), (1, 1, 0.5), (2, 2, 1))
    ids2, xyz2, conn2 = box((0.25, 0.25, 0.5), (0.5, 0.5, 0.5), (2, 2, 2), first_node=101)
    ids, xyz, conn = (
        np.concatenate([ids1, ids2]),
        np.vstack([xyz1, xyz2]),
        np.vstack([conn1, conn2]),
    )
    lower = np.arange(conn1.shape[0])
    upper = np.arange(conn1.shape[0], conn.shape[0])
    master = [
        (e, f)
        for e, f in faces_where("C3D8", conn, ids, xyz, lambda x: np.isclose(x[:, 2], 0.5))
        if e in lower
    ]
    slave_nodes = ids2[np.isclose(xyz2[:, 2], 0.5)]
    lines = [
        "*HEADING\nTwo C3D8 blocks, node-based slave, EXPONENTIAL law (generated by make_decks.py)",
        "*NODE, NSET=NALL",
        *node_lines(ids, xyz),
    ]
    lines += ["*ELEMENT, TYPE=C3D8, ELSET=EALL", *element_lines(1, conn)]
    lines += [
        "*ELSET, ELSET=LOWER",
        *id_lines(lower + 1),
        "*ELSET, ELSET=UPPER",
        *id_lines(upper + 1),
    ]
    lines += ["*NSET, NSET=BASE", *id_lines(ids1[np.isclose(xyz1[:, 2], 0.0)])]
    lines += ["*NSET, NSET=TOP", *id_lines(ids2[np.isclose(xyz2[:, 2], 1.0)])]
    lines += ["*NSET, NSET=SLAVENODES", *id_lines(slave_nodes)]
    lines += [
        "*MATERIAL, NAME=SOFT",
        "*ELASTIC",
        "1000.0, 0.3",
        "*SOLID SECTION, ELSET=EALL, MATERIAL=SOFT",
    ]
    lines += ["*SURFACE, NAME=MASTER"] + [f"{e + 1}, S{f}" for e, f in master]
    lines += ["*SURFACE, NAME=SLAVE, TYPE=NODE", "SLAVENODES"]
    lines += [
        "*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE",
        "SLAVE, MASTER",
        "*SURFACE INTERACTION, NAME=SI",
        "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=EXPONENTIAL",
        "1.0e-3, 0.5",
    ]
    lines += ["*AMPLITUDE, NAME=PUSH", "0.0, 0.0, 0.5, 0.25, 1.0, 1.0"]
    lines += [
        "*STEP, INC=50",
        "*STATIC",
        "0.25, 1.0",
        "*BOUNDARY",
        "BASE, 1, 3",
        "TOP, 1, 2",
        "*BOUNDARY, AMPLITUDE=PUSH",
        "TOP, 3, 3, -0.004",
        "*NODE PRINT, NSET=TOP, FREQUENCY=2",
        "U",
        "*NODE PRINT, NSET=BASE, TOTALS=YES",
        "RF",
        "*CONTACT PRINT",
        "CDIS, CSTR, CELS, CNUM",
        "*CONTACT PRINT, TOTALS=ONLY",
        "CELS",
        "*NODE FILE, CONTACT ELEMENTS",
        "U",
        "*END STEP",
    ]
    corner = int(ids2[np.flatnonzero(np.all(np.isclose(xyz2, [0.75, 0.75, 1.0]), axis=1))[0]])
    lines += [
        "*STEP",
        "*STATIC, DIRECT",
        "0.5, 1.0",
        "*CLOAD",
        f"{corner}, 3, -1.0",
        "*NODE PRINT, NSET=TOP",
        "U",
        "*END STEP",
    ]
    return "\n".join(lines) + "\n"


# The unit cube in ccx node order: one C3D8 with nodes 1..8.
UNIT_CUBE_NODES = """1, 0.0, 0.0, 0.0
2, 1.0, 0.0, 0.0
3, 1.0, 1.0, 0.0
4, 0.0, 1.0, 0.0
5, 0.0, 0.0, 1.0
6, 1.0, 0.0, 1.0
7, 1.0, 1.0, 1.0
8, 0.0, 1.0, 1.0"""

TWO_CUBES = f"""*NODE, NSET=NALL
{UNIT_CUBE_NODES}
11, 0.25, 0.25, 1.0
12, 0.75, 0.25, 1.0
13, 0.75, 0.75, 1.0
14, 0.25, 0.75, 1.0
15, 0.25, 0.25, 1.5
16, 0.75, 0.25, 1.5
17, 0.75, 0.75, 1.5
18, 0.25, 0.75, 1.5
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
2, 11, 12, 13, 14, 15, 16, 17, 18
*NSET, NSET=FIX
1, 2, 3, 4
*NSET, NSET=TOP
15, 16, 17, 18
*MATERIAL, NAME=STEEL
*ELASTIC
210000., 0.3
*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL
*SURFACE, NAME=MASTER
1, S2
*SURFACE, NAME=SLAVE
2, S1
"""

PAIR = """*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE{adjust}
SLAVE, {master}
*SURFACE INTERACTION, NAME=SI
*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR
1.0e7, 1.0, 1.0e-3
{friction}"""

STEP = """*STEP
*STATIC
0.5, 1.0
*BOUNDARY
FIX, 1, 3
TOP, 1, 2
TOP, 3, 3, -0.001
{extra}*NODE PRINT, NSET=NALL
U
*CONTACT PRINT
CDIS, CSTR
*END STEP
"""


def two_cubes(*, adjust="", master="MASTER", friction="", extra="", more=""):
    """The two-cube contact deck of ``tests/data/calculix/two_cubes.inp`` with variations."""
    return (
        TWO_CUBES
        + PAIR.format(adjust=adjust, master=master, friction=friction)
        + STEP.format(extra=extra)
        + more
    )


DIVERGE_STEP = """*STEP
*STATIC, DIRECT
0.5, 1.0
*CONTROLS, PARAMETERS=FIELD
1e-30, 1e-30, , , 1e-30, , 1e-30, 1e-40
*BOUNDARY
TOP, 3, 3, -0.002
*END STEP
"""

MIXED = f"""*NODE
{UNIT_CUBE_NODES}
9, 0.5, 0.5, 2.0
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
*ELEMENT, TYPE=C3D4, ELSET=EALL
2, 5, 6, 7, 9
*MATERIAL, NAME=M
*ELASTIC
1000.0, 0.3
*SOLID SECTION, ELSET=EALL, MATERIAL=M
*STEP
*STATIC
*BOUNDARY
1, 1, 3
*END STEP
"""

BRICK = f"""*NODE, NSET=NALL
{UNIT_CUBE_NODES}
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
*NSET, NSET=BOTTOM
1, 2, 3, 4
*NSET, NSET=TOP
5, 6, 7, 8
*MATERIAL, NAME=M
*ELASTIC
1000.0, 0.3
*SOLID SECTION, ELSET=EALL, MATERIAL=M
*AMPLITUDE, NAME=STEPAMP
0.0, 0.0, 0.5, 1.0, 1.0, 0.5
*AMPLITUDE, NAME=TOTALAMP, TIME=TOTAL TIME
0.0, 0.0, 4.0, 1.0
*BOUNDARY
BOTTOM, 1, 3
"""

TIGHT = "*CONTROLS, PARAMETERS=FIELD\n1e-10, 1e-8, , , 1e-10, , 1e-8, 1e-12\n"


def loads(pressure: bool) -> str:
    """One NLGEOM brick, three steps exercising ccx's load rules (see model.py's docstring)."""
    p1 = "*DLOAD\n1, P2, 20.0\n1, P2, 10.0\n" if pressure else ""
    p2 = "*DLOAD, OP=NEW\n1, P4, 50.0\n" if pressure else ""
    return (
        "*HEADING\nOne C3D8 brick, NLGEOM, three steps: ramps, amplitudes, OP=NEW/MOD, sums within "
        "a step (generated by make_decks.py)\n"
        + BRICK
        + "*STEP, NLGEOM\n*STATIC, DIRECT\n0.25, 1.0\n"
        + TIGHT
        + "*CLOAD\n7, 3, -10.0\n8, 3, -5.0\n*CLOAD\n8, 3, -5.0\n"
        + "*CLOAD, AMPLITUDE=STEPAMP\n5, 1, 4.0\n"
        + p1
        + "*NODE PRINT, NSET=NALL\nU\n*END STEP\n"
        + "*STEP, NLGEOM\n*STATIC, DIRECT\n0.5, 2.0\n"
        + TIGHT
        + "*CLOAD\n7, 3, -20.0\n"
        + p2
        + "*BOUNDARY\n6, 1, 1, 0.01\n*END STEP\n"
        + "*STEP, NLGEOM\n*STATIC, DIRECT\n0.25, 1.0\n"
        + TIGHT
        + "*CLOAD, OP=NEW, AMPLITUDE=TOTALAMP\n6, 2, 8.0\n"
        + "*BOUNDARY, OP=NEW\nBOTTOM, 1, 3\n*END STEP\n"
    )


def c3d10_points() -> str:
    """One C3D10, u = (a x^2, b y^2, c z^2) prescribed at every node, nu = 0: sxx = 2 E a x etc."""
    corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    x = np.vstack([corners, [(corners[a] + corners[b]) / 2 for a, b in TET_EDGES]])
    lines = [
        "*HEADING\nOne C3D10, quadratic displacement: stress linear in x, y, z (make_decks.py)",
        "*NODE, NSET=NALL",
        *node_lines(np.arange(1, 11), x),
    ]
    lines += ["*ELEMENT, TYPE=C3D10, ELSET=EALL", "1, " + ", ".join(str(i) for i in range(1, 11))]
    lines += [
        "*MATERIAL, NAME=M",
        "*ELASTIC",
        "1000.0, 0.0",
        "*SOLID SECTION, ELSET=EALL, MATERIAL=M",
        "*STEP",
        "*STATIC",
        "*BOUNDARY",
    ]
    for i, p in enumerate(x):
        for d, coefficient in enumerate((1e-3, 2e-3, 3e-3)):
            lines.append(f"{i + 1}, {d + 1}, {d + 1}, {float(coefficient * p[d] ** 2)!r}")
    lines += ["*EL PRINT, ELSET=EALL", "S", "*END STEP"]
    return "\n".join(lines) + "\n"


def error_decks() -> dict[str, str]:
    """Decks that must fail with a clear message."""
    return {
        "err_mixed": MIXED,
        "err_unknown_surface": two_cubes(master="NOSUCH"),
        "diverge": two_cubes(more=DIVERGE_STEP),
    }


def main() -> None:
    for etype in ("C3D8", "C3D4", "C3D10"):
        (HERE / f"cube_{etype.lower()}.inp").write_text(cube(etype))
    (HERE / "cube_c3d10_curved.inp").write_text(cube("C3D10", curved=True))
    (HERE / "cube_nlgeom.inp").write_text(cube("C3D8", nlgeom=True, pressure=100.0))
    (HERE / "blocks.inp").write_text(blocks())
    (HERE / "loads.inp").write_text(loads(pressure=False))
    (HERE / "loads_pressure.inp").write_text(loads(pressure=True))
    (HERE / "c3d10_points.inp").write_text(c3d10_points())
    for name, text in error_decks().items():
        (HERE / f"{name}.inp").write_text(text)


if __name__ == "__main__":
    main()
