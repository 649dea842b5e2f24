"""Generated 2D CalculiX decks: two blocks pressed together, meshed with ccx's 2D elements.

:func:`write_deck` writes ``<name>.inp`` for plane strain (CPE), plane stress (CPS) and
axisymmetric (CAX) elements, linear (4-node) or quadratic (8-node) quadrilaterals, with the
LINEAR or EXPONENTIAL pressure-overclosure law. The lower block ``[0, 2] x [0, 1]`` (master, its
top edge) rests on rollers; the upper block ``[0.3, 1.3] x [1, 2]`` (slave, its bottom edge, a
non-matching grid) is pushed down by a prescribed displacement of its top edge, by point forces
(``load="cload"``) or by a pressure (``load="dload"``). For CAX decks ``x`` is the radius: the
lower block touches the axis (``u_r = 0`` there). Both ccx 2.20 and the deck runner run the
same file (``tests/calculix/test_ccx_2d_decks.py``). 3-node elements (CPE3, ...) split each
quadrilateral into two triangles.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from dolfinx_ntf.calculix.controls import FIELD_CONTROL_NAMES, TIGHT_FIELD_CONTROLS
from dolfinx_ntf.calculix.dat import DatBlock, read_dat

__all__ = ["Deck2D", "block_difference", "dat_pairs", "write_deck"]


@dataclass(frozen=True)
class Deck2D:
    """A generated 2D deck.

    Attributes:
        name: Job name.
        element: ccx element type (``CPE4``, ``CPS8R``, ``CAX4`` ...).
        law: ``LINEAR`` or ``EXPONENTIAL``.
        thickness: ``*SOLID SECTION`` thickness (None: no value, ccx's default 1).
        load: ``displacement`` (prescribed top displacement), ``cload`` (point forces) or
            ``dload`` (a pressure on the top edges).
        lower, upper: Elements along x and y of the lower and the upper block.
        contact: False: the lower block alone, its top edge pushed down (the bulk without
            contact, to separate the bulk's differences from the springs').
        tight: ``*CONTROLS, PARAMETERS=FIELD`` with ``TIGHT_FIELD_CONTROLS``: ccx converges to
            round-off, so that converged solutions are compared.
        friction: ``(mu, stick slope)`` of a ``*FRICTION`` card (None: frictionless). The upper
            block's top edge is then held in x in the first step (pressed) and moved by ``drag``
            along x in a second step (dragged sideways), instead of the roller on its left edge.
        drag: x displacement of the upper block's top edge in the second step (with friction).
        change_mu: ``*CHANGE FRICTION`` to this mu (same stick slope) in the second step.
    """

    name: str
    element: str
    law: str = "LINEAR"
    thickness: float | None = None
    load: str = "displacement"
    lower: tuple[int, int] = (4, 2)
    upper: tuple[int, int] = (3, 2)
    contact: bool = True
    tight: bool = True
    friction: tuple[float, float] | None = None
    drag: float = 0.004
    change_mu: float | None = None

    def write(self, directory: Path) -> Path:
        """Write ``<name>.inp`` into ``directory``; returns its path."""
        return write_deck(self, directory)


def _block(
    x0: float,
    y0: float,
    width: float,
    height: float,
    nx: int,
    ny: int,
    quadratic: bool,
    first: int,
    triangles: bool = False,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nodes ``(n, 2)``, their ids and the ccx connectivity of a structured block.

    Quadrilaterals, or with ``triangles`` and ``quadratic`` 6-node triangles (two per square).
    """
    step = 2 if quadratic else 1
    gx, gy = step * nx + 1, step * ny + 1
    xs, ys = np.linspace(x0, x0 + width, gx), np.linspace(y0, y0 + height, gy)
    grid = np.arange(gx * gy).reshape(gy, gx)  # grid[j, i]
    cells = []
    for j in range(0, gy - 1, step):
        for i in range(0, gx - 1, step):
            c = [grid[j, i], grid[j, i + step], grid[j + step, i + step], grid[j + step, i]]
            if quadratic:  # midside nodes on 1-2, 2-3, 3-4, 4-1, then the centre
                c += [grid[j, i + 1], grid[j + 1, i + 2], grid[j + 2, i + 1], grid[j + 1, i]]
                c += [grid[j + 1, i + 1]]
            cells.append(c)
    cells = np.asarray(cells)
    if quadratic and not triangles:  # 8-node quadrilaterals: no centre nodes
        cells = cells[:, :8]
    if quadratic and triangles:  # 6-node triangles 1-2-3 and 1-3-4 (midside nodes 1-2, 2-3, 3-1)
        cells = np.stack([cells[:, [0, 1, 2, 4, 5, 8]], cells[:, [0, 2, 3, 8, 6, 7]]], axis=1)
        cells = cells.reshape(-1, 6)
    used = np.unique(cells)
    ids = np.full(gx * gy, -1)
    ids[used] = first + np.arange(used.size)
    X, Y = np.meshgrid(xs, ys)
    coords = np.column_stack([X.ravel(), Y.ravel()])
    return coords[used], ids[used], ids[cells]


def _lines(values: list[int], per_line: int = 8) -> str:
    return "".join(
        ", ".join(str(v) for v in values[k : k + per_line]) + "\n"
        for k in range(0, len(values), per_line)
    )


def write_deck(deck: Deck2D, directory: Path) -> Path:
    """Write the deck's ``.inp`` (see the module docstring)."""
    quadratic = deck.element[3] in "68"
    six = deck.element[3] == "6"
    lo_x, lo_y, lo_ids, lo_cells = _split(
        _block(0.0, 0.0, 2.0, 1.0, *deck.lower, quadratic, 1, six)
    )
    up_first = int(lo_ids.max()) + 1
    up_x, up_y, up_ids, up_cells = _split(
        _block(0.3, 1.0, 1.0, 1.0, *deck.upper, quadratic, up_first, six)
    )
    if not deck.contact:  # the lower block alone
        up_x, up_y, up_ids, up_cells = lo_x[:0], lo_y[:0], lo_ids[:0], lo_cells[:0]
    nodes = np.concatenate([lo_ids, up_ids])
    x = np.concatenate([lo_x, up_x])
    y = np.concatenate([lo_y, up_y])

    def where(ids: np.ndarray, mask: np.ndarray) -> list[int]:
        return sorted(int(i) for i in ids[mask])

    lower_bottom = where(lo_ids, np.isclose(lo_y, 0.0))
    lower_left = where(lo_ids, np.isclose(lo_x, 0.0))
    upper_top = where(up_ids, np.isclose(up_y, 2.0))
    upper_left = where(up_ids, np.isclose(up_x, 0.3))
    if not deck.contact:
        upper_top, upper_left = where(lo_ids, np.isclose(lo_y, 1.0)), lower_left
    # faces: S1 on edge 1-2 (bottom), S3 on edge 3-4 (top) of the structured cells
    nlx, nux = deck.lower[0], deck.upper[0]
    tri = deck.element[3] in "36"  # triangles, two per square: elements 2q - 1 and 2q
    lower_quads = len(lo_cells) // (2 if six else 1)
    lower_top_elements = [lower_quads - nlx + k + 1 for k in range(nlx)]
    upper_bottom_elements = [lower_quads + k + 1 for k in range(nux)]
    master_face, slave_face = "S3", "S1"
    if tri:  # top edge 3-4: S2 of triangle 1-3-4; bottom 1-2: S1 of 1-2-3
        lower_top_elements = [2 * e for e in lower_top_elements]
        upper_bottom_elements = [2 * e - 1 for e in upper_bottom_elements]
        master_face = "S2"
    out = [f"** {deck.name}: generated by tests/helpers/ccx_2d_decks.py\n*NODE\n"]
    out += [f"{n}, {float(a)!r}, {float(b)!r}, 0.0\n" for n, a, b in zip(nodes, x, y)]
    cells = np.vstack([lo_cells, up_cells])
    if deck.element[3] == "3":  # each quadrilateral 1-2-3-4 as triangles 1-2-3, 1-3-4
        cells = np.stack([cells[:, [0, 1, 2]], cells[:, [0, 2, 3]]], axis=1).reshape(-1, 3)
    out.append(f"*ELEMENT, TYPE={deck.element}, ELSET=EALL\n")
    out += [f"{e + 1}, " + ", ".join(str(int(n)) for n in c) + "\n" for e, c in enumerate(cells)]
    out.append("*NSET, NSET=LBOT\n" + _lines(lower_bottom))
    out.append("*NSET, NSET=LLEFT\n" + _lines(lower_left))
    out.append("*NSET, NSET=UTOP\n" + _lines(upper_top))
    out.append("*NSET, NSET=ULEFT\n" + _lines(upper_left))
    out.append("*ELSET, ELSET=MTOP\n" + _lines(lower_top_elements))
    if deck.contact:
        out.append("*ELSET, ELSET=SBOT\n" + _lines(upper_bottom_elements))
    if deck.contact:
        out.append(f"*SURFACE, NAME=MASTER\nMTOP, {master_face}\n")
        out.append(f"*SURFACE, NAME=SLAVE\nSBOT, {slave_face}\n")
    out.append("*MATERIAL, NAME=STEEL\n*ELASTIC\n210000.0, 0.3\n")
    out.append("*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n")
    if deck.thickness is not None:
        out.append(f"{deck.thickness!r}\n")
    if not deck.contact:
        pass
    elif deck.law == "LINEAR":
        out.append(
            "*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n"
        )
        out.append("2.1e6, 3.0, 0.01\n")
    else:
        out.append(
            "*SURFACE INTERACTION, NAME=SI\n*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=EXPONENTIAL\n"
        )
        out.append("1e-3, 1000.0\n")
    if deck.contact and deck.friction is not None:
        out.append(f"*FRICTION\n{deck.friction[0]!r}, {deck.friction[1]!r}\n")
    if deck.contact:
        out.append("*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE\nSLAVE, MASTER\n")
    rollers = "" if deck.friction is not None else "ULEFT, 1, 1\n"
    out.append(f"*BOUNDARY\nLBOT, 2, 2\nLLEFT, 1, 1\n{rollers}")
    out.append("*STEP\n*STATIC\n0.5, 1.0\n")
    controls = ""
    if deck.tight:
        values = [TIGHT_FIELD_CONTROLS.get(k) for k in FIELD_CONTROL_NAMES]
        while values[-1] is None:
            values.pop()
        fields = ", ".join("" if v is None else repr(float(v)) for v in values)
        controls = f"*CONTROLS, PARAMETERS=FIELD\n{fields}\n"
    out.append(controls)
    if deck.friction is not None:
        out.append("*BOUNDARY\nUTOP, 1, 1, 0.0\n")
    if deck.load == "dload":  # a pressure on the upper block's top edges (P3; triangles: P2)
        first = len(cells) - (2 if tri else 1) * nux
        top = range(first + (2 if tri else 1), len(cells) + 1)
        face = "P2" if tri else "P3"
        step = 2 if tri else 1
        out.append("*DLOAD\n" + "".join(f"{e}, {face}, 100.0\n" for e in list(top)[::step]))
    elif deck.load == "displacement":
        out.append("*BOUNDARY\nUTOP, 2, 2, -0.002\n")
    else:
        out.append(
            "*CLOAD\n" + "".join(f"{n}, 2, {-2000.0 / len(upper_top)!r}\n" for n in upper_top)
        )
    prints = (
        "*NODE PRINT, NSET=NALL\nU\n*NODE PRINT, NSET=NALL, TOTALS=YES\nRF\n"
        "*EL PRINT, ELSET=EALL\nS\n"
        + ("*CONTACT PRINT\nCDIS, CSTR, CELS, CNUM\n" if deck.contact else "")
        + "*END STEP\n"
    )
    out.append(prints)
    if deck.friction is not None:  # drag the pressed block sideways
        out.append(f"*STEP\n*STATIC\n0.25, 1.0\n{controls}")
        if deck.change_mu is not None:
            out.append(
                f"*CHANGE FRICTION, INTERACTION=SI\n*FRICTION\n"
                f"{deck.change_mu!r}, {deck.friction[1]!r}\n"
            )
        out.append(f"*BOUNDARY\nUTOP, 1, 1, {deck.drag!r}\n{prints}")
    text = "".join(out).replace(
        "*ELSET, ELSET=MTOP",
        f"*NSET, NSET=NALL, GENERATE\n1, {int(nodes.max())}\n*ELSET, ELSET=MTOP",
    )
    path = Path(directory) / f"{deck.name}.inp"
    path.write_text(text)
    return path


def _split(block):
    coords, ids, cells = block
    return coords[:, 0], coords[:, 1], ids, cells


def _largest_node(path: Path) -> int:
    """Largest node number of a generated deck (ccx numbers its expanded nodes above it)."""
    lines = path.read_text().split("*NODE\n", 1)[1].split("*ELEMENT", 1)[0].splitlines()
    return max(int(line.split(",")[0]) for line in lines)


def _collapse(block: DatBlock, base: int, mirrored: bool = False) -> DatBlock:
    """ccx's contact rows at its expanded nodes as rows of the 2D slave nodes.

    ccx numbers three expanded nodes per 2D node above the deck's largest node number (front,
    mid-plane, back); a 2D node has rows at the front and back (and at the mid-plane for the
    corners of quadratic edges), all with the same clearance and pressure; energies are summed.
    Their tangential columns agree to ccx's round-off (tang2 of a plane-strain deck: +-1e-16 of
    the block, where the 2D model prints 0). With ``mirrored`` (CAX and CPS decks) tang2 has
    opposite signs on the front and back lines and sums to 0; the collapsed tang2 is its
    magnitude: on CAX decks the lines lie at -1 and +1 degree (``+-sin(1 deg)`` of a radial slip
    or shear), on CPS decks the two plane-stress bodies thin or thicken apart (a z slip).
    """
    node = (block.labels - base - 1) // 3 + 1
    nodes, inverse, counts = np.unique(node, return_inverse=True, return_counts=True)
    assert np.all((counts == 2) | (counts == 3))
    values = np.zeros((nodes.size, block.values.shape[1]))
    np.add.at(values, inverse, block.values)
    if block.name != "CELS":
        first = np.zeros((nodes.size, block.values.shape[1]))
        first[inverse] = block.values
        scale = np.abs(block.values).max()
        mean = values / counts[:, None]
        if mirrored and block.name in ("CDIS", "CSTR"):  # tang2 sums to 0 over the node lines
            first[:, 2] = 0.0
        np.testing.assert_allclose(mean, first, rtol=1e-12, atol=1e-12 * scale)
        if mirrored and block.name in ("CDIS", "CSTR"):  # tang2: opposite signs, largest |value|
            first[:, 2] = 0.0
            np.maximum.at(first[:, 2], inverse, np.abs(block.values[:, 2]))
        values = first
    return DatBlock(block.name, block.time, block.set, nodes, values)


def dat_pairs(
    ccx_dir: Path, ntf_dir: Path, name: str, common_nodes: bool = False
) -> list[tuple[DatBlock, DatBlock]]:
    """(ccx, ours) block pairs, ccx's contact rows collapsed to the 2D nodes.

    ``common_nodes``: contact blocks keep the slave nodes both print (otherwise both must print
    the same nodes).
    """
    theirs, ours = read_dat(ccx_dir / f"{name}.dat"), read_dat(ntf_dir / f"{name}.dat")
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in theirs]
    base = _largest_node(ccx_dir / f"{name}.inp")
    text = (ccx_dir / f"{name}.inp").read_text()
    mirrored = "TYPE=CAX" in text or "TYPE=CPS" in text
    pairs = []
    for reference, mine in zip(theirs, ours):
        if reference.name in ("CDIS", "CSTR", "CELS"):
            reference = _collapse(reference, base, mirrored)
        if reference.name == "CNUM":  # two or three contact elements per 2D slave node
            if not common_nodes:
                assert mine.values[0, 0] * 2 <= reference.values[0, 0] <= mine.values[0, 0] * 3
            continue
        if common_nodes and reference.name in ("CDIS", "CSTR", "CELS"):
            both = np.intersect1d(mine.labels, reference.labels)
            reference, mine = (
                DatBlock(b.name, b.time, b.set, both, b.values[np.isin(b.labels, both)])
                for b in (reference, mine)
            )
        np.testing.assert_array_equal(mine.labels, reference.labels)
        pairs.append((reference, mine))
    return pairs


def block_difference(reference: DatBlock, mine: DatBlock, columns=slice(None)) -> float:
    """Largest difference relative to ccx's largest value of the block."""
    scale = np.abs(reference.values).max()
    difference = np.abs(mine.values[:, columns] - reference.values[:, columns]).max()
    return float(difference / scale) if scale > 0 else float(difference)


def write_mixed_deck(
    directory: Path,
    name: str,
    *,
    thickness: float = 2.0,
    node_slave: bool = False,
    nlgeom: bool = False,
    radius: float = 0.0,
    law: tuple[float, float] = (1e-3, 1000.0),
) -> Path:
    """A quasi-axisymmetric deck: a CAX8R ring (lower block) pressed by a CPS8R block (upper).

    The deck of :class:`Deck2D` (EXPONENTIAL law, the top edge pushed down) with the upper
    block's elements turned into plane-stress ones of ``thickness`` (the whole circumference's
    width, ccx's manual), both blocks moved out by ``radius``; ``node_slave``: the slave surface
    is the upper block's bottom nodes (``TYPE=NODE``, midside nodes included) instead of its
    bottom faces; ``nlgeom``: the step is NLGEOM; ``law``: the EXPONENTIAL law's ``c0, p0``.
    """
    path = Deck2D(name, "CAX8R", law="EXPONENTIAL", thickness=thickness).write(directory)
    text = path.read_text()
    head, rest = text.split("*ELEMENT, TYPE=CAX8R, ELSET=EALL\n", 1)
    lines = rest.splitlines(keepends=True)
    count = next(k for k, line in enumerate(lines) if line.startswith("*"))
    elements, tail = lines[:count], lines[count:]
    lower = [e for e in elements if int(e.split(",")[0]) <= 8]  # Deck2D's lower block: 4 x 2
    upper = [e for e in elements if int(e.split(",")[0]) > 8]
    nodes = {}
    for line in head.split("*NODE\n", 1)[1].splitlines():
        n, x, y, _ = line.split(",")
        nodes[int(n)] = (float(x) + radius, float(y))
    head = head.split("*NODE\n", 1)[0] + "*NODE\n"
    head += "".join(f"{n}, {x!r}, {y!r}, 0.0\n" for n, (x, y) in nodes.items())
    text = (
        head
        + "*ELEMENT, TYPE=CAX8R, ELSET=EALL\n"
        + "".join(lower)
        + "*ELEMENT, TYPE=CPS8R, ELSET=EALL\n"
        + "".join(upper)
        + "".join(tail)
    )
    # one section per block: the ring's without a thickness (as in ccx's bolt deck)
    text = text.replace("TYPE=CAX8R, ELSET=EALL", "TYPE=CAX8R, ELSET=ERING")
    text = text.replace("TYPE=CPS8R, ELSET=EALL", "TYPE=CPS8R, ELSET=EPLATE")
    text = text.replace(
        f"*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n{thickness!r}\n",
        "*SOLID SECTION, ELSET=ERING, MATERIAL=STEEL\n"
        f"*SOLID SECTION, ELSET=EPLATE, MATERIAL=STEEL\n{thickness!r}\n",
    )
    text = text.replace(
        "*EL PRINT, ELSET=EALL", "*EL PRINT, ELSET=ERING\nS\n*EL PRINT, ELSET=EPLATE"
    )
    if node_slave:  # one node per line: ccx's rule for node surfaces
        used = {int(n) for e in upper for n in e.split(",")[1:]}
        bottom = sorted(n for n in used if np.isclose(nodes[n][1], 1.0))
        text = text.replace(
            "*SURFACE, NAME=SLAVE\nSBOT, S1\n",
            "*SURFACE, NAME=SLAVE, TYPE=NODE\n" + _lines(bottom, per_line=1),
        )
    if radius:  # the ring no longer touches the axis: no radial support at x = radius
        text = text.replace("LLEFT, 1, 1\n", "LBOT, 1, 1\n", 1)
    if nlgeom:
        text = text.replace("*STEP\n", "*STEP, NLGEOM\n")
    text = text.replace("1e-3, 1000.0\n", f"{law[0]!r}, {law[1]!r}\n")
    path.write_text(text)
    return path
