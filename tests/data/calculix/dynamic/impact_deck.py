"""A CalculiX deck of a block moving onto a base (implicit ``*DYNAMIC``, C3D8, coarse).

The base ``[0, 2]^2 x [-1, 0]`` (3 x 3 x 1 elements) is clamped at its bottom; the block
``[0.5, 1.5]^2 x [gap, gap + 1]`` (2 x 2 x 2 elements) starts with the velocity ``-speed`` along z
(``*INITIAL CONDITIONS, TYPE=VELOCITY``), hits the base, and bounces off. Its bottom face is the
slave surface, the top of the base the master (LINEAR law with ccx's defaults). Pure Python: no
dolfinx, so ccx and the deck runner read the very same file.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["write_impact_deck"]

E, NU, RHO = 1000.0, 0.3, 1.0


def _box(lo, hi, n, first_node, first_element):
    """Nodes (id -> xyz) and C3D8 elements (id -> 8 node ids) of a structured box."""
    axes = [np.linspace(lo[i], hi[i], n[i] + 1) for i in range(3)]
    ids = {}
    nodes = {}
    nid = first_node
    for k, z in enumerate(axes[2]):
        for j, y in enumerate(axes[1]):
            for i, x in enumerate(axes[0]):
                ids[i, j, k] = nid
                nodes[nid] = (x, y, z)
                nid += 1
    elements = {}
    eid = first_element
    for k in range(n[2]):
        for j in range(n[1]):
            for i in range(n[0]):
                c = [
                    ids[i, j, k], ids[i + 1, j, k], ids[i + 1, j + 1, k], ids[i, j + 1, k],
                    ids[i, j, k + 1], ids[i + 1, j, k + 1], ids[i + 1, j + 1, k + 1],
                    ids[i, j + 1, k + 1],
                ]  # fmt: skip
                elements[eid] = (c, (k == 0, k == n[2] - 1))
                eid += 1
    return ids, nodes, elements


def write_impact_deck(
    directory: str | Path,
    name: str = "impact",
    *,
    gap: float = 0.01,
    speed: float = 1.0,
    increment: float = 5e-4,
    period: float = 0.08,
    alpha: float | None = None,
    direct: bool = True,
    tight: bool = True,
    load: float = 0.0,
    damping: float | None = None,
    tangent_fraction: float | None = None,
) -> Path:
    """Write ``directory/name.inp`` and return its path.

    Args:
        gap: Initial clearance between block and base (negative: initial overlap).
        speed: Initial downward speed of the block.
        increment, period: ``*DYNAMIC`` time increment and step time.
        alpha: ``ALPHA`` parameter (None: ccx's default -0.05).
        direct: Fixed increments (``DIRECT``).
        tight: Field controls at round-off level, so that converged solutions are compared.
        load: A ``*CLOAD`` along z on every node of the block top (ccx applies it in full from
            the step start).
        damping: A ``*CONTACT DAMPING`` constant (None: no card).
        tangent_fraction: Its ``TANGENT FRACTION`` parameter (None: not given).
    """
    _, base_nodes, base_elements = _box((0, 0, -1), (2, 2, 0), (3, 3, 1), 1, 1)
    first_node = max(base_nodes) + 1
    first_element = max(base_elements) + 1
    _, block_nodes, block_elements = _box(
        (0.5, 0.5, gap), (1.5, 1.5, gap + 1), (2, 2, 2), first_node, first_element
    )
    lines = ["*HEADING", "block moving onto a base, implicit dynamics", "*NODE, NSET=NALL"]
    for nodes in (base_nodes, block_nodes):
        lines += [f"{i}, {x:.17g}, {y:.17g}, {z:.17g}" for i, (x, y, z) in nodes.items()]
    for label, elements in (("EBASE", base_elements), ("EBLOCK", block_elements)):
        lines.append(f"*ELEMENT, TYPE=C3D8, ELSET={label}")
        lines += [f"{e}, " + ", ".join(str(n) for n in c) for e, (c, _) in elements.items()]
    lines.append("*ELSET, ELSET=EALL\nEBASE, EBLOCK")
    bottom = sorted(i for i, (_, _, z) in base_nodes.items() if z == -1)
    block = sorted(block_nodes)
    top = sorted(i for i, (_, _, z) in block_nodes.items() if z == gap + 1)
    lines += ["*NSET, NSET=NBOTTOM", *(f"{i}," for i in bottom)]
    lines += ["*NSET, NSET=NBLOCK", *(f"{i}," for i in block)]
    lines += ["*NSET, NSET=NTOP", *(f"{i}," for i in top)]
    # C3D8 face S1 is nodes 1-2-3-4 (bottom, z-), S2 nodes 5-6-7-8 (top, z+)
    lines.append("*SURFACE, NAME=SLAVE")
    lines += [f"{e}, S1" for e, (_, (low, _)) in block_elements.items() if low]
    lines.append("*SURFACE, NAME=MASTER")
    lines += [f"{e}, S2" for e, (_, (_, high)) in base_elements.items() if high]
    lines += [
        "*MATERIAL, NAME=STEEL",
        "*ELASTIC",
        f"{E}, {NU}",
        "*DENSITY",
        f"{RHO}",
        "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL",
        "*SURFACE INTERACTION, NAME=SI",
        "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
    ]
    if damping is not None:
        fraction = "" if tangent_fraction is None else f", TANGENT FRACTION={tangent_fraction}"
        lines += [f"*CONTACT DAMPING{fraction}", f"{damping}"]
    lines += [
        "*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE",
        "SLAVE, MASTER",
        "*BOUNDARY",
        "NBOTTOM, 1, 3",
        "*INITIAL CONDITIONS, TYPE=VELOCITY",
        f"NBLOCK, 3, {-speed}",
        "*STEP, INC=10000",
        "*DYNAMIC" + (", DIRECT" if direct else "") + ("" if alpha is None else f", ALPHA={alpha}"),
        f"{increment}, {period}",
    ]
    if tight:
        lines += ["*CONTROLS, PARAMETERS=FIELD", "1e-10, 1e-8, , , 1e-10, 1e-5, 1e-8, 1e-12"]
    if load:
        lines += ["*CLOAD", f"NTOP, 3, {load}"]
    lines += [
        "*NODE PRINT, NSET=NALL",
        "U",
        "*CONTACT PRINT",
        "CDIS, CSTR, CELS",
        "*END STEP",
    ]
    path = Path(directory) / f"{name}.inp"
    path.write_text("\n".join(lines) + "\n")
    return path


if __name__ == "__main__":
    import sys

    write_impact_deck(sys.argv[1] if len(sys.argv) > 1 else ".")
