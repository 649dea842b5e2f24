"""ccx's two-point C3D6 rule on a hexahedron collapsed into a wedge (docs/method.md §30.5).

A C3D6 wedge meshed as a C3D8 with one face collapsed into an edge has the wedge's field (the
collapsed trilinear map spans the linear wedge's functions), so ccx's C3D6 integration rule (one
point at the triangle's centroid times two Gauss points through the thickness, weights ``1/2 x 1``
on ccx's reference wedge) is a fixed rule on the reference hexahedron ``[0, 1]^3``: the same
physical points, each weight divided by the Jacobian of the collapse map at its point. Which rule
depends on which face of the reference hexahedron collapses, and along which axis: one of twelve
*classes* (:func:`collapses`, :func:`collapse_classes`), each with its rule (:func:`wedge_rule`);
the XDMF writer takes the wedges' vertices from the same classes. Pure numpy.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = [
    "DOLFINX_HEXAHEDRON",
    "NUM_CLASSES",
    "VTK_HEXAHEDRON",
    "Collapse",
    "collapse_classes",
    "collapses",
    "wedge_rule",
]

#: The twelve ways a face of the reference hexahedron collapses into an edge.
NUM_CLASSES = 12

#: Vertices of dolfinx's reference hexahedron, vertex ``i`` at ``(i & 1, i >> 1 & 1, i >> 2 & 1)``.
DOLFINX_HEXAHEDRON = np.array(
    [[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=np.int64
)
DOLFINX_HEXAHEDRON.flags.writeable = False

#: Vertices of VTK's reference hexahedron (XDMF's and ccx's C3D8), ``0-1-2-3`` below ``4-5-6-7``.
VTK_HEXAHEDRON = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]],
    dtype=np.int64,
)
VTK_HEXAHEDRON.flags.writeable = False


@dataclass(frozen=True)
class Collapse:
    """One way two parallel edges of one face of a hexahedron collapse (a wedge cell).

    Attributes:
        rule_class: ``4 c + 2 k + s``: ``c`` the axis of the collapsed edges, the collapsed face
            normal to the ``k``-th other axis (in increasing order), at coordinate ``s``.
        edges: The two collapsed edges, each ``(vertex, vertex + axis c)``.
        wedge: The wedge's six vertices: a triangle (on a face holding one collapsed edge; the
            face holding both is gone), then the partners of its vertices across.
    """

    rule_class: int
    edges: tuple[tuple[int, int], tuple[int, int]]
    wedge: tuple[int, ...]


def collapses(vertices: np.ndarray = DOLFINX_HEXAHEDRON) -> tuple[Collapse, ...]:
    """The twelve collapses of a hexahedron whose vertex ``i`` sits at ``vertices[i]``.

    One function for every vertex numbering (dolfinx's, VTK's), so that the classes of the
    integration rule and the wedges of the XDMF file are one thing.

    Args:
        vertices: ``(8, 3)`` the reference coordinates (0 or 1) of the numbering's vertices.
    """
    vertices = np.asarray(vertices, dtype=np.int64)

    def vertex(at: np.ndarray) -> int:
        return int(np.flatnonzero((vertices == at).all(axis=1))[0])

    found = []
    for axis in range(3):  # the collapsed edges run along this axis
        unit = np.eye(3, dtype=np.int64)[axis]
        edges = [(v, vertex(vertices[v] + unit)) for v in range(8) if vertices[v, axis] == 0]
        for i, first in enumerate(edges):
            for second in edges[i + 1 :]:
                differ = np.flatnonzero(vertices[first[0]] != vertices[second[0]])
                if differ.size != 1:  # diagonal edges: not on one face
                    continue
                across = int(differ[0])  # the triangles are the faces normal to this axis
                face = 3 - axis - across  # the collapsed face is normal to this one
                side = vertices[first[0], across]
                triangle = [v for v in range(8) if vertices[v, across] == side and v != first[1]]
                flip = np.eye(3, dtype=np.int64)[across]
                partner = [vertex(np.abs(vertices[v] - flip)) for v in triangle]
                others = [a for a in range(3) if a != axis]
                rule_class = 4 * axis + 2 * others.index(face) + int(vertices[first[0], face])
                found.append(Collapse(rule_class, (first, second), tuple(triangle + partner)))
    return tuple(found)


def collapse_classes(
    cell_nodes: np.ndarray, vertices: np.ndarray = DOLFINX_HEXAHEDRON
) -> np.ndarray:
    """The collapse class of each cell (:class:`Collapse`), from its 8 nodes.

    A wedge cell repeats two nodes, along two parallel edges of one face (the face collapsed
    into an edge), and no other; a cell that repeats nodes otherwise, or none, gets -1.

    Args:
        cell_nodes: ``(n, 8)`` node (or geometry dof) numbers of the cells.
        vertices: The cells' vertex numbering (:func:`collapses`): dolfinx's by default.

    Returns:
        ``(n,)`` classes in ``0..11``, or -1.
    """
    cell_nodes = np.asarray(cell_nodes)
    ordered = np.sort(cell_nodes, axis=1)
    repeated = (ordered[:, 1:] == ordered[:, :-1]).sum(axis=1)
    classes = np.full(cell_nodes.shape[0], -1, dtype=np.int64)
    for collapse in collapses(vertices):
        (a, b), (c, d) = collapse.edges
        hit = (cell_nodes[:, a] == cell_nodes[:, b]) & (cell_nodes[:, c] == cell_nodes[:, d])
        classes[hit & (repeated == 2)] = collapse.rule_class
    return classes


def wedge_rule(rule_class: int) -> tuple[np.ndarray, np.ndarray]:
    """ccx's C3D6 points and weights on the reference hexahedron of a collapse class.

    The points lie at the middle of the collapse axis, at 1/3 of the way from the face opposite
    the collapsed one (the triangle's centroid), and at the two Gauss points ``1/2 -+ 1/(2 sqrt 3)``
    of the thickness axis, in that order (ccx's bottom point first where the thickness axis runs
    from the wedge's first triangle to its second). Each weight is ``1/2 * 1/2`` (the wedge's
    weights on ``[0, 1]`` through the thickness) over the collapse map's Jacobian ``2/3``.

    Args:
        rule_class: A class of :func:`collapse_classes`, ``0..11``.

    Returns:
        ``(2, 3)`` points and ``(2,)`` weights.
    """
    if not 0 <= rule_class < NUM_CLASSES:
        raise ValueError(f"wedge_rule: the collapse class must be in 0..11, got {rule_class}")
    c, rest = divmod(int(rule_class), 4)
    k, s = divmod(rest, 2)
    f = [a for a in range(3) if a != c][k]
    t = 3 - c - f
    points = np.empty((2, 3))
    points[:, c] = 0.5
    points[:, f] = 1.0 / 3.0 if s == 1 else 2.0 / 3.0
    points[:, t] = 0.5 + np.array([-1.0, 1.0]) / (2.0 * np.sqrt(3.0))
    weights = np.full(2, 0.25 / (2.0 / 3.0))
    return points, weights
