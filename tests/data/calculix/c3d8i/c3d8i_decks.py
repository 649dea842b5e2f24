"""Generated C3D8I decks for the deck runner's tests against ccx 2.20 (docs/method.md §22).

``cantilever_deck``: a clamped beam of 8 x 1 x 2 hexahedra with a tip load in z (and optionally a
pressure on its top), its inner nodes optionally moved off the grid (distorted cells, not
parallelepipeds). ``contact_deck``: a beam of
6 x 1 x 1 hexahedra pressed at its ends onto a block of 4 x 2 x 2 in 2 increments (contact, the
beam's bottom the slave face S1, the block's top the master S2; non-matching meshes). Both write
every print and file request the tests compare.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

E, NU = 210000.0, 0.3


def _grid(first_node, origin, size, divisions, rng=None, shift=0.0):
    """Nodes ``(id, x, y, z)`` and C3D8 connectivity of a box, ``first_node`` the first id."""
    axes = [np.linspace(o, o + s, n + 1) for o, s, n in zip(origin, size, divisions)]
    nx, ny, nz = divisions
    ids = first_node + np.arange((nx + 1) * (ny + 1) * (nz + 1)).reshape(nz + 1, ny + 1, nx + 1)
    z, y, x = np.meshgrid(axes[2], axes[1], axes[0], indexing="ij")
    points = np.stack([x, y, z], axis=-1)
    if rng is not None:  # move inner nodes of the x axis: cells are no longer parallelepipeds
        inner = np.zeros(points.shape[:3], bool)
        inner[:, :, 1:-1] = True
        step = np.array(size) / np.array(divisions)
        points[inner] += rng.uniform(-shift, shift, (inner.sum(), 3)) * step
    cells = []
    for k in range(nz):
        for j in range(ny):
            for i in range(nx):
                cells.append(
                    [ids[k, j, i], ids[k, j, i + 1], ids[k, j + 1, i + 1], ids[k, j + 1, i],
                     ids[k + 1, j, i], ids[k + 1, j, i + 1], ids[k + 1, j + 1, i + 1],
                     ids[k + 1, j + 1, i]]
                )  # fmt: skip
    return ids, points, np.array(cells)


def _nodes(ids, points) -> list[str]:
    return [
        f"{n}, {x!r}, {y!r}, {z!r}"
        for n, (x, y, z) in zip(ids.ravel().tolist(), points.reshape(-1, 3).tolist())
    ]


def _elements(first, cells) -> list[str]:
    return [f"{first + e}, " + ", ".join(map(str, c)) for e, c in enumerate(cells.tolist())]


def cantilever_deck(
    element: str = "C3D8I", *, distorted: bool = False, pressure: float | None = None
) -> str:
    """A clamped beam 8 x 1 x 2 under a tip force in z (1 in total, on the 6 tip nodes).

    ``pressure``: also a ``*DLOAD`` pressure on the top faces (S2 of the upper layer).
    """
    rng = np.random.default_rng(7) if distorted else None
    ids, points, cells = _grid(1, (0, 0, 0), (10.0, 1.0, 1.0), (8, 1, 2), rng, 0.2)
    fixed, tip = ids[:, :, 0].ravel(), ids[:, :, -1].ravel()
    lines = ["*HEADING", f"Cantilever of {element}", "*NODE, NSET=NALL", *_nodes(ids, points)]
    lines += [f"*ELEMENT, TYPE={element}, ELSET=EALL", *_elements(1, cells)]
    lines += ["*NSET, NSET=FIX", ", ".join(map(str, fixed)), "*NSET, NSET=TIP"]
    lines += [", ".join(map(str, tip)), "*MATERIAL, NAME=STEEL", "*ELASTIC", f"{E}, {NU}"]
    lines += ["*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL", "*STEP", "*STATIC", "*BOUNDARY"]
    lines += ["FIX, 1, 3"]
    if pressure is not None:
        lines += ["*DLOAD", *[f"{e}, P2, {pressure!r}" for e in range(9, 17)]]
    lines += ["*CLOAD", f"TIP, 3, {1.0 / tip.size!r}"]
    lines += ["*NODE PRINT, NSET=NALL", "U", "*NODE PRINT, NSET=FIX, TOTALS=YES", "RF"]
    lines += ["*EL PRINT, ELSET=EALL", "S", "*NODE FILE", "U", "*EL FILE", "S", "*END STEP"]
    return "\n".join(lines) + "\n"


def contact_deck(element: str = "C3D8I") -> str:
    """A beam pressed at its ends onto a block: node-to-surface contact, LINEAR law."""
    block, block_points, block_cells = _grid(1, (0, 0, 0), (4.0, 1.0, 1.0), (4, 2, 2))
    beam, beam_points, beam_cells = _grid(101, (0.3, 0.25, 1.0), (3.0, 0.5, 0.5), (6, 1, 1))
    ends = np.concatenate([beam[-1, :, 0], beam[-1, :, -1]])
    lines = ["*HEADING", f"A {element} beam on a {element} block", "*NODE, NSET=NALL"]
    lines += [*_nodes(block, block_points), *_nodes(beam, beam_points)]
    lines += [f"*ELEMENT, TYPE={element}, ELSET=BLOCK", *_elements(1, block_cells)]
    lines += [f"*ELEMENT, TYPE={element}, ELSET=BEAM", *_elements(101, beam_cells)]
    lines += ["*ELSET, ELSET=EALL", "BLOCK, BEAM", "*NSET, NSET=FIX"]
    lines += [", ".join(map(str, block[0].ravel())), "*NSET, NSET=ENDS"]
    lines += [", ".join(map(str, ends)), "*MATERIAL, NAME=STEEL", "*ELASTIC", f"{E}, {NU}"]
    lines += ["*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL"]
    top = [101 + e for e in range(6)]  # the beam's cells: their bottom faces are S1
    block_top = [1 + e for e in range(8, 16)]  # the block's upper layer: top faces S2
    lines += ["*SURFACE, NAME=SLAVE", *[f"{e}, S1" for e in top]]
    lines += ["*SURFACE, NAME=MASTER", *[f"{e}, S2" for e in block_top]]
    lines += ["*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE", "SLAVE, MASTER"]
    lines += ["*SURFACE INTERACTION, NAME=SI", "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR"]
    lines += ["1.0e6, 1.0, 1.0e-3", "*STEP", "*STATIC", "0.5, 1.0", "*BOUNDARY", "FIX, 1, 3"]
    lines += ["ENDS, 1, 2", "ENDS, 3, 3, -0.002"]
    lines += ["*NODE PRINT, NSET=NALL", "U", "*NODE PRINT, NSET=FIX, TOTALS=YES", "RF"]
    lines += ["*NODE PRINT, NSET=ENDS, TOTALS=YES", "RF", "*EL PRINT, ELSET=EALL", "S"]
    lines += ["*CONTACT PRINT", "CDIS, CSTR, CELS", "*NODE FILE", "U", "*EL FILE", "S"]
    lines += ["*END STEP"]
    return "\n".join(lines) + "\n"


def write_deck(directory: Path, name: str, text: str) -> Path:
    """Write ``text`` as ``directory/name.inp``; its path."""
    path = Path(directory) / f"{name}.inp"
    path.write_text(text)
    return path
