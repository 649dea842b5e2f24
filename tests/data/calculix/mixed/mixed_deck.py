"""Small decks that mix C3D8 with C3D20/C3D20R elements, for the tests against ccx 2.20.

docs/method.md §27. ``cube_on_floor_deck``: a distorted C3D8 cube pressed 0.01 onto a floor
that is either a fully fixed S8 shell (ccx expands it into a C3D20 brick: ball's configuration)
or a C3D20R block fixed at its bottom; the cube's bottom corners are a node slave surface on
the floor's top face. ``falling_cube_deck``: the C3D8 cube in a ``*DYNAMIC`` step with an
initial velocity, ``GRAV`` and ``*TIME POINTS``, next to the fixed S8 floor (ball in small).
"""

from __future__ import annotations

#: The C3D8 cube: unit cube over (-0.4, -0.45) with its top corners moved (distorted, so
#: that the integration rule matters); bottom at z = 0.05 above the floor's top at 0.05.
_CUBE = [
    (0.0, 0.0, 0.0),
    (1.0, 0.0, 0.0),
    (1.0, 1.0, 0.0),
    (0.0, 1.0, 0.0),
    (0.1, -0.05, 1.0),
    (1.05, 0.1, 1.2),
    (0.95, 1.1, 0.9),
    (-0.1, 0.9, 1.1),
]

_FLOOR = [(-2, -2), (2, -2), (2, 2), (-2, 2), (0, -2), (2, 0), (0, 2), (-2, 0)]


def _cube_lines(z0: float) -> list[str]:
    lines = ["*NODE, NSET=NCUBE"]
    lines += [f"{k + 1}, {x - 0.4:.6f}, {y - 0.45:.6f}, {z + z0:.6f}" for k, (x, y, z) in
              enumerate(_CUBE)]  # fmt: skip
    return [*lines, "*ELEMENT, TYPE=C3D8, ELSET=ECUBE", "1, 1, 2, 3, 4, 5, 6, 7, 8"]


def _s8_floor() -> list[str]:
    lines = ["*NODE, NSET=NFLOOR"]
    lines += [f"{101 + k}, {x}, {y}, 0.0" for k, (x, y) in enumerate(_FLOOR)]
    return [
        *lines,
        "*ELEMENT, TYPE=S8, ELSET=EFLOOR", "101, 101, 102, 103, 104, 105, 106, 107, 108",
        "*BOUNDARY", "NFLOOR, 1, 6",
    ]  # fmt: skip


def _c3d20r_floor() -> list[str]:
    """A 4 x 4 x 0.5 C3D20R block with its top at z = 0.05, fixed at the bottom."""
    corners = [(-2, -2, -0.45), (2, -2, -0.45), (2, 2, -0.45), (-2, 2, -0.45),
               (-2, -2, 0.05), (2, -2, 0.05), (2, 2, 0.05), (-2, 2, 0.05)]  # fmt: skip
    edges = [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5),
             (2, 6), (3, 7)]  # fmt: skip
    points = corners + [
        tuple((p + q) / 2 for p, q in zip(corners[i], corners[j])) for i, j in edges
    ]
    lines = ["*NODE, NSET=NFLOOR"]
    lines += [f"{101 + k}, {x}, {y}, {z}" for k, (x, y, z) in enumerate(points)]
    return [
        *lines,
        "*ELEMENT, TYPE=C3D20R, ELSET=EFLOOR",
        "101, " + ", ".join(str(101 + k) for k in range(15)) + ",",
        ", ".join(str(101 + k) for k in range(15, 20)),
        "*NSET, NSET=NBASE", "101, 102, 103, 104, 109, 110, 111, 112",
        "*BOUNDARY", "NBASE, 1, 3",
    ]  # fmt: skip


def _common(floor: str, face: str) -> list[str]:
    section = (
        ["*SHELL SECTION, ELSET=EFLOOR, MATERIAL=M", "0.1"]
        if floor == "S8"
        else ["*SOLID SECTION, ELSET=EFLOOR, MATERIAL=M"]
    )
    return [
        "*NSET, NSET=NBOT", "1, 2, 3, 4", "*NSET, NSET=NTOP", "5, 6, 7, 8",
        "*MATERIAL, NAME=M", "*ELASTIC", "1000.0, 0.3", "*DENSITY", "2.5e-9",
        "*SOLID SECTION, ELSET=ECUBE, MATERIAL=M", *section,
        "*SURFACE, NAME=FLOOR, TYPE=ELEMENT", f"EFLOOR, {face}",
        "*SURFACE, NAME=BOT, TYPE=NODE", "NBOT",
        "*CONTACT PAIR, INTERACTION=CI, TYPE=NODE TO SURFACE", "BOT, FLOOR",
        "*SURFACE INTERACTION, NAME=CI", "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
        "1.0e4",
    ]  # fmt: skip


def cube_on_floor_deck(floor: str = "S8") -> str:
    """The C3D8 cube's top pressed down 0.01 (and held sideways) onto the ``floor``.

    ``floor``: ``S8`` (a fully fixed shell, a C3D20 brick in ccx) or ``C3D20R`` (a block).
    """
    if floor == "S8":
        lines = _cube_lines(0.05) + _s8_floor() + _common("S8", "SPOS")
    else:
        lines = _cube_lines(0.05) + _c3d20r_floor() + _common("C3D20R", "S2")
    lines += [
        "*BOUNDARY", "NTOP, 1, 2", "*STEP", "*STATIC", "*BOUNDARY", "NTOP, 3, 3, -0.01",
        "*NODE PRINT, NSET=NCUBE", "U", "*NODE PRINT, NSET=NFLOOR", "U", "*CONTACT PRINT",
        "CDIS, CSTR", "*END STEP",
    ]  # fmt: skip
    return "\n".join(lines) + "\n"


def falling_cube_deck() -> str:
    """ball in small: the C3D8 cube 0.2 above the S8 floor, thrown with vx = 100 under GRAV.

    ``*DYNAMIC`` with NLGEOM, increments of 3e-4 over 1e-3 and ``*TIME POINTS`` every 2.5e-4
    (ccx shortens the increments to land on them); no contact is reached.
    """
    lines = _cube_lines(0.25) + _s8_floor() + _common("S8", "SPOS")
    lines += [
        "*TIME POINTS, NAME=T, GENERATE", "0.0, 0.001, 0.00025",
        "*INITIAL CONDITIONS, TYPE=VELOCITY", "NCUBE, 1, 100.0",
        "*STEP, NLGEOM, INC=1000", "*DYNAMIC", "0.0003, 0.001, 1e-9, 0.0003",
        "*DLOAD", "ECUBE, GRAV, 9810.0, 0.0, 0.0, -1.0",
        "*NODE PRINT, NSET=NCUBE, TIME POINTS=T", "U", "*END STEP",
    ]  # fmt: skip
    return "\n".join(lines) + "\n"


def spinning_cube_deck(floor: bool = True) -> str:
    """The distorted C3D8 cube thrown spinning (no load), beside the S8 floor or alone.

    Nodal initial velocities of a rotation about z (0.5) plus a shear; ``*DYNAMIC, DIRECT``
    with NLGEOM, 10 increments of 0.02. The motion depends on the mass matrix: ccx's C3D8 mass
    is integrated with the element's 2x2x2 Gauss points (docs/method.md §27.4).
    """
    lines = _cube_lines(0.05) + (_s8_floor() if floor else [])
    lines += [
        "*MATERIAL, NAME=M", "*ELASTIC", "1000.0, 0.3", "*DENSITY", "1.0",
        "*SOLID SECTION, ELSET=ECUBE, MATERIAL=M",
    ]  # fmt: skip
    if floor:
        lines += ["*SHELL SECTION, ELSET=EFLOOR, MATERIAL=M", "0.1"]
    lines.append("*INITIAL CONDITIONS, TYPE=VELOCITY")
    for k, (x, y, z) in enumerate(_CUBE):
        x, y = x - 0.4, y - 0.45
        lines += [f"{k + 1}, 1, {-0.5 * y + 0.3 * z:.6f}", f"{k + 1}, 2, {0.5 * x:.6f}",
                  f"{k + 1}, 3, {0.2 * x * y:.6f}"]  # fmt: skip
    lines += [
        "*STEP, NLGEOM, INC=100", "*DYNAMIC, DIRECT", "0.02, 0.2", "*NODE PRINT, NSET=NCUBE",
        "U", "*END STEP",
    ]  # fmt: skip
    return "\n".join(lines) + "\n"
