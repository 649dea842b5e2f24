"""Small decks with S8 shells for the tests against ccx 2.20 (docs/method.md §24).

``plate_deck``: two S8 elements (4 x 1, thickness 0.2) with one edge held and the far corners
pulled up by a prescribed displacement; ``cylinder_deck``: two curved S8 elements on a cylinder
(normals averaged across the shared edge, an offset); ``block_deck``: a C3D20 cube pressed onto a
fully fixed S8 floor through a node-to-surface pair on the floor's SPOS face.
"""

from __future__ import annotations

import math
from pathlib import Path

PLATE = """*NODE, NSET=NALL
1, 0, 0, 0
2, 2, 0, 0
3, 2, 1, 0
4, 0, 1, 0
5, 1, 0, 0
6, 2, 0.5, 0
7, 1, 1, 0
8, 0, 0.5, 0
9, 4, 0, 0
10, 4, 1, 0
11, 3, 0, 0
12, 4, 0.5, 0
13, 3, 1, 0
*ELEMENT, TYPE=S8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
2, 2, 9, 10, 3, 11, 12, 13, 6
*NSET, NSET=FIX
1, 4, 8
"""

#: Plate variants: the model's *BOUNDARY lines, the OFFSET and the step's NLGEOM.
PLATE_VARIANTS = {
    "clamped": ("FIX, 1, 6\n", "", False),  # dofs 1-6 of the edge fixed
    "hinged": ("FIX, 1, 3\n2, 1, 2\n", ", OFFSET=0.3", False),  # translations only, offset
    "supported": ("FIX, 1, 3\n2, 3, 3\n3, 3, 3\n", "", False),  # a middle line support
    "clamped-nlgeom": ("FIX, 1, 6\n", "", True),
}


def plate_deck(variant: str, *, file_output: bool = False) -> str:
    """The text of the plate deck ``variant`` (``PLATE_VARIANTS``)."""
    boundary, offset, nlgeom = PLATE_VARIANTS[variant]
    lift = 0.5 if nlgeom else 0.01
    files = "*NODE FILE, OUTPUT=3D\nU\n" if file_output else ""
    return (
        PLATE
        + f"*BOUNDARY\n{boundary}*MATERIAL, NAME=M\n*ELASTIC\n1000.0, 0.3\n"
        + f"*SHELL SECTION, ELSET=EALL, MATERIAL=M{offset}\n0.2\n"
        + f"*STEP{', NLGEOM' if nlgeom else ''}\n*STATIC\n*BOUNDARY\n9, 3, 3, {lift}\n"
        + f"10, 3, 3, {lift}\n*NODE PRINT, NSET=NALL\nU\n{files}*END STEP\n"
    )


def cylinder_deck(*, file_output: bool = False) -> str:
    """Two S8 elements on a cylinder of radius 10 (0-10 and 10-25 degrees), offset -0.25."""
    ids: dict[tuple[float, int], int] = {}

    def node(angle: float, y: int) -> int:
        return ids.setdefault((angle, y), len(ids) + 1)

    elements = []
    for a, b in ((0.0, 10.0), (10.0, 25.0)):
        m = (a + b) / 2
        elements.append(
            [node(a, 0), node(b, 0), node(b, 2), node(a, 2), node(m, 0), node(b, 1), node(m, 2),
             node(a, 1)]
        )  # fmt: skip
    lines = ["*NODE, NSET=NALL"]
    for (angle, y), k in ids.items():
        x, z = 10 * math.sin(math.radians(angle)), 10 * math.cos(math.radians(angle))
        lines.append(f"{k}, {x:.12f}, {y}, {z:.12f}")
    lines.append("*ELEMENT, TYPE=S8, ELSET=EALL")
    lines += [f"{e + 1}, " + ", ".join(map(str, nodes)) for e, nodes in enumerate(elements)]
    lines += [
        "*NSET, NSET=FIX", f"{node(0.0, 0)}, {node(0.0, 1)}, {node(0.0, 2)}",
        "*BOUNDARY", "FIX, 1, 3", "*MATERIAL, NAME=M", "*ELASTIC", "1000., 0.3",
        "*SHELL SECTION, ELSET=EALL, MATERIAL=M, OFFSET=-0.25", "0.3", "*STEP", "*STATIC",
        "*BOUNDARY", f"{node(25.0, 0)}, 1, 3, 0.01", f"{node(25.0, 2)}, 1, 3, 0.01",
        "*NODE PRINT, NSET=NALL", "U",
    ]  # fmt: skip
    if file_output:
        lines += ["*NODE FILE, OUTPUT=3D", "U"]
    return "\n".join([*lines, "*END STEP"]) + "\n"


def block_deck(law: str = "LINEAR") -> str:
    """A C3D20 unit cube pressed 0.01 onto a fully fixed S8 floor (4 x 4, thickness 0.1).

    ``law``: ``LINEAR`` (slope 1e4) or ``EXPONENTIAL`` (c0 0.001, p0 10).
    """
    corners = [
        (0, 0, 0),
        (1, 0, 0),
        (1, 1, 0),
        (0, 1, 0),
        (0, 0, 1),
        (1, 0, 1),
        (1, 1, 1),
        (0, 1, 1),
    ]
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5),
             (2, 6), (3, 7)]  # fmt: skip
    points = corners + [
        tuple((p + q) / 2 for p, q in zip(corners[i], corners[j])) for i, j in edges
    ]
    lines = ["*NODE, NSET=NBLOCK"]
    lines += [
        f"{k + 1}, {x - 0.4:.6f}, {y - 0.45:.6f}, {z + 0.05:.6f}"
        for k, (x, y, z) in enumerate(points)
    ]
    lines += ["*ELEMENT, TYPE=C3D20, ELSET=EBLOCK", "1, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10,",
              "11, 12, 13, 14, 15, 16, 17, 18, 19, 20", "*NODE, NSET=NFLOOR"]  # fmt: skip
    floor = [(-2, -2), (2, -2), (2, 2), (-2, 2), (0, -2), (2, 0), (0, 2), (-2, 0)]
    lines += [f"{101 + k}, {x}, {y}, 0.0" for k, (x, y) in enumerate(floor)]
    behavior = (
        ["*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR", "1.0e4"]
        if law == "LINEAR"
        else ["*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=EXPONENTIAL", "0.001, 10.0"]
    )
    lines += [
        "*ELEMENT, TYPE=S8, ELSET=EFLOOR", "101, 101, 102, 103, 104, 105, 106, 107, 108",
        "*NSET, NSET=NBOT", "1, 2, 3, 4, 9, 10, 11, 12", "*NSET, NSET=NTOP",
        "5, 6, 7, 8, 13, 14, 15, 16", "*BOUNDARY", "NFLOOR, 1, 6", "NTOP, 1, 2",
        "*MATERIAL, NAME=M", "*ELASTIC", "1000.0, 0.3", "*SOLID SECTION, ELSET=EBLOCK, MATERIAL=M",
        "*SHELL SECTION, ELSET=EFLOOR, MATERIAL=M", "0.1", "*SURFACE, NAME=FLOOR, TYPE=ELEMENT",
        "EFLOOR, SPOS", "*SURFACE, NAME=BOT, TYPE=NODE", "NBOT",
        "*CONTACT PAIR, INTERACTION=CI, TYPE=NODE TO SURFACE", "BOT, FLOOR",
        "*SURFACE INTERACTION, NAME=CI", *behavior, "*STEP", "*STATIC", "*BOUNDARY",
        "NTOP, 3, 3, -0.01", "*NODE PRINT, NSET=NBLOCK", "U", "*CONTACT PRINT", "CDIS, CSTR",
        "*END STEP",
    ]  # fmt: skip
    return "\n".join(lines) + "\n"


def write_deck(directory: Path, job: str, text: str) -> Path:
    """Write ``text`` as ``directory/job.inp``."""
    path = Path(directory) / f"{job}.inp"
    path.write_text(text)
    return path


def s4_block_deck() -> str:
    """A C3D8I unit cube pressed 0.01 onto a fully fixed 2 x 2 S4 floor (thickness 0.1, LINEAR)."""
    corners = [
        (0, 0, 0),
        (1, 0, 0),
        (1, 1, 0),
        (0, 1, 0),
        (0, 0, 1),
        (1, 0, 1),
        (1, 1, 1),
        (0, 1, 1),
    ]
    lines = ["*NODE, NSET=NBLOCK"]
    lines += [
        f"{k + 1}, {x - 0.4:.6f}, {y - 0.45:.6f}, {z + 0.05:.6f}"
        for k, (x, y, z) in enumerate(corners)
    ]
    lines += [
        "*ELEMENT, TYPE=C3D8I, ELSET=EBLOCK",
        "1, 1, 2, 3, 4, 5, 6, 7, 8",
        "*NODE, NSET=NFLOOR",
    ]
    grid = [(x, y) for y in (-2, 0, 2) for x in (-2, 0, 2)]
    lines += [f"{101 + k}, {x}, {y}, 0.0" for k, (x, y) in enumerate(grid)]
    lines += ["*ELEMENT, TYPE=S4, ELSET=EFLOOR"]
    for e, (i, j) in enumerate(((0, 0), (1, 0), (0, 1), (1, 1))):
        n = 101 + 3 * j + i
        lines.append(f"{101 + e}, {n}, {n + 1}, {n + 4}, {n + 3}")
    lines += [
        "*NSET, NSET=NBOT", "1, 2, 3, 4", "*NSET, NSET=NTOP", "5, 6, 7, 8", "*BOUNDARY",
        "NFLOOR, 1, 6", "NTOP, 1, 2", "*MATERIAL, NAME=M", "*ELASTIC", "1000.0, 0.3",
        "*SOLID SECTION, ELSET=EBLOCK, MATERIAL=M", "*SHELL SECTION, ELSET=EFLOOR, MATERIAL=M",
        "0.1", "*SURFACE, NAME=FLOOR, TYPE=ELEMENT", "EFLOOR, SPOS",
        "*SURFACE, NAME=BOT, TYPE=NODE", "NBOT",
        "*CONTACT PAIR, INTERACTION=CI, TYPE=NODE TO SURFACE", "BOT, FLOOR",
        "*SURFACE INTERACTION, NAME=CI", "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
        "1.0e4",
        "*STEP", "*STATIC", "*BOUNDARY", "NTOP, 3, 3, -0.01", "*NODE PRINT, NSET=NBLOCK", "U",
        "*CONTACT PRINT", "CDIS, CSTR", "*END STEP",
    ]  # fmt: skip
    return "\n".join(lines) + "\n"


def s4_plate_deck() -> str:
    """Two S4 elements (4 x 1, thickness 0.2, OFFSET=0.2), one edge fixed, ``.frd`` in 3D."""
    return (
        "*NODE, NSET=NALL\n1, 0, 0, 0\n2, 2, 0, 0\n3, 2, 1, 0\n4, 0, 1, 0\n5, 4, 0, 0\n"
        "6, 4, 1, 0.5\n*ELEMENT, TYPE=S4, ELSET=EALL\n1, 1, 2, 3, 4\n2, 2, 5, 6, 3\n"
        "*NSET, NSET=FIX\n1, 4\n*BOUNDARY\nFIX, 1, 3\n*MATERIAL, NAME=M\n*ELASTIC\n1000.0, 0.3\n"
        "*SHELL SECTION, ELSET=EALL, MATERIAL=M, OFFSET=0.2\n0.2\n*STEP\n*STATIC\n"
        "*NODE FILE, OUTPUT=3D\nU\n*END STEP\n"
    )


def flying_block_deck() -> str:
    """``block_deck`` in a ``*DYNAMIC`` step without contact: the C3D20 cube flies at vz = -2.

    The cube starts 0.002 above the fixed S8 floor and moves 0.001 in 0.0005 (ccx's increments
    grow from 2e-5); its displacement is ``v t`` at every node.
    """
    text = block_deck("LINEAR")
    head = text.split("*SURFACE, NAME=FLOOR", 1)[0]
    lines = head.split("\n")
    start = lines.index("*NODE, NSET=NBLOCK") + 1
    for k in range(start, start + 20):
        number, x, y, z = lines[k].split(",")
        lines[k] = f"{number},{x},{y}, {float(z) + 0.002:.6f}"
    head = "\n".join(lines).replace("NTOP, 1, 2\n", "")
    head = head.replace("*ELASTIC\n1000.0, 0.3\n", "*ELASTIC\n1000.0, 0.3\n*DENSITY\n2.5e-9\n")
    return head + (
        "*INITIAL CONDITIONS, TYPE=VELOCITY\nNBLOCK, 3, -2.0\n*STEP, NLGEOM, INC=1000\n"
        "*DYNAMIC\n0.00002, 0.0005\n*NODE PRINT, NSET=NBLOCK\nU\n*END STEP\n"
    )
