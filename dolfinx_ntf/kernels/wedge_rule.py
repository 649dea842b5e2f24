"""ccx's two-point C3D6 rule on a hexahedron collapsed into a wedge (docs/method.md §30.5).

A C3D6 wedge meshed as a C3D8 with one face collapsed into an edge has the wedge's field (the
collapsed trilinear map spans the linear wedge's functions), so ccx's C3D6 integration rule (one
point at the triangle's centroid times two Gauss points through the thickness, weights ``1/2 x 1``
on ccx's reference wedge) is a fixed rule on the reference hexahedron ``[0, 1]^3``: the same
physical points, each weight divided by the Jacobian of the collapse map at its point. Which rule
depends on which face of the reference hexahedron collapses, and along which axis: one of twelve
*classes* (:func:`collapse_classes`), each with its rule (:func:`wedge_rule`). Pure numpy.
"""

from __future__ import annotations

import numpy as np

__all__ = ["NUM_CLASSES", "collapse_classes", "wedge_rule"]

#: The twelve ways a face of the reference hexahedron collapses into an edge.
NUM_CLASSES = 12

#: dolfinx's reference hexahedron: vertex ``i`` at ``(i & 1, i >> 1 & 1, i >> 2 & 1)``.
_VERTICES = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=np.int64)


def collapse_classes(cell_nodes: np.ndarray) -> np.ndarray:
    """The collapse class of each cell, from its 8 nodes in dolfinx's reference order.

    A wedge cell repeats two nodes, along two parallel edges of one face (the face collapsed
    into an edge); the class is ``4 c + 2 k + s``: ``c`` the axis of the collapsed edges, the
    face normal to the ``k``-th other axis (in increasing order), at coordinate ``s``. A cell
    whose repeated nodes are not two such edges gets -1.

    Args:
        cell_nodes: ``(n, 8)`` node (or geometry dof) numbers of the cells.

    Returns:
        ``(n,)`` classes in ``0..11``, or -1.
    """
    cell_nodes = np.asarray(cell_nodes)
    n = cell_nodes.shape[0]
    classes = np.full(n, -1, dtype=np.int64)
    for c in range(3):
        low = np.flatnonzero(_VERTICES[:, c] == 0)  # edges along axis c: (v, v + 2^c)
        high = low + (1 << c)
        same = cell_nodes[:, low] == cell_nodes[:, high]  # (n, 4) collapsed edges along c
        others = [a for a in range(3) if a != c]
        for k, f in enumerate(others):
            for s in range(2):
                on_face = _VERTICES[low, f] == s  # the two edges of that face
                hit = same[:, on_face].all(axis=1) & (same.sum(axis=1) == 2)
                classes[hit] = 4 * c + 2 * k + s
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
