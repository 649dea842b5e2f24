"""CalculiX 2.20 ``.dat`` blocks: an exact writer and a reader (docs/method.md §8.5).

A ``.dat`` file is a sequence of blocks, each a blank line, a title line, a blank line and one
row per item (no rows is allowed: ccx then writes the title and the two blank lines only)::

    <blank>
     displacements (vx,vy,vz) for set NALL and time  0.5000000E+00
    <blank>
             5 -3.464183E-05 -3.464183E-05 -1.616619E-04

Formats, verified byte for byte against ``ccx`` 2.20 output:
    - titles end with the time in Fortran ``E14.7`` (``0.5000000E+00``); contact titles put it
      right after ``time`` (one blank), the other titles after ``time `` (two blanks);
    - a row is the label as ``I10`` followed by ``1X,1PE13.6`` per value; ``*EL PRINT`` rows are
      ``I10,1X,I3`` (element, integration point) then the point's values (six stresses, three
      heat fluxes or one equivalent plastic strain);
    - totals rows (``TOTALS=YES/ONLY`` of RF and CELS) are ``6X`` then the values;
    - the CNUM row is the count right-aligned in 17 columns.

Block names used here: ``U``, ``RF``, ``NT``, ``RF_TOTAL``, ``S``, ``E``, ``PEEQ``, ``ENER``,
``SDV``, ``ME``, ``HFL``, ``CDIS``, ``CSTR``, ``CELS``, ``CELS_TOTAL``, ``CNUM``. ``read_dat``
also reads blocks it has no name for (the name is then the title text before the first
parenthesis) so that any ccx ``.dat`` file can be compared.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "BLOCK_NAMES",
    "CCX_FORMATS",
    "DatBlock",
    "blocks_named",
    "contact_print_blocks",
    "el_print_blocks",
    "format_block",
    "format_e13",
    "format_time",
    "increment_heading",
    "node_print_blocks",
    "read_dat",
    "step_heading",
    "write_dat",
]


@dataclass(frozen=True, eq=False)
class DatBlock:
    """One ``.dat`` block.

    Attributes:
        name: block name (see the module docstring).
        time: total time of the block title.
        set: set name of the title, or None for contact blocks and totals without a set.
        labels: ``(n,)`` node/element numbers, ``(n, 2)`` (element, integration point) for ``S``,
            ``(0,)`` for totals and CNUM.
        values: ``(n, k)`` values of the rows (``(1, k)`` for totals, ``(1, 1)`` for CNUM).
    """

    name: str
    time: float
    set: str | None
    labels: np.ndarray
    values: np.ndarray

    @property
    def rows(self) -> list[tuple]:
        """Rows as tuples ``(*labels, *values)``."""
        labels = self.labels.reshape(self.values.shape[0], -1) if self.labels.size else None
        return [
            tuple(int(v) for v in labels[i]) + tuple(float(v) for v in self.values[i])
            if labels is not None
            else tuple(float(v) for v in self.values[i])
            for i in range(self.values.shape[0])
        ]


# name -> (title template, number of label columns, number of value columns: None for any)
_BLOCKS: dict[str, tuple[str, int, int | None]] = {
    "U": (" displacements (vx,vy,vz) for set {set} and time {time}", 1, 3),
    "V": (" velocities (vx,vy,vz) for set {set} and time {time}", 1, 3),
    "RF": (" forces (fx,fy,fz) for set {set} and time {time}", 1, 3),
    "NT": (" temperatures for set {set} and time {time}", 1, 1),
    "RF_TOTAL": (" total force (fx,fy,fz) for set {set} and time {time}", 0, 3),
    "S": (
        " stresses (elem, integ.pnt.,sxx,syy,szz,sxy,sxz,syz) for set {set} and time {time}",
        2,
        6,
    ),
    "E": (
        " strains (elem, integ.pnt.,exx,eyy,ezz,exy,exz,eyz) for set {set} and time {time}",
        2,
        6,
    ),
    # ccx 2.20 writes no blank between "pe)" and "for" in this title (also for the key PE)
    "PEEQ": (
        " equivalent plastic strain (elem, integ.pnt.,pe)for set {set} and time {time}",
        2,
        1,
    ),
    "ENER": (
        " internal energy density (elem, integ.pnt.,energy) for set {set} and time {time}",
        2,
        1,
    ),
    # as many values as the deck's materials have state variables (13 with *PLASTIC, else 0)
    "SDV": (
        " internal state variables (elem, integ.pnt.,values) for set {set} and time {time}",
        2,
        None,
    ),
    "ME": (
        " mechanical strains (elem, integ.pnt.,exx,eyy,ezz,exy,exz,eyz) for set {set} and time "
        "{time}",
        2,
        6,
    ),
    # ccx 2.20 writes no blank between "set" and the set's name in this title
    "HFL": (" heat flux (elem, integ.pnt.,qx,qy,qz) for set{set} and time {time}", 2, 3),
    "CDIS": (
        " relative contact displacement (slave node,normal,tang1,tang2) for all contact "
        "elements and time{time}",
        1,
        3,
    ),
    "CSTR": (
        " contact stress (slave node,press,tang1,tang2) for all contact elements and time{time}",
        1,
        3,
    ),
    "CELS": (
        " contact print energy (slave node,energy) forall contact elements and time{time}",
        1,
        1,
    ),
    "CELS_TOTAL": (" total contact spring energy for time {time}", 0, 1),
    "CNUM": (" total number of contact elements for time {time}", 0, 1),
}

BLOCK_NAMES: tuple[str, ...] = tuple(_BLOCKS)
"""Names of the blocks this module writes."""

CCX_FORMATS: tuple[str, ...] = ("2.20", "2.23")
"""The ccx versions whose ``.dat`` format is written (docs/method.md §13.6)."""

#: Titles of ccx 2.23 that differ from 2.20's (the blocks' rows do not).
_TITLES_2_23 = {
    "CELS": " contact spring energy (slave node,energy) for all contact elements and time{time}",
}


def step_heading(step: int) -> str:
    """ccx 2.23's line before a step's first printed block (``S T E P       1``), with blanks."""
    return f"\n{'':24}S T E P{step:8d}\n\n"


def increment_heading(increment: int) -> str:
    """ccx 2.23's line before a printed increment's blocks (``INCREMENT     1``), with blanks."""
    return f"\n{'':32}INCREMENT{increment:6d}\n\n"


# ----------------------------------------------------------------------------- number formats


def format_e13(value: float) -> str:
    """Fortran ``1PE13.6`` (e.g. ``-1.501435E-05``), right-aligned in 13 columns.

    Like gfortran, a three-digit exponent drops the ``E`` (``1.000000-100``).
    """
    value = float(value)
    if not math.isfinite(value):
        text = "NaN" if math.isnan(value) else ("Infinity" if value > 0 else "-Infinity")
        return text.rjust(13)
    mantissa, exponent = f"{value:.6E}".split("E")
    exp = int(exponent)
    tail = f"E{exp:+03d}" if abs(exp) < 100 else f"{exp:+04d}"
    return f"{mantissa}{tail}".rjust(13)


def format_time(value: float) -> str:
    """Fortran ``E14.7`` (``0.5000000E+00``: mantissa in [0.1, 1)), right-aligned in 14 columns."""
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"time must be finite, got {value}")
    if value == 0.0:
        return " 0.0000000E+00"
    digits, exponent = f"{abs(value):.6E}".split("E")
    exp = int(exponent) + 1
    tail = f"E{exp:+03d}" if abs(exp) < 100 else f"{exp:+04d}"
    text = f"{'-' if value < 0 else ''}0.{digits.replace('.', '')}{tail}"
    return text.rjust(14)


# ----------------------------------------------------------------------------- writer


def _title(name: str, time: float, set_name: str | None, ccx: str = "2.20") -> str:
    template = _TITLES_2_23.get(name, _BLOCKS[name][0]) if ccx == "2.23" else _BLOCKS[name][0]
    if "{set}" in template and not set_name:
        raise ValueError(f"block {name} needs a set name")
    return template.format(set=set_name, time=format_time(time))


def format_block(block: DatBlock, ccx: str = "2.20") -> str:
    """The text of one block exactly as ccx 2.20 (or ``ccx="2.23"``) writes it, blank line first.

    Raises:
        ValueError: unknown block name, or labels/values of the wrong shape.
    """
    if block.name not in _BLOCKS:
        raise ValueError(f"unknown .dat block {block.name!r}; known: {', '.join(_BLOCKS)}")
    _, num_labels, num_values = _BLOCKS[block.name]
    values = np.asarray(block.values, dtype=np.float64)
    labels = np.asarray(block.labels, dtype=np.int64)
    if values.ndim != 2 or values.shape[1] != (num_values or values.shape[1]):
        raise ValueError(
            f"block {block.name}: values must have shape (n, {num_values}), got {values.shape}"
        )
    if ccx not in CCX_FORMATS:
        raise ValueError(f"ccx format {ccx!r}: one of {', '.join(CCX_FORMATS)}")
    lines = ["", _title(block.name, block.time, block.set, ccx), ""]
    if num_labels == 0:
        if values.shape[0] != 1:
            raise ValueError(f"block {block.name} has one row, got {values.shape[0]}")
        if block.name == "CNUM":
            count = values[0, 0]
            if count != int(count) or count < 0:
                raise ValueError(f"CNUM must be a count, got {count}")
            lines.append(f"{int(count):17d}")
        else:
            lines.append("      " + "".join(" " + format_e13(v) for v in values[0]))
        return "\n".join(lines) + "\n"
    labels = labels.reshape(values.shape[0], -1) if labels.size else labels.reshape(0, num_labels)
    if labels.shape != (values.shape[0], num_labels):
        raise ValueError(
            f"block {block.name}: labels must have shape ({values.shape[0]}"
            f"{', 2' if num_labels == 2 else ''}), got {np.asarray(block.labels).shape}"
        )
    lines += _labelled_rows(labels, values)
    return "\n".join(lines) + "\n"


def _labelled_rows(labels: np.ndarray, values: np.ndarray) -> list[str]:
    """Rows ``I10[ I3]``, then `` 1PE13.6`` per value, as :func:`format_e13` writes them.

    Python's ``%13.6E`` is that format for finite values with a two-digit exponent: one format
    for all rows, :func:`format_e13` for the other rows.
    """
    head = "%10d" + (" %3d" if labels.shape[1] == 2 else "")
    rows = list(map((head + " %13.6E" * values.shape[1]).__mod__,
                    zip(*labels.T.tolist(), *values.T.tolist())))  # fmt: skip
    size = np.abs(values)
    plain = np.isfinite(values) & (size < 9.9e99) & ((size >= 1.1e-99) | (values == 0))
    for i in np.flatnonzero(~plain.all(axis=1)).tolist():
        label = labels[i].tolist()
        head_text = f"{label[0]:10d}" + (f" {label[1]:3d}" if len(label) == 2 else "")
        rows[i] = head_text + "".join(" " + format_e13(v) for v in values[i])
    return rows


def _totals(totals: str) -> str:
    totals = totals.upper()
    if totals not in ("NO", "YES", "ONLY"):
        raise ValueError(f"totals must be NO, YES or ONLY, got {totals!r}")
    return totals


def _rows(labels, values, width: int, what: str) -> tuple[np.ndarray, np.ndarray]:
    labels = np.asarray(labels, dtype=np.int64).reshape(-1)
    values = np.asarray(values, dtype=np.float64)
    if width == 1 and values.shape == (labels.size,):
        values = values[:, None]
    if values.shape != (labels.size, width):
        shape = f"({labels.size}, {width})" + (f" or ({labels.size},)" if width == 1 else "")
        raise ValueError(f"{what}: values must have shape {shape}, got {values.shape}")
    return labels, values


def node_print_blocks(
    key: str, set_name: str, time: float, nodes, values, *, totals: str = "NO"
) -> list[DatBlock]:
    """Blocks of a ``*NODE PRINT`` key (``U``, ``V``, ``RF`` or ``NT``) for one set and time.

    Args:
        key: ``U``, ``V`` (velocities), ``RF`` or ``NT`` (temperatures).
        set_name: node set name as printed (upper case).
        time: total time.
        nodes: ``(n,)`` node numbers in set order.
        values: ``(n, 3)`` displacements or external forces, ``(n, 1)`` temperatures.
        totals: ``NO``, ``YES`` or ``ONLY``; ccx applies it to RF only (a sum row).
    """
    if key not in ("U", "V", "RF", "NT"):
        raise ValueError(f"*NODE PRINT key must be U, V, RF or NT, got {key!r}")
    totals = _totals(totals)
    nodes, values = _rows(nodes, values, 1 if key == "NT" else 3, f"*NODE PRINT {key}")
    blocks = []
    if key != "RF" or totals != "ONLY":
        blocks.append(DatBlock(key, time, set_name, nodes, values))
    if key == "RF" and totals != "NO":
        total = values.sum(axis=0, keepdims=True)
        blocks.append(DatBlock("RF_TOTAL", time, set_name, np.zeros(0, np.int64), total))
    return blocks


def el_print_blocks(
    key: str, set_name: str, time: float, elements, values, points=None
) -> list[DatBlock]:
    """Block of an ``*EL PRINT`` key at the integration points (``S``, ``E``, ``PEEQ``, ...).

    ``S`` is the Cauchy stress, ``E`` the strain, ``PEEQ`` the equivalent plastic strain, ``HFL``
    the heat flux, ``ENER`` the strain energy density, ``SDV`` the internal state variables (any
    number per point), ``ME`` the mechanical strain.

    Args:
        key: ``S``, ``E``, ``PEEQ``, ``HFL``, ``ENER``, ``SDV`` or ``ME``.
        set_name: element set name as printed.
        time: total time.
        elements: ``(E,)`` element numbers in set order.
        values: ``(E, q, 6)`` stresses ``sxx, syy, szz, sxy, sxz, syz`` or strains (tensor
            components, same order), ``(E, q, 1)`` equivalent plastic strains or energy
            densities, ``(E, q, 3)`` heat fluxes ``qx, qy, qz`` or ``(E, q, k)`` state variables
            per integration point (ccx order of the points).
        points: ``(E,)`` number of points printed of each element (its first rows of
            ``values``; C3D6 wedges print 2), all ``q`` if None.
    """
    widths = {"S": 6, "E": 6, "PEEQ": 1, "HFL": 3, "ENER": 1, "SDV": None, "ME": 6}
    if key not in widths:
        raise ValueError(f"*EL PRINT key must be one of {', '.join(widths)}, got {key!r}")
    values = np.asarray(values, dtype=np.float64)
    width = widths[key] if widths[key] is not None else values.shape[-1]
    elements = np.asarray(elements, dtype=np.int64).reshape(-1)
    if values.ndim != 3 or values.shape[0] != elements.size or values.shape[2] != width:
        raise ValueError(f"*EL PRINT {key}: values must have shape ({elements.size}, q, {width})")
    q = values.shape[1]
    labels = np.stack([np.repeat(elements, q), np.tile(np.arange(1, q + 1), elements.size)], 1)
    values = values.reshape(elements.size * q, width)
    if points is not None:
        keep = (np.arange(q)[None, :] < np.asarray(points).reshape(-1, 1)).reshape(-1)
        labels, values = labels[keep], values[keep]
    return [DatBlock(key, time, set_name, labels, values)]


def contact_print_blocks(
    key: str, time: float, slave_nodes, values=None, *, totals: str = "NO"
) -> list[DatBlock]:
    """Blocks of a ``*CONTACT PRINT`` key for one time (docs/method.md §8.5).

    Args:
        key: ``CDIS``, ``CSTR``, ``CELS`` or ``CNUM``.
        time: total time.
        slave_nodes: ``(N,)`` slave node number of each contact element, in element order.
        values: ``(N, 3)`` for CDIS (clearance, t1, t2) and CSTR (pressure, tau1, tau2),
            ``(N,)`` energies for CELS, unused for CNUM (the count is ``N``).
        totals: ``NO``, ``YES`` or ``ONLY``; ccx applies it to CELS only (a sum row).
    """
    totals = _totals(totals)
    slave_nodes = np.asarray(slave_nodes, dtype=np.int64).reshape(-1)
    empty = np.zeros(0, np.int64)
    if key == "CNUM":
        return [DatBlock("CNUM", time, None, empty, np.array([[float(slave_nodes.size)]]))]
    if key in ("CDIS", "CSTR"):
        nodes, rows = _rows(slave_nodes, values, 3, f"*CONTACT PRINT {key}")
        return [DatBlock(key, time, None, nodes, rows)]
    if key == "CELS":
        nodes, rows = _rows(slave_nodes, values, 1, "*CONTACT PRINT CELS")
        blocks = [DatBlock("CELS", time, None, nodes, rows)] if totals != "ONLY" else []
        if totals != "NO":
            total = rows.sum(axis=0, keepdims=True)
            blocks.append(DatBlock("CELS_TOTAL", time, None, empty, total))
        return blocks
    raise ValueError(f"*CONTACT PRINT key must be CDIS, CSTR, CELS or CNUM, got {key!r}")


def write_dat(
    path: str | Path,
    blocks: Iterable[DatBlock],
    *,
    append: bool = False,
    ccx: str = "2.20",
    heading: str = "",
) -> None:
    """Write ``blocks`` to the ``.dat`` file at ``path`` (``append=False`` truncates it first).

    Truncating first is what ccx does at program start. ``ccx`` is the version whose titles are
    written; ``heading`` goes first (ccx 2.23's ``step_heading`` and ``increment_heading``).
    """
    with open(path, "a" if append else "w", encoding="ascii", newline="\n") as handle:
        handle.write(heading)
        for block in blocks:
            handle.write(format_block(block, ccx))


# ----------------------------------------------------------------------------- reader

_TIME_RE = re.compile(r"time\s*(\S+)\s*$")
_SET_RE = re.compile(r"for set ?(\S+) and time")  # PEEQ: no blank before "for"
#: ccx 2.23 (not 2.20) heads each step's and increment's blocks with ``S T E P       1`` and
#: ``INCREMENT     1`` lines; blocks carry their time, so the reader skips them.
_STEP_RE = re.compile(r"\s*(S T E P|INCREMENT)\s+\d+\s*$")
#: A ``*FREQUENCY`` step's first table title, and the heading of each mode's print blocks.
_MODAL_TABLES = "E I G E N V A L U E   O U T P U T"
_MODE_HEADING = "E I G E N V A L U E    N U M B E R"
_FORTRAN_EXP_RE = re.compile(r"(\d)([+-]\d{3})$")


def _block_name(title: str) -> str:
    for name, template in _TITLES_2_23.items():
        if title.startswith(template.split("{", 1)[0]):
            return name
    for name, (template, _, _) in _BLOCKS.items():
        prefix = template.split("{", 1)[0]
        if "{set}" in template:
            prefix = prefix.rsplit(" for set", 1)[0]
        if title.startswith(prefix):
            return name
    return title.split("(", 1)[0].strip()


def _parse_number(token: str, where: str) -> float:
    try:
        return float(_FORTRAN_EXP_RE.sub(r"\1E\2", token))
    except ValueError:
        raise ValueError(f"{where}: bad number {token!r}") from None


def read_dat(path: str | Path) -> list[DatBlock]:
    """Read every block of the ccx ``.dat`` file at ``path`` (ccx 2.20 or 2.23, or ``write_dat``'s).

    A ``*FREQUENCY`` step's tables (eigenvalues to total effective mass) are skipped (read them
    with ``calculix.modal_dat``'s functions); its modes' print blocks are read like the others,
    all at the step's time.

    Raises:
        ValueError: a line that is neither a title nor a row of numbers (message gives file:line).
    """
    path = Path(path)
    modal = False  # inside a frequency step's tables
    blocks: list[DatBlock] = []
    current: dict | None = None

    def close() -> None:
        if current is None:
            return
        name = current["name"]
        num_labels = _BLOCKS[name][1] if name in _BLOCKS else None
        rows = current["rows"]
        if num_labels is None:  # unknown block: integer tokens first are labels
            num_labels = min((sum(1 for t in r if re.fullmatch(r"-?\d+", t)) for r in rows),
                             default=0)  # fmt: skip
        width = {len(r) for r in rows}
        if len(width) > 1:
            raise ValueError(f"{path}:{current['line']}: rows of block {name} differ in length")
        ncols = width.pop() if width else num_labels + ((_BLOCKS.get(name) or (0, 0, 0))[2] or 0)
        labels = np.array([[int(t) for t in r[:num_labels]] for r in rows], dtype=np.int64)
        values = np.array(
            [
                [_parse_number(t, f"{path}:{line}") for t in r[num_labels:]]
                for r, line in zip(rows, current["lines"])
            ],
            dtype=np.float64,
        ).reshape(len(rows), ncols - num_labels)
        labels = labels.reshape(len(rows), num_labels)
        if num_labels == 1:
            labels = labels[:, 0]
        elif num_labels == 0:
            labels = np.zeros(0, np.int64)
        blocks.append(DatBlock(name, current["time"], current["set"], labels, values))

    for number, line in enumerate(path.read_text(encoding="latin-1").splitlines(), start=1):
        if not line.strip():
            continue
        if _STEP_RE.fullmatch(line):
            continue
        if _MODAL_TABLES in line:
            close()
            current, modal = None, True
            continue
        if _MODE_HEADING in line:
            modal = False
            continue
        if modal and _TIME_RE.search(line) is None:
            continue
        modal = False
        tokens = line.split()
        if re.fullmatch(r"-?\d+", tokens[0]) or re.match(r"-?\d*\.\d", tokens[0]):
            if current is None:
                raise ValueError(f"{path}:{number}: data row before any block title")
            current["rows"].append(tokens)
            current["lines"].append(number)
            continue
        match = _TIME_RE.search(line)
        if match is None:
            raise ValueError(f"{path}:{number}: not a .dat block title or row: {line.strip()!r}")
        close()
        set_match = _SET_RE.search(line)
        current = {
            "name": _block_name(line),
            "time": _parse_number(match.group(1), f"{path}:{number}"),
            "set": set_match.group(1) if set_match else None,
            "rows": [],
            "lines": [],
            "line": number,
        }
    close()
    return blocks


def blocks_named(blocks: Sequence[DatBlock], name: str) -> list[DatBlock]:
    """The blocks called ``name``, in file order."""
    return [b for b in blocks if b.name == name]
