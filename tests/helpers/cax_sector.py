"""A CAX4 contact deck and ccx's expansion of it written out by hand, for any sector angle.

ccx runs a CAX4 element as a C3D8 sector of 2 degrees (its node lines at +-1 degree, straight
sides). ``sector_deck(theta)`` writes that sector as an ordinary 3D deck: every 2D node becomes two
nodes at ``-+theta/2`` about the y axis, a cylindrical ``*TRANSFORM`` turns their degrees of freedom
into radial, hoop and axial ones, the hoop ones are held and the second node line follows the first
by ``*EQUATION`` (radial and axial). At 2 degrees ccx gives its CAX4 deck's results with it; other
angles show how the results depend on the sector (docs/method.md §23.3, "The remainder").

Both decks: a 1 x 1 block (3 x 2 elements) at r in [R0 + 0.3, R0 + 1.3] pressed by a prescribed
axial displacement of its top onto a 2 x 1 block (4 x 2 elements) held axially at its bottom, both
held radially at their left edges; LINEAR law; controls 1e-12; ``U`` printed at every node.
"""

from __future__ import annotations

import numpy as np

#: Node numbers of the sector's second node line: the 2D node's plus this.
SECOND_LINE = 1000

_MATERIAL = "*MATERIAL, NAME=STEEL\n*ELASTIC\n210000.0, 0.3\n"
_CONTROLS = "*CONTROLS, PARAMETERS=FIELD\n1e-12, 1e-12\n"
_LAW = (
    "*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n"
    "2.1e6, 3.0, 0.01\n*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE\nSLAVE, MASTER\n"
)


def _grid(x0: float, y0: float, width: float, height: float, nx: int, ny: int, first: int):
    xs, ys = np.linspace(x0, x0 + width, nx + 1), np.linspace(y0, y0 + height, ny + 1)
    ids = first + np.arange((nx + 1) * (ny + 1)).reshape(ny + 1, nx + 1)
    x, y = np.meshgrid(xs, ys)
    cells = [
        [ids[j, i], ids[j, i + 1], ids[j + 1, i + 1], ids[j + 1, i]]
        for j in range(ny)
        for i in range(nx)
    ]
    return ids, x.ravel(), y.ravel(), cells


def _lines(values) -> str:
    values = [int(v) for v in values]
    return "".join(", ".join(map(str, values[i : i + 8])) + "\n" for i in range(0, len(values), 8))


class CaxBlocks:
    """The two blocks' mesh at radius ``r0`` (the lower block's inner edge)."""

    def __init__(self, r0: float = 0.0) -> None:
        lower, lx, ly, lcells = _grid(r0, 0.0, 2.0, 1.0, 4, 2, 1)
        upper, ux, uy, ucells = _grid(r0 + 0.3, 1.0, 1.0, 1.0, 3, 2, 100)
        self.ids = np.concatenate([lower.ravel(), upper.ravel()])
        self.x, self.y = np.concatenate([lx, ux]), np.concatenate([ly, uy])
        self.cells = lcells + ucells
        self.master = list(range(len(lcells) - 3, len(lcells) + 1))  # the lower top row
        self.slave = list(range(len(lcells) + 1, len(lcells) + 4))  # the upper bottom row
        self.bottom, self.top = lower[0], upper[-1]
        self.left = np.concatenate([lower[:, 0], upper[:, 0]])

    def _common(self, master_face: str, slave_face: str) -> list[str]:
        return [
            "*ELSET, ELSET=MTOP\n", _lines(self.master), "*ELSET, ELSET=SBOT\n",
            _lines(self.slave), f"*SURFACE, NAME=MASTER\nMTOP, {master_face}\n",
            f"*SURFACE, NAME=SLAVE\nSBOT, {slave_face}\n", _MATERIAL,
            "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n", _LAW, "*NSET, NSET=B\n",
            _lines(self.bottom), "*NSET, NSET=L\n", _lines(self.left), "*NSET, NSET=T\n",
            _lines(self.top),
        ]  # fmt: skip

    def cax4_deck(self) -> str:
        """The CAX4 deck."""
        out = ["*NODE, NSET=NALL\n"]
        coords = zip(self.ids, self.x.tolist(), self.y.tolist())  # Python floats: repr is a number
        out += [f"{n}, {x!r}, {y!r}, 0.0\n" for n, x, y in coords]
        out.append("*ELEMENT, TYPE=CAX4, ELSET=EALL\n")
        out += [f"{e + 1}, " + ", ".join(map(str, c)) + "\n" for e, c in enumerate(self.cells)]
        out += self._common("S3", "S1")
        out += ["*BOUNDARY\nB, 2, 2\nL, 1, 1\n*STEP\n*STATIC\n0.5, 1.0\n", _CONTROLS]
        out.append("*BOUNDARY\nT, 2, 2, -0.002\n*NODE PRINT, NSET=NALL\nU\n*END STEP\n")
        return "".join(out)

    def sector_deck(self, theta_degrees: float) -> str:
        """The C3D8 sector of ``theta_degrees``, printing radial, hoop and axial displacements."""
        half = np.radians(theta_degrees) / 2
        out = ["*NODE, NSET=NALL\n"]
        for n, x, y in zip(self.ids, self.x.tolist(), self.y.tolist()):  # Python floats
            c, s = x * np.cos(half), x * np.sin(half)
            c, s = float(c), float(s)
            out.append(f"{n}, {c!r}, {y!r}, {-s!r}\n{n + SECOND_LINE}, {c!r}, {y!r}, {s!r}\n")
        out.append("*ELEMENT, TYPE=C3D8, ELSET=EALL\n")
        for e, c in enumerate(self.cells):
            nodes = list(c) + [k + SECOND_LINE for k in c]
            out.append(f"{e + 1}, " + ", ".join(map(str, nodes)) + "\n")
        out += self._common("S5", "S3")  # C3D8 faces 3-7-8-4 and 1-5-6-2: the 2D top and bottom
        out.append("*TRANSFORM, NSET=NALL, TYPE=C\n0., 0., 0., 0., 1., 0.\n*EQUATION\n")
        for n in self.ids:
            out += [f"2\n{n + SECOND_LINE}, {d}, 1., {n}, {d}, -1.\n" for d in (1, 3)]
        out += ["*BOUNDARY\nNALL, 2, 2\nB, 3, 3\nL, 1, 1\n*STEP\n*STATIC\n0.5, 1.0\n", _CONTROLS]
        out.append("*BOUNDARY\nT, 3, 3, -0.002\n*NODE PRINT, NSET=NALL\nU\n*END STEP\n")
        return "".join(out)
