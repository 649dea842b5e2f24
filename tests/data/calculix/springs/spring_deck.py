"""A small spring deck for the deck runner's comparison with ccx 2.20 (docs/method.md §18.3).

Two C3D8 unit cubes, the first clamped at x = 0, the second 1 unit further along x and 0.3 along
y, held only by springs: five SPRINGA (four between the facing corners, inclined, and one from a
clamped node, whose force is in the reactions ``RF``), three SPRING1 in z to the ground and one
SPRING2 in y between the cubes; concentrated forces on the second cube.
``write_spring_deck(directory, name, nlgeom=..., nonlinear=...)`` writes ``name.inp``.
"""

from __future__ import annotations

from pathlib import Path

#: The corners of a unit cube in C3D8 order.
_CORNERS = [
    (0, 0, 0), (1, 0, 0), (1, 1, 0), (0, 1, 0), (0, 0, 1), (1, 0, 1), (1, 1, 1), (0, 1, 1),
]  # fmt: skip


def spring_deck(*, nlgeom: bool, nonlinear: bool, contact: bool = False) -> str:
    """The deck: SPRINGA constant 200, or a force-elongation table with ``nonlinear``.

    ``contact``: a contact pair between the cubes' facing sides that stays open (the loads pull the
    second cube away), which makes ccx iterate without NLGEOM too.
    """
    nodes = [(1 + i, float(x), float(y), float(z)) for i, (x, y, z) in enumerate(_CORNERS)]
    nodes += [(9 + i, 2.0 + x, 0.3 + y, float(z)) for i, (x, y, z) in enumerate(_CORNERS)]
    lines = ["*NODE, NSET=NALL", *(f"{n},{x!r},{y!r},{z!r}" for n, x, y, z in nodes)]
    lines += [
        "*ELEMENT, TYPE=C3D8, ELSET=EA", "1,1,2,3,4,5,6,7,8",
        "*ELEMENT, TYPE=C3D8, ELSET=EB", "2,9,10,11,12,13,14,15,16",
        "*ELEMENT, TYPE=SPRINGA, ELSET=ESA", "3,2,9", "4,3,12", "5,6,13", "6,7,16", "11,8,16",
        "*ELEMENT, TYPE=SPRING1, ELSET=ES1", "7,10", "8,11", "9,14",
        "*ELEMENT, TYPE=SPRING2, ELSET=ES2", "10,6,15",
        "*NSET, NSET=FIX", "1,4,5,8", "*BOUNDARY", "FIX,1,3",
        "*MATERIAL, NAME=EL", "*ELASTIC", "1000.,0.3",
        "*SOLID SECTION, ELSET=EA, MATERIAL=EL", "*SOLID SECTION, ELSET=EB, MATERIAL=EL",
    ]  # fmt: skip
    if nonlinear:
        lines += ["*SPRING, ELSET=ESA, NONLINEAR", "", "-50.,-1.", "0.,0.", "40.,0.1", "60.,1."]
    else:
        lines += ["*SPRING, ELSET=ESA", "", "200."]
    lines += ["*SPRING, ELSET=ES1", "3", "50.", "*SPRING, ELSET=ES2", "2,2", "80."]
    if contact:
        lines += [
            "*SURFACE, NAME=SB, TYPE=NODE", "9", "12", "13", "16", "*SURFACE, NAME=MA", "1,S4",
            "*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE", "SB, MA",
            "*SURFACE INTERACTION, NAME=SI", "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
            "1.e5",
        ]  # fmt: skip
    lines += ["*STEP, NLGEOM" if nlgeom else "*STEP", "*STATIC"]
    lines += ["0.25,1."] if nlgeom else []
    lines += ["*CLOAD", "15,1,4.", "11,2,-3.", "14,3,2.", "*NODE PRINT, NSET=NALL", "U"]
    lines += ["*NODE PRINT, NSET=FIX, TOTALS=YES", "RF"]
    lines += ["*END STEP"]
    return "\n".join(lines) + "\n"


def write_spring_deck(
    directory: Path, name: str, *, nlgeom: bool, nonlinear: bool, contact: bool = False
) -> Path:
    """Write ``name.inp`` into ``directory``; returns its path."""
    path = Path(directory) / f"{name}.inp"
    path.write_text(spring_deck(nlgeom=nlgeom, nonlinear=nonlinear, contact=contact))
    return path
