"""Small generated decks of ``*TIE`` (docs/method.md §19): tied blocks and a cyclic sector.

``tied_blocks_deck``: two C3D8 blocks, the upper one (its bottom the slave surface) meshed
differently from the lower one (its top the master), the lower one clamped at its bottom, a shear
and a compressive force on the upper top; ``tied_quadratic_blocks_deck`` the same of C3D20 or
C3D20R. ``sector_deck``: a 30 degree sector of a ring (C3D8)
under internal pressure, its two radial faces tied by cyclic symmetry about z.
"""

import numpy as np


def _box(origin, size, div, first_node, first_elem):
    axes = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, div)]
    nx, ny, nz = div
    ids = {}
    lines = []
    nid = first_node
    for k in range(nz + 1):
        for j in range(ny + 1):
            for i in range(nx + 1):
                ids[i, j, k] = nid
                lines.append(f"{nid}, {axes[0][i]:.12g}, {axes[1][j]:.12g}, {axes[2][k]:.12g}")
                nid += 1
    elems = []
    eid = first_elem
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                n = [
                    ids[i, j, k],
                    ids[i + 1, j, k],
                    ids[i + 1, j + 1, k],
                    ids[i, j + 1, k],
                    ids[i, j, k + 1],
                    ids[i + 1, j, k + 1],
                    ids[i + 1, j + 1, k + 1],
                    ids[i, j + 1, k + 1],
                ]
                elems.append((eid, k, n))
                eid += 1
    return lines, elems, ids


def tied_blocks_deck(
    lower=(2, 2, 2),
    upper=(3, 3, 2),
    gap=0.0,
    tie="*TIE, NAME=T1\nSLAVE, MASTER",
    slave_nodal=False,
    nlgeom=False,
):
    ln, le, lids = _box((0, 0, -1), (1, 1, 1), lower, 1, 1)
    un, ue, uids = _box((0, 0, gap), (1, 1, 1), upper, 1001, 1001)
    out = ["*NODE, NSET=NALL", *ln, *un]
    out.append("*ELEMENT, TYPE=C3D8, ELSET=EALL")
    out += [f"{e}, " + ", ".join(map(str, n)) for e, _, n in le + ue]
    out.append("*ELSET, ELSET=TOPEL")
    out += [str(e) for e, k, _ in le if k == lower[2] - 1]
    out.append("*ELSET, ELSET=BOTEL")
    out += [str(e) for e, k, _ in ue if k == 0]
    out.append("*NSET, NSET=FIX")
    out += [str(v) for (i, j, k), v in lids.items() if k == 0]
    out.append("*NSET, NSET=LOAD")
    out += [str(v) for (i, j, k), v in uids.items() if k == upper[2]]
    out.append("*NSET, NSET=UBOT")
    out += [str(v) for (i, j, k), v in uids.items() if k == 0]
    out.append("*SURFACE, NAME=MASTER\nTOPEL, S2")
    if slave_nodal:
        out.append("*SURFACE, NAME=SLAVE, TYPE=NODE\nUBOT")
    else:
        out.append("*SURFACE, NAME=SLAVE\nBOTEL, S1")
    out.append(tie)
    out.append(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n210000., 0.3\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL"
    )
    out.append("*BOUNDARY\nFIX, 1, 3")
    out.append("*STEP" + (", NLGEOM" if nlgeom else "") + "\n*STATIC")
    n = len([1 for (i, j, k) in uids if k == upper[2]])
    out.append(f"*CLOAD\nLOAD, 1, {1000.0 / n:g}\nLOAD, 3, {-3000.0 / n:g}")
    out.append("*NODE PRINT, NSET=NALL\nU\n*END STEP")
    return "\n".join(out) + "\n"


def sector_deck(
    nr=3,
    nt=4,
    nz=1,
    angle=30.0,
    n=12,
    tie_params="POSITION TOLERANCE=0.001",
    nodal=True,
    master_first=False,
):
    ids = {}
    out = ["*NODE, NSET=NALL"]
    nid = 1
    for k in range(nz + 1):
        for j in range(nt + 1):
            for i in range(nr + 1):
                r = 1.0 + i / nr
                t = np.radians(angle) * j / nt
                z = 0.2 * k / nz
                ids[i, j, k] = nid
                out.append(f"{nid}, {r * np.cos(t):.15g}, {r * np.sin(t):.15g}, {z:.15g}")
                nid += 1
    out.append("*ELEMENT, TYPE=C3D8, ELSET=EALL")
    eid = 1
    inner = []
    for k in range(nz):
        for j in range(nt):
            for i in range(nr):
                c = [ids[i, j, k], ids[i + 1, j, k], ids[i + 1, j + 1, k], ids[i, j + 1, k]]
                c += [
                    ids[i, j, k + 1],
                    ids[i + 1, j, k + 1],
                    ids[i + 1, j + 1, k + 1],
                    ids[i, j + 1, k + 1],
                ]
                out.append(f"{eid}, " + ", ".join(map(str, c)))
                if i == 0:
                    inner.append(eid)
                eid += 1

    def nset(name, pred):
        out.append(f"*NSET, NSET={name}")
        out.extend(str(v) for key, v in ids.items() if pred(*key))

    nset("MASTERN", lambda i, j, k: j == 0)
    nset("SLAVEN", lambda i, j, k: j == nt)
    nset("BOTTOM", lambda i, j, k: k == 0 and j < nt)
    out.append("*SURFACE, NAME=SIND, TYPE=NODE\nMASTERN\n*SURFACE, NAME=SDEP, TYPE=NODE\nSLAVEN")
    out.append(f"*TIE, NAME=CS, CYCLIC SYMMETRY, {tie_params}\nSDEP, SIND")
    out.append(f"*CYCLIC SYMMETRY MODEL, N={n}, TIE=CS\n0., 0., 0., 0., 0., 1.")
    out.append(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n210000., 0.3\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL"
    )
    out.append("*BOUNDARY\nBOTTOM, 3, 3\nMASTERN, 2, 2")
    out.append("*STEP\n*STATIC\n*DLOAD")
    out.extend(f"{e}, P6, 100." for e in inner)
    out.append("*NODE PRINT, NSET=NALL\nU\n*END STEP")
    return "\n".join(out) + "\n"


def _box20(origin, size, div, first_node, first_elem, lines, ids_out):
    nx, ny, nz = div
    ids = {}
    nid = first_node
    for kk in range(2 * nz + 1):
        for jj in range(2 * ny + 1):
            for ii in range(2 * nx + 1):
                if (ii % 2) + (jj % 2) + (kk % 2) > 1:
                    continue
                ids[ii, jj, kk] = nid
                x = origin[0] + size[0] * ii / (2 * nx)
                y = origin[1] + size[1] * jj / (2 * ny)
                z = origin[2] + size[2] * kk / (2 * nz)
                lines.append(f"{nid}, {x:.15g}, {y:.15g}, {z:.15g}")
                nid += 1
    elems = []
    eid = first_elem
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                ii, jj, kk = 2 * i, 2 * j, 2 * k
                c = [
                    (ii, jj, kk),
                    (ii + 2, jj, kk),
                    (ii + 2, jj + 2, kk),
                    (ii, jj + 2, kk),
                    (ii, jj, kk + 2),
                    (ii + 2, jj, kk + 2),
                    (ii + 2, jj + 2, kk + 2),
                    (ii, jj + 2, kk + 2),
                ]
                m = [
                    (ii + 1, jj, kk),
                    (ii + 2, jj + 1, kk),
                    (ii + 1, jj + 2, kk),
                    (ii, jj + 1, kk),
                    (ii + 1, jj, kk + 2),
                    (ii + 2, jj + 1, kk + 2),
                    (ii + 1, jj + 2, kk + 2),
                    (ii, jj + 1, kk + 2),
                    (ii, jj, kk + 1),
                    (ii + 2, jj, kk + 1),
                    (ii + 2, jj + 2, kk + 1),
                    (ii, jj + 2, kk + 1),
                ]
                elems.append((eid, k, [ids[p] for p in (*c, *m)]))
                eid += 1
    ids_out.update(ids)
    return elems


def tied_quadratic_blocks_deck(
    etype="C3D20", lower=(2, 2, 2), upper=(3, 3, 2), gap=0.0, slave_nodal=False
):
    """``tied_blocks_deck`` with 20-node hexahedra (``etype`` C3D20 or C3D20R)."""
    lines = []
    lids = {}
    uids = {}
    le = _box20((0, 0, -1), (1, 1, 1), lower, 1, 1, lines, lids)
    ue = _box20((0, 0, gap), (1, 1, 1), upper, 10001, 1001, lines, uids)
    out = ["*NODE, NSET=NALL", *lines, f"*ELEMENT, TYPE={etype}, ELSET=EALL"]
    for e, _, n in le + ue:
        out.append(f"{e}, " + ", ".join(map(str, n[:15])) + ",")
        out.append(", ".join(map(str, n[15:])))
    out.append("*ELSET, ELSET=TOPEL")
    out += [str(e) for e, k, _ in le if k == lower[2] - 1]
    out.append("*ELSET, ELSET=BOTEL")
    out += [str(e) for e, k, _ in ue if k == 0]
    out.append("*NSET, NSET=FIX")
    out += [str(v) for (ii, jj, kk), v in lids.items() if kk == 0]
    out.append("*NSET, NSET=LOAD")
    out += [
        str(v)
        for (ii, jj, kk), v in uids.items()
        if kk == 2 * upper[2] and ii % 2 == 0 and jj % 2 == 0
    ]
    out.append("*NSET, NSET=UBOT")
    out += [str(v) for (ii, jj, kk), v in uids.items() if kk == 0]
    out.append("*SURFACE, NAME=MASTER\nTOPEL, S2")
    out.append(
        "*SURFACE, NAME=SLAVE, TYPE=NODE\nUBOT"
        if slave_nodal
        else "*SURFACE, NAME=SLAVE\nBOTEL, S1"
    )
    out.append("*TIE, NAME=T1\nSLAVE, MASTER")
    out.append(
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n210000., 0.3\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL"
    )
    out.append("*BOUNDARY\nFIX, 1, 3\n*STEP\n*STATIC")
    n = len([1 for (ii, jj, kk) in uids if kk == 2 * upper[2] and ii % 2 == 0 and jj % 2 == 0])
    out.append(f"*CLOAD\nLOAD, 1, {1000.0 / n:g}\nLOAD, 3, {-3000.0 / n:g}")
    out.append("*NODE PRINT, NSET=NALL\nU\n*END STEP")
    return "\n".join(out) + "\n"
