"""CalculiX ``.frd`` result files (ASCII, ccx 2.20's layout): writer and reader.

See docs/method.md §13.2. ``FrdWriter`` writes what ccx writes for ``*NODE FILE`` (U -> ``DISP``, RF
-> ``FORC``), ``*EL FILE`` (S -> ``STRESS``, E -> ``TOSTRAIN``, ME -> ``MESTRAIN``, PEEQ -> ``PE``,
ENER -> ``ENER``, SDV -> ``SDV``: integration-point values extrapolated to the nodes and averaged
over the elements around each node) and ``*CONTACT FILE`` (CDIS/CSTR -> ``CONTACT``): a header,
the nodes, the elements, then per written increment one block per result, and `` 9999`` at the
end. cgx and converters read it like ccx's file. ``read_frd`` reads both ccx's files and ours (the
tests compare them value by value). Pure Python/numpy.

Record layout (cgx manual, "Result Format"; widths checked against ccx 2.20's files):
    - ``    2C`` nodes and ``    3C`` elements blocks, rows ``-1`` (and ``-2`` for element nodes);
    - per result: ``    1PSTEP`` (block counter, increment, step), ``  100CL`` (output counter,
      time, number of nodes, increment), ``-4`` name, ``-5`` one line per component, ``-1`` rows
      (node number I10 and values E12.5), ``-3`` closes.
"""

from __future__ import annotations

import datetime as dt
import typing
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .elements import C3D8_EXTRAPOLATION, ELEMENT_TYPES, nodal_extrapolation

__all__ = [
    "C3D8_EXTRAPOLATION",
    "FRD_ELEMENT_TYPES",
    "FrdBlock",
    "FrdFile",
    "FrdWriter",
    "format_frd_time",
    "nodal_extrapolation",
    "read_frd",
]

#: frd element type numbers of the ccx element types (cgx manual: he8 1, te4 3, te10 6, he20 4).
FRD_ELEMENT_TYPES: dict[str, int] = {n: t.frd_type for n, t in ELEMENT_TYPES.items()}

#: Row and column of the six components of a symmetric tensor, in ccx's order.
_TENSOR_SLOTS = (("XX", 1, 1), ("YY", 2, 2), ("ZZ", 3, 3), ("XY", 1, 2), ("YZ", 2, 3), ("ZX", 3, 1))


def _tensor_components(names: typing.Iterable[str]) -> tuple[tuple[str, int, int, int], ...]:
    """Component lines of a symmetric-tensor block whose six components are called ``names``."""
    return tuple((name, 4, row, col) for name, (_, row, col) in zip(names, _TENSOR_SLOTS))


def _tensor_named(prefix: str) -> tuple[tuple[str, int, int, int], ...]:
    """Component lines ``prefix`` + XX, YY, ZZ, XY, YZ, ZX (``STRESS``: SXX, ...)."""
    return _tensor_components(prefix + slot for slot, _, _ in _TENSOR_SLOTS)


#: Result blocks: frd name -> (component lines ``(name, type, row, column)``, ccx's ALL line).
_COMPONENTS: dict[str, tuple[tuple[tuple[str, int, int, int], ...], bool]] = {
    "DISP": ((("D1", 2, 1, 0), ("D2", 2, 2, 0), ("D3", 2, 3, 0)), True),
    "FORC": ((("F1", 2, 1, 0), ("F2", 2, 2, 0), ("F3", 2, 3, 0)), True),
    "STRESS": (_tensor_named("S"), False),
    "TOSTRAIN": (_tensor_named("E"), False),
    "MESTRAIN": (_tensor_named("ME"), False),
    "PE": ((("PE", 1, 0, 0),), False),
    "ENER": ((("ENER", 1, 0, 0),), False),
    "SDV": ((), False),  # SDV1, SDV2, ...: as many as the block's values have columns
    "CONTACT": (
        _tensor_components(("COPEN", "CSLIP1", "CSLIP2", "CPRESS", "CSHEAR1", "CSHEAR2")),
        False,
    ),
}


@dataclass(frozen=True, eq=False)
class FrdBlock:
    """One result block of one increment.

    Attributes:
        name: ``DISP``, ``FORC``, ``STRESS``, ``TOSTRAIN``, ``MESTRAIN``, ``PE``, ``ENER``,
            ``SDV``, ``CONTACT`` (or any name ccx
            writes, when read).
        components: Component names in column order (read blocks; the writer knows them).
        step, increment: 1-based step and increment numbers (``1PSTEP`` record).
        time: Total time.
        nodes: ``(n,)`` node numbers.
        values: ``(n, k)`` values.
    """

    name: str
    components: tuple[str, ...]
    step: int
    increment: int
    time: float
    nodes: np.ndarray
    values: np.ndarray


@dataclass(frozen=True, eq=False)
class FrdFile:
    """A read ``.frd`` file: node coordinates, elements and result blocks in file order."""

    node_ids: np.ndarray
    node_coords: np.ndarray
    element_ids: np.ndarray
    element_types: np.ndarray
    element_nodes: list[np.ndarray]
    blocks: list[FrdBlock]

    def blocks_named(self, name: str) -> list[FrdBlock]:
        """The blocks called ``name``, in file order."""
        return [b for b in self.blocks if b.name == name]


def format_frd_time(value: float) -> str:
    """ccx's 12-character time field: ``E12.5`` below 1, fixed point with 10 digits from 1 on."""
    if abs(value) < 1.0:
        return f"{value:12.5E}"
    digits = len(str(int(abs(value))))
    return f"{value:12.{max(10 - digits, 1)}f}"


def _rows(ids: np.ndarray, values: np.ndarray) -> list[str]:
    """`` -1`` rows: the number (I10), then its values (E12.5); one format for all rows.

    Past six values a row goes on in `` -2`` lines of six (ccx's ``SDV`` blocks).
    """
    values = np.asarray(values, dtype=float)
    width = values.shape[1]
    row = " -1%10d" + "%12.5E" * min(width, 6)
    row += "".join("\n -2" + " " * 10 + "%12.5E" * min(6, width - k) for k in range(6, width, 6))
    return list(map(row.__mod__, zip(np.asarray(ids).tolist(), *values.T.tolist())))


def _line72(text: str) -> str:
    return f"{text:<72}"


# ----------------------------------------------------------------------------- writer


class FrdWriter:
    """Writes ``JOB.frd``: header, mesh, then result blocks per written increment.

    Args:
        path: The file (overwritten).
        node_ids, node_coords: Nodes, ascending numbers.
        element_ids: ``(E,)`` element numbers.
        element_type: The ccx element type of all elements.
        connectivity: ``(E, n)`` ccx node numbers, ccx order.
        element_materials: ``(E,)`` 1-based material index of each element.
        materials: Material names in index order (the ``1UMAT`` lines).
        ccx: The ccx version whose records are written: ``"2.23"`` declares the CONTACT block's
            components scalars (``1    1    0    0``), 2.20 tensor components as STRESS's.
        wedges: ``(ids, nodes (W, 6))`` of the C3D6 elements among ``element_ids`` (which list
            them as collapsed C3D8), written as ccx does: frd type 2 with their six nodes, all
            elements by ascending number (docs/method.md §35).
    """

    def __init__(
        self,
        path: str | Path,
        node_ids: np.ndarray,
        node_coords: np.ndarray,
        element_ids: np.ndarray,
        element_type: str,
        connectivity: np.ndarray,
        element_materials: np.ndarray,
        materials: typing.Sequence[str],
        ccx: str = "2.20",
        wedges: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> None:
        if ccx not in ("2.20", "2.23"):
            raise ValueError(f"ccx format {ccx!r}: one of 2.20, 2.23")
        self.path = Path(path)
        self.ccx = ccx
        self._blocks = 0
        self._outputs = 0
        self._increment_key: tuple[int, int] | None = None
        now = dt.datetime.now()
        lines = ["    1C"]
        for key, value in (
            ("USER", ""),
            ("DATE", f"{now.day}.{now.strftime('%B').lower()}.{now.year}"),
            ("TIME", now.strftime("%H:%M:%S")),
            ("HOST", ""),
            ("PGM", "dolfinx_ntf"),
            ("VERSION", f"CalculiX {ccx} format"),
            ("DIR", ""),
            ("DBN", ""),
        ):
            lines.append(_line72(f"    1U{key:<18}{value}"))
        lines += [_line72(f"    1UMAT{k + 1:5d}{name}") for k, name in enumerate(materials)]
        ids = np.asarray(node_ids)
        coords = np.asarray(node_coords)
        lines.append(f"    2C{'':18}{ids.size:12d}{'':37}1")
        lines += _rows(ids, coords)
        lines.append(" -3")
        frd_type = FRD_ELEMENT_TYPES[element_type]
        element_ids = np.asarray(element_ids)
        lines.append(f"    3C{'':18}{element_ids.size:12d}{'':37}1")
        connectivity = np.asarray(connectivity)[:, ELEMENT_TYPES[element_type].frd_nodes]
        # per element: its " -1" line, then " -2" lines of up to 10 node numbers
        width = connectivity.shape[1]
        record = f" -1%10d{frd_type:5d}{0:5d}%5d" + "".join(
            "\n -2" + "%10d" * min(10, width - start) for start in range(0, width, 10)
        )
        columns = [np.asarray(element_materials).astype(np.int64).tolist()]
        records = list(
            map(record.__mod__, zip(element_ids.tolist(), *columns, *connectivity.T.tolist()))
        )
        if wedges is not None and len(wedges[0]):
            records = _with_wedges(records, element_ids, columns[0], wedges)
        lines += records
        lines.append(" -3")
        self.path.write_text("\n".join(lines) + "\n")

    def write(self, block: FrdBlock) -> None:
        """Append one result block (blocks of one increment share its output counter)."""
        if block.name not in _COMPONENTS:
            raise ValueError(f"frd block {block.name} is not supported")
        key = (block.step, block.increment)
        if key != self._increment_key:
            self._increment_key = key
            self._outputs += 1
        self._blocks += 1
        components, with_all = _COMPONENTS[block.name]
        nodes = np.asarray(block.nodes)
        if block.name == "SDV":
            count = np.asarray(block.values).size // max(nodes.size, 1)
            components = tuple((f"SDV{k + 1}", 1, 0, 0) for k in range(count))
        lines = [
            f"    1PSTEP{'':14}{self._blocks:12d}{block.increment:12d}{block.step:12d}{'':10}",
            f"  100CL{100 + self._outputs:5d}{format_frd_time(block.time)}{nodes.size:12d}"
            f"{'':20}{0:2d}{self._outputs:5d}{'':10}{1:2d}",
            f" -4  {block.name:<8}{len(components) + with_all:5d}{1:5d}",
        ]
        if block.name == "CONTACT" and self.ccx == "2.23":
            components = tuple((name, 1, 0, 0) for name, _, _, _ in components)
        lines += [
            f" -5  {name:<8}{1:5d}{kind:5d}{row:5d}{column:5d}"
            for name, kind, row, column in components
        ]
        if with_all:
            lines.append(f" -5  {'ALL':<8}{1:5d}{2:5d}{0:5d}{0:5d}{1:5d}ALL")
        values = np.asarray(block.values, dtype=float).reshape(nodes.size, len(components))
        if components:  # ccx writes no rows of a block without components (SDV of no *PLASTIC)
            lines += _rows(nodes, values)
        lines.append(" -3")
        with self.path.open("a") as stream:
            stream.write("\n".join(lines) + "\n")

    def close(self) -> None:
        """Write the end record."""
        with self.path.open("a") as stream:
            stream.write(" 9999\n")


def _with_wedges(
    records: list[str],
    element_ids: np.ndarray,
    materials: list[int],
    wedges: tuple[np.ndarray, np.ndarray],
) -> list[str]:
    """The element records with the C3D6 wedges' as ccx's (type 2, six nodes), by number."""
    ids, nodes = np.asarray(wedges[0]), np.asarray(wedges[1])
    wedge = np.isin(element_ids, ids)
    position = np.searchsorted(ids, element_ids[wedge], sorter=np.argsort(ids))
    rows = nodes[np.argsort(ids)[position]]
    record = f" -1%10d{2:5d}{0:5d}%5d\n -2" + "%10d" * 6
    chosen = np.asarray(materials)[wedge].tolist()
    written = map(record.__mod__, zip(element_ids[wedge].tolist(), chosen, *rows.T.tolist()))
    for k, text in zip(np.flatnonzero(wedge).tolist(), written):
        records[k] = text
    order = np.argsort(element_ids, kind="stable")
    return [records[k] for k in order.tolist()]


# ----------------------------------------------------------------------------- reader


def _floats(text: str, count: int, where: str) -> list[float]:
    try:
        return [float(text[12 * k : 12 * (k + 1)]) for k in range(count)]
    except ValueError:
        raise ValueError(f"{where}: bad number in {text!r}") from None


def read_frd(path: str | Path) -> FrdFile:
    """Read an ASCII ``.frd`` file (ccx's or ours; short format).

    Rows past six values go on in `` -2`` lines (ccx's ``SDV``).
    """
    path = Path(path)
    lines = path.read_text(encoding="latin-1").splitlines()
    node_ids: list[int] = []
    coords: list[list[float]] = []
    element_ids: list[int] = []
    element_types: list[int] = []
    element_nodes: list[list[int]] = []
    blocks: list[FrdBlock] = []
    step = increment = 0
    time = 0.0
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("    2C"):
            i += 1
            while not lines[i].startswith(" -3"):
                node_ids.append(int(lines[i][3:13]))
                coords.append(_floats(lines[i][13:], 3, f"{path}:{i + 1}"))
                i += 1
        elif line.startswith("    3C"):
            i += 1
            while not lines[i].startswith(" -3"):
                if lines[i].startswith(" -1"):
                    element_ids.append(int(lines[i][3:13]))
                    element_types.append(int(lines[i][13:18]))
                    element_nodes.append([])
                else:
                    text = lines[i][3:]
                    element_nodes[-1] += [int(text[k : k + 10]) for k in range(0, len(text), 10)]
                i += 1
        elif line.startswith("    1PSTEP"):
            fields = line[10:].split()
            increment, step = int(fields[1]), int(fields[2])
        elif line.startswith("  100C"):
            time = float(line[12:24])
        elif line.startswith(" -4"):
            name = line[5:13].strip()
            count = int(line[13:18])
            i += 1
            components = []
            for _ in range(count):
                if not lines[i].startswith(" -5"):
                    raise ValueError(f"{path}:{i + 1}: component line (-5) expected")
                if lines[i][5:13].strip() != "ALL":
                    components.append(lines[i][5:13].strip())
                i += 1
            ids, values = [], []
            while not lines[i].startswith(" -3"):
                if lines[i].startswith(" -2") and values:  # a row's values past the sixth
                    left = len(components) - len(values[-1])
                    values[-1] += _floats(lines[i][13:], min(left, 6), f"{path}:{i + 1}")
                    i += 1
                    continue
                if not lines[i].startswith(" -1"):
                    raise ValueError(f"{path}:{i + 1}: result row (-1) expected")
                ids.append(int(lines[i][3:13]))
                first = min(len(components), 6)
                values.append(_floats(lines[i][13:], first, f"{path}:{i + 1}"))
                i += 1
            blocks.append(
                FrdBlock(
                    name,
                    tuple(components),
                    step,
                    increment,
                    time,
                    np.asarray(ids, dtype=np.int64),
                    np.asarray(values, dtype=float).reshape(len(ids), len(components)),
                )
            )
        elif line.startswith(" 9999"):
            break
        i += 1
    return FrdFile(
        np.asarray(node_ids, dtype=np.int64),
        np.asarray(coords, dtype=float).reshape(-1, 3),
        np.asarray(element_ids, dtype=np.int64),
        np.asarray(element_types, dtype=np.int64),
        [np.asarray(n, dtype=np.int64) for n in element_nodes],
        blocks,
    )
