"""Files of CalculiX's test suite (``calculix-ccx-test``): gzipped (Debian 12) or not (13, sid)."""

from __future__ import annotations

import gzip

from .decks import CCX_TESTS


def suite_file_exists(name: str) -> bool:
    """True if ``name`` (e.g. ``contact5.inp``) is installed, gzipped or not."""
    return (CCX_TESTS / name).exists() or (CCX_TESTS / f"{name}.gz").exists()


def suite_text(name: str) -> str:
    """The text of ``name`` (e.g. ``contact5.dat.ref``), gzipped (Debian 12) or not."""
    plain = CCX_TESTS / name
    if plain.exists():
        return plain.read_text()
    return gzip.decompress((CCX_TESTS / f"{name}.gz").read_bytes()).decode()


def node_to_surface_suite_deck(name: str) -> bool:
    """True if the installed ``name`` deck is the node-to-surface one (Debian 12's 2.20 suite).

    Debian 13's and sid's packages ship another contact5 (``TYPE=SURFACE TO SURFACE``).
    """
    return suite_file_exists(f"{name}.inp") and "TYPE=NODE TO SURFACE" in suite_text(f"{name}.inp")


def two_beams_deck(
    procedure: str, *, pair: bool = True, modes: int = 10, frequency: int = 1
) -> str:
    """Two C3D8 cantilevers (1 x 1 x 8, 2 x 2 x 8 cells) 0.5 apart along y, the upper one's tip
    loaded towards the lower one; a node-to-surface pair between them (EXPONENTIAL), a
    ``*FREQUENCY, STORAGE=YES`` step, then ``procedure`` (the ``*MODAL DYNAMIC`` card and its data
    line) with ``*MODAL DAMPING, RAYLEIGH`` (alpha 15000) and ``*NODE PRINT`` U, V.
    """
    lines = ["*NODE, NSET=NALL"]
    index = {}
    for beam, y0 in enumerate((0.0, 1.5)):
        for k in range(9):
            for j in range(3):
                for i in range(3):
                    number = len(index) + 1
                    index[beam, i, j, k] = number
                    lines.append(f"{number}, {0.5 * i}, {y0 + 0.5 * j}, {1.0 * k}")
    lines.append("*ELEMENT, TYPE=C3D8, ELSET=EALL")
    element, lower_top = 0, []
    for beam in (0, 1):
        for k in range(8):
            for j in range(2):
                for i in range(2):
                    element += 1
                    n = [index[beam, i + a, j + b, k + c] for c, b, a in
                         ((0, 0, 0), (0, 0, 1), (0, 1, 1), (0, 1, 0),
                          (1, 0, 0), (1, 0, 1), (1, 1, 1), (1, 1, 0))]  # fmt: skip
                    lines.append(f"{element}, " + ", ".join(map(str, n)))
                    if beam == 0 and j == 1:
                        lower_top.append(element)  # face S5 (nodes 3, 7, 8, 4) at y = 1
    fixed = [index[b, i, j, 0] for b in (0, 1) for j in range(3) for i in range(3)]
    tip = [index[1, i, j, 8] for j in range(3) for i in range(3)]
    slaves = [index[1, i, 0, k] for k in range(9) for i in range(3)]
    lines += ["*NSET, NSET=FIX", *map(str, fixed), "*NSET, NSET=TIP", *map(str, tip)]
    lines += ["*BOUNDARY", "FIX, 1, 3", "*MATERIAL, NAME=EL", "*ELASTIC", "210000., 0.3"]
    lines += ["*DENSITY", "7.8E-9", "*SOLID SECTION, ELSET=EALL, MATERIAL=EL"]
    if pair:
        lines += ["*SURFACE, NAME=SMAST", *(f"{e}, S5" for e in lower_top)]
        lines += ["*SURFACE, NAME=SSLAV, TYPE=NODE", *map(str, slaves)]
        lines += ["*CONTACT PAIR, INTERACTION=SI1, TYPE=NODE TO SURFACE", "SSLAV, SMAST"]
        lines += ["*SURFACE INTERACTION, NAME=SI1"]
        lines += ["*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=EXPONENTIAL", "1e-2, 4."]
    lines += ["*STEP", "*FREQUENCY, STORAGE=YES", str(modes), "*END STEP"]
    lines += ["*STEP, INC=100000", procedure.rstrip("\n"), "*CLOAD", "TIP, 2, -7."]
    lines += ["*MODAL DAMPING, RAYLEIGH", ", , 15000., 0."]
    lines += [f"*NODE PRINT, NSET=NALL, FREQUENCY={frequency}", "U, V", "*END STEP"]
    return "\n".join(lines) + "\n"
