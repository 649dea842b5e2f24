"""The wedge block decks of the C3D6 tests (docs/method.md §30, §35): split hexahedra.

Every other hexahedron can stay a C3D8 beside the wedges (``mixed``).
"""

from __future__ import annotations

import numpy as np

__all__ = ["wedge_block"]


def wedge_block(
    n: int = 2, layers: int = 2, element: str = "C3D6", surfaces: bool = True, mixed: bool = False
) -> tuple[str, list[list[int]]]:
    """The wedge block deck (``element`` C3D6, or C3D8 with nodes 1,2,3,3,4,5,6,6) and wedges.

    ``surfaces``: one surface per wedge face label S1..S5 (some inside the block). ``mixed``:
    every other hexahedron stays one C3D8 (numbered after the wedges; without surfaces).
    """

    def nid(i: int, j: int, k: int) -> int:
        return 1 + i + (n + 1) * (j + (n + 1) * k)

    lines = ["*NODE, NSET=NALL"]
    for k in range(layers + 1):
        for j in range(n + 1):
            for i in range(n + 1):
                x = i / n + (0.05 * np.sin(3 * j / n + k / layers) if 0 < i < n else 0.0)
                lines.append(f"{nid(i, j, k)}, {x:.6f}, {j / n:.6f}, {k / layers:.6f}")
    wedges = []
    hexes = []
    for k in range(layers):
        for j in range(n):
            for i in range(n):
                a, b, c, d = nid(i, j, k), nid(i + 1, j, k), nid(i + 1, j + 1, k), nid(i, j + 1, k)
                A, B, C, D = (nid(i, j, k + 1), nid(i + 1, j, k + 1), nid(i + 1, j + 1, k + 1),
                              nid(i, j + 1, k + 1))  # fmt: skip
                if mixed and (i + j + k) % 2 == 1:
                    hexes.append([a, b, c, d, A, B, C, D])
                elif (i + j) % 2 == 0:
                    wedges += [[a, b, c, A, B, C], [a, c, d, A, C, D]]
                else:
                    wedges += [[a, b, d, A, B, D], [b, c, d, B, C, D]]
    lines.append(f"*ELEMENT, TYPE={element}, ELSET=EALL")
    for e, w in enumerate(wedges, start=1):
        row = w if element == "C3D6" else [w[0], w[1], w[2], w[2], w[3], w[4], w[5], w[5]]
        lines.append(", ".join(map(str, [e, *row])))
    if hexes:
        lines.append("*ELEMENT, TYPE=C3D8, ELSET=EALL")
        lines += [", ".join(map(str, [len(wedges) + e, *h])) for e, h in enumerate(hexes, 1)]
    bottom = [nid(i, j, 0) for j in range(n + 1) for i in range(n + 1)]
    top = [nid(i, j, layers) for j in range(n + 1) for i in range(n + 1)]
    lines += ["*NSET, NSET=BOT", ", ".join(map(str, bottom)), "*NSET, NSET=TOP"]
    lines += [", ".join(map(str, top))]
    if surfaces:
        lines += [f"*SURFACE, NAME=S{k}\n{e}, S{k}" for k, e in zip(range(1, 6), (1, 3, 5, 6, 8))]
    lines.append("""*MATERIAL, NAME=EL
*ELASTIC
210000., 0.3
*SOLID SECTION, ELSET=EALL, MATERIAL=EL
*BOUNDARY
BOT, 1, 3
*STEP
*STATIC
*BOUNDARY
TOP, 3, 3, -0.01
TOP, 1, 1, 0.02
TOP, 2, 2, 0.0
*NODE PRINT, NSET=NALL
U
*NODE PRINT, NSET=TOP, TOTALS=ONLY
RF
*END STEP""")
    return "\n".join(lines) + "\n", wedges
