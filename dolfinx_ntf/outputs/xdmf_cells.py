"""XDMF time series of a mesh of hexahedra and wedges (collapsed hexahedra), for ParaView.

docs/method.md §30.6. dolfinx cannot write fields of a mesh whose hexahedra collapse into wedges
(its point values pull the cells' vertices back, which fails where the Jacobian vanishes, at the
collapsed edge), so :class:`MixedXdmfFile` writes such a mesh itself: the hexahedra as XDMF
``Hexahedron`` cells, the collapsed ones as ``Wedge`` cells (:func:`collapsed_wedges`), in one
``Mixed`` topology; or cells of one given type, such as the quadratic wedges ``Wedge_15`` and
``Wedge_18`` that dolfinx does not write (docs/method.md §43); and per time step the point
fields, as dolfinx and meshio lay out a time series (the mesh once, each step's grid including its
topology and geometry by an XPointer). The
data are written inline (``Format="XML"``, shortest round-trip decimals), so the file needs no HDF5
library and has no companion ``.h5``. Node ordering: VTK's (and XDMF's), hexahedra
``0-1-2-3`` below ``4-5-6-7``, wedges ``0-1-2`` below ``3-4-5`` with the first triangle's normal
pointing away from the second, quadratic wedges the same, then their edges ``0-1, 1-2, 2-0, 3-4,
4-5, 5-3, 0-3, 1-4, 2-5`` and (18 nodes) the centres of the quadrilaterals ``0-1-4-3, 1-2-5-4,
2-0-3-5`` (``VTK_QUADRATIC_WEDGE``, ``VTK_BIQUADRATIC_QUADRATIC_WEDGE``). Pure Python and numpy;
one process writes.
"""

from __future__ import annotations

import typing
from pathlib import Path

import numpy as np

from dolfinx_ntf.kernels.wedge_rule import VTK_HEXAHEDRON, collapse_classes, collapses

__all__ = [
    "COLLAPSE_PATTERNS",
    "NODES_PER_CELL",
    "XDMF_HEXAHEDRON",
    "XDMF_WEDGE",
    "XDMF_WEDGE_15",
    "XDMF_WEDGE_18",
    "MixedXdmfFile",
    "collapsed_wedges",
]

#: XDMF's cell type number of a hexahedron in a ``Mixed`` topology.
XDMF_HEXAHEDRON = 9
#: XDMF's cell type number of a 6-node wedge.
XDMF_WEDGE = 8
#: XDMF's cell type number of a 15-node wedge (``VTK_QUADRATIC_WEDGE``).
XDMF_WEDGE_15 = 40
#: XDMF's cell type number of an 18-node wedge (``VTK_BIQUADRATIC_QUADRATIC_WEDGE``).
XDMF_WEDGE_18 = 41

#: Nodes per cell of the XDMF types written.
NODES_PER_CELL = {XDMF_HEXAHEDRON: 8, XDMF_WEDGE: 6, XDMF_WEDGE_15: 15, XDMF_WEDGE_18: 18}

#: The twelve collapses in VTK's vertex order, each as ``((a, b), (c, d), wedge)``: the repeated
#: edges and the wedge's six vertices of the hexahedron (a triangle, then the partners of its
#: vertices across); ``kernels.wedge_rule.collapses``, the integration rule's classes.
COLLAPSE_PATTERNS = [(c.edges[0], c.edges[1], list(c.wedge)) for c in collapses(VTK_HEXAHEDRON)]

#: The wedge vertices of each collapse class, VTK's order: ``(12, 6)``.
_WEDGE_VERTICES = np.array(
    [c.wedge for c in sorted(collapses(VTK_HEXAHEDRON), key=lambda c: c.rule_class)]
)


def collapsed_wedges(cells: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Which hexahedra are collapsed into wedges, and those wedges' nodes in XDMF order.

    A collapsed hexahedron repeats its nodes along two parallel edges of one face (CalculiX's
    C3D6 ``1, 2, 3, 3, 4, 5, 6, 6`` as the deck reader writes it, in any of the twelve ways).

    Args:
        cells: ``(n, 8)`` node indices of the hexahedra in VTK order (ccx's C3D8 order).
        points: ``(N, 3)`` node coordinates (the wedges' orientation is taken from them).

    Returns:
        ``(n,)`` True for the collapsed cells, and ``(m, 6)`` their wedge nodes (in cell order).

    Raises:
        ValueError: A cell repeats nodes otherwise (its index is named).
    """
    cells = np.asarray(cells, dtype=np.int64)
    points = np.asarray(points, dtype=np.float64)
    if cells.ndim != 2 or cells.shape[1] != 8:
        raise ValueError(f"collapsed_wedges: cells must have shape (n, 8), got {cells.shape}")
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"collapsed_wedges: points must have shape (N, 3), got {points.shape}")
    repeated = (np.sort(cells, axis=1)[:, 1:] == np.sort(cells, axis=1)[:, :-1]).sum(axis=1)
    classes = collapse_classes(cells, VTK_HEXAHEDRON)
    wedge = classes >= 0
    bad = np.flatnonzero((repeated > 0) & ~wedge)
    if bad.size:
        raise ValueError(
            f"collapsed_wedges: cell {int(bad[0])} repeats nodes {cells[bad[0]].tolist()} but is "
            "not a hexahedron collapsed along two parallel edges of one face"
        )
    nodes = np.take_along_axis(cells[wedge], _WEDGE_VERTICES[classes[wedge]], axis=1)
    p = points[nodes]  # (m, 6, 3)
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    toward = p[:, 3:].mean(axis=1) - p[:, :3].mean(axis=1)
    turn = np.einsum("ij,ij->i", normal, toward) > 0.0  # VTK: the first normal points away
    nodes[turn] = nodes[turn][:, [0, 2, 1, 3, 5, 4]]
    return wedge, nodes


def _numbers(values: np.ndarray, indent: str) -> str:
    """Rows of ``values`` as text, shortest round-trip decimals (``repr``), one row a line."""
    values = np.asarray(values)
    rows = values.reshape(values.shape[0], -1).tolist()
    return "\n".join(indent + " ".join(map(repr, row)) for row in rows)


def _data_item(values: np.ndarray, indent: str, number_type: str = "Float") -> str:
    values = np.asarray(values)
    dims = " ".join(str(n) for n in values.shape)
    precision = ' Precision="8"' if number_type == "Float" else ""
    return (
        f'{indent}<DataItem Dimensions="{dims}" NumberType="{number_type}"{precision} '
        f'Format="XML">\n{_numbers(values, indent + "  ")}\n{indent}</DataItem>'
    )


class MixedXdmfFile:
    """An XDMF time series on hexahedra and collapsed wedges, or on cells of one type (inline data).

    Each :meth:`write` appends one time step and leaves a complete file behind (the closing tags
    are rewritten after it), so a file of an interrupted run opens.

    Args:
        path: The ``.xdmf`` file to create (overwritten).
        points: ``(N, 3)`` node coordinates.
        cells: ``(n, 8)`` hexahedra in VTK order, wedges as collapsed hexahedra
            (:func:`collapsed_wedges`); with ``cell_type``, ``(n, k)`` cells of that type in
            XDMF's (VTK's) node order.
        cell_type: One XDMF type for all cells (:data:`NODES_PER_CELL`'s keys, e.g.
            :data:`XDMF_WEDGE_15`); the topology stays ``Mixed``, each cell with its type.

    Raises:
        ValueError: Cells of another width than ``cell_type``'s, or not indexing the points.
    """

    _TAIL = "    </Grid>\n  </Domain>\n</Xdmf>\n"

    def __init__(
        self,
        path: str | Path,
        points: np.ndarray,
        cells: np.ndarray,
        *,
        cell_type: int | None = None,
    ) -> None:
        points = np.asarray(points, dtype=np.float64)
        if cell_type is None:
            wedge, wedge_nodes = collapsed_wedges(cells, points)
        cells = np.asarray(cells, dtype=np.int64)
        if cell_type is not None and (
            cell_type not in NODES_PER_CELL
            or cells.ndim != 2
            or cells.shape[1] != NODES_PER_CELL[cell_type]
        ):
            raise ValueError(
                f"MixedXdmfFile: cells of XDMF type {cell_type} must have shape "
                f"(n, {NODES_PER_CELL.get(cell_type, '?')}), got {cells.shape}"
            )
        if cells.size and (cells.min() < 0 or cells.max() >= points.shape[0]):
            raise ValueError(f"MixedXdmfFile: cells must index the {points.shape[0]} points")
        #: The file.
        self.path = Path(path)
        self.num_points = points.shape[0]
        if cell_type is not None:
            #: ``(n,)`` True for the cells written as (linear) wedges.
            self.wedges = np.full(cells.shape[0], cell_type == XDMF_WEDGE)
            typed = np.column_stack([np.full(cells.shape[0], cell_type, np.int64), cells])
            topology = typed.ravel()
        else:
            self.wedges = wedge
            rows: list[np.ndarray] = [np.zeros(0, np.int64)] * cells.shape[0]
            for k in np.flatnonzero(~wedge).tolist():
                rows[k] = np.concatenate([[XDMF_HEXAHEDRON], cells[k]])
            for k, nodes in zip(np.flatnonzero(wedge).tolist(), wedge_nodes):
                rows[k] = np.concatenate([[XDMF_WEDGE], nodes])
            topology = np.concatenate(rows) if rows else np.zeros(0, np.int64)
        ints = " ".join(map(str, topology.tolist()))
        head = (
            '<?xml version="1.0"?>\n<!DOCTYPE Xdmf SYSTEM "Xdmf.dtd" []>\n'
            '<Xdmf Version="3.0" xmlns:xi="http://www.w3.org/2001/XInclude">\n  <Domain>\n'
            '    <Grid Name="mesh" GridType="Uniform">\n'
            f'      <Topology TopologyType="Mixed" NumberOfElements="{cells.shape[0]}">\n'
            f'        <DataItem Dimensions="{topology.size}" NumberType="Int" Format="XML">\n'
            f"          {ints}\n        </DataItem>\n      </Topology>\n"
            '      <Geometry GeometryType="XYZ">\n'
            f"{_data_item(points, '        ')}\n      </Geometry>\n    </Grid>\n"
            '    <Grid Name="TimeSeries" GridType="Collection" CollectionType="Temporal">\n'
        )
        data = head.encode("ascii")
        self._tail_at = len(data)
        self._closed = False
        self.path.write_bytes(data + self._TAIL.encode("ascii"))

    def write(self, t: float, fields: typing.Mapping[str, np.ndarray]) -> None:
        """Append one time step with its point fields.

        Args:
            t: The time.
            fields: Name -> ``(N,)`` scalars or ``(N, 3)`` vectors at the points.

        Raises:
            ValueError: The file is closed, or a field has another shape.
        """
        if self._closed:
            raise ValueError(f"MixedXdmfFile.write: {self.path} is closed")
        lines = [
            f'      <Grid Name="mesh" GridType="Uniform">\n'
            "        <xi:include xpointer=\"xpointer(/Xdmf/Domain/Grid[@Name='mesh']/"
            '*[self::Topology or self::Geometry])" />\n'
            f'        <Time Value="{float(t)!r}" />'
        ]
        for name, values in fields.items():
            values = np.asarray(values, dtype=np.float64)
            if values.shape not in ((self.num_points,), (self.num_points, 3)):
                raise ValueError(
                    f"MixedXdmfFile.write: field {name!r} must have shape ({self.num_points},) or "
                    f"({self.num_points}, 3), got {values.shape}"
                )
            kind = "Scalar" if values.ndim == 1 else "Vector"
            lines.append(
                f'        <Attribute Name="{name}" AttributeType="{kind}" Center="Node">\n'
                f"{_data_item(values.reshape(self.num_points, -1), '          ')}\n"
                "        </Attribute>"
            )
        lines.append("      </Grid>\n")
        grid = "\n".join(lines).encode("ascii")
        with self.path.open("r+b") as stream:
            stream.seek(self._tail_at)
            stream.write(grid + self._TAIL.encode("ascii"))
            stream.truncate()
        self._tail_at += len(grid)

    def close(self) -> None:
        """Close the file (it is complete after every write; later writes are refused)."""
        self._closed = True
