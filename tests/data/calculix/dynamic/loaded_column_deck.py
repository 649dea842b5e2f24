"""A ``*DYNAMIC`` deck with a load from the step start, for the tests against ccx 2.20.

docs/method.md §12.7: a column of two C3D8 cubes (1 x 1 x 2) held vertically at its base and
loaded downwards at its top (``*CLOAD``) or by its weight (``*DLOAD ... GRAV``) from the start of
the step; no contact. Its lowest period is about 0.2, so that increments of 0.03 resolve it
coarsely and ccx's initial acceleration (from an alpha-method increment of a tenth of the initial
increment) differs visibly from the exact one (8.5e-4 of the largest displacement).
"""

from __future__ import annotations

#: Nodes of the column: four corners at z = 0, 1, 2.
_CORNERS = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]


def loaded_column_deck(
    load: str = "CLOAD",
    *,
    alpha: float | None = None,
    direct: bool = True,
    increment: float = 0.03,
    period: float = 0.3,
    velocity: bool = False,
    nlgeom: bool = False,
    time_points: str | None = None,
) -> str:
    """The deck's text.

    Args:
        load: ``"CLOAD"`` (-1 in z spread over the four top nodes) or ``"GRAV"`` (g = 2 downwards).
        alpha: ``*DYNAMIC``'s ALPHA; None: ccx's default.
        direct: ``*DYNAMIC, DIRECT`` (fixed increments) or automatic increments.
        increment, period: The initial increment and the step time.
        velocity: Give the top nodes an initial upwards velocity that stretches the column.
        nlgeom: ``*STEP, NLGEOM``.
        time_points: A ``*TIME POINTS`` data line for the node print (needs automatic increments).
    """
    lines = ["*NODE, NSET=NALL"]
    lines += [
        f"{4 * level + k + 1}, {x}, {y}, {float(level)}"
        for level in range(3)
        for k, (x, y) in enumerate(_CORNERS)
    ]
    lines += [
        "*ELEMENT, TYPE=C3D8, ELSET=EALL",
        "1, 1, 2, 3, 4, 5, 6, 7, 8",
        "2, 5, 6, 7, 8, 9, 10, 11, 12",
        "*NSET, NSET=NBOT", "1, 2, 3, 4",
        "*NSET, NSET=NTOP", "9, 10, 11, 12",
        "*BOUNDARY", "NBOT, 3, 3", "1, 1, 2", "2, 2, 2",
        "*MATERIAL, NAME=M", "*ELASTIC", "1000.0, 0.3", "*DENSITY", "1.0",
        "*SOLID SECTION, ELSET=EALL, MATERIAL=M",
    ]  # fmt: skip
    if velocity:
        lines += ["*INITIAL CONDITIONS, TYPE=VELOCITY", "9, 3, 0.05", "10, 3, 0.05"]
        lines += ["11, 3, 0.1", "12, 3, 0.1"]
    if time_points is not None:
        lines += ["*TIME POINTS, NAME=T1", time_points]
    dynamic = "*DYNAMIC" + (", DIRECT" if direct else "")
    dynamic += f", ALPHA={alpha}" if alpha is not None else ""
    lines += [
        "*STEP" + (", NLGEOM" if nlgeom else "") + ", INC=1000",
        dynamic,
        f"{increment}, {period}",
        "*CONTROLS, PARAMETERS=FIELD",
        "1e-12, 1e-12, 1e-12, 1e-12, 1e-12",
    ]
    if load == "CLOAD":
        lines += ["*CLOAD", "NTOP, 3, -0.25"]
    elif load == "GRAV":
        lines += ["*DLOAD", "EALL, GRAV, 2.0, 0.0, 0.0, -1.0"]
    else:
        raise ValueError(f"loaded_column_deck: load must be CLOAD or GRAV, got {load!r}")
    lines += ["*NODE PRINT, NSET=NALL" + (", TIME POINTS=T1" if time_points else ""), "U"]
    lines += ["*END STEP"]
    return "\n".join(lines) + "\n"
