"""C3D6 wedges read as C3D8 hexahedra with one collapsed edge (docs/method.md §30).

ccx's wedge ``1..6`` (triangle ``1-2-3`` below ``4-5-6``) becomes the hexahedron
``1, 2, 3, 3, 4, 5, 6, 6``: its face S5 (``3-3-6-6``) collapses into the edge ``3-6``, its faces
S1 and S2 are the wedge's triangles with corner 3 (6) twice, and S3, S4, S6 are the wedge's
quadrilaterals S3, S4, S5. The model then treats the wedge as any C3D8 (2x2x2 Gauss points, all
in the element's interior, where the Jacobian stays positive).

dolfinx 0.5.2 corrupts its memory when two cells collapse onto the same edge (measured), and a
triangle two wedges share is one facet only if both repeat the same corner. Each wedge is therefore
first turned (its corners renumbered cyclically, ``rotation`` 0..2, which keeps the element):
wedges that share triangles repeat the same corner there, and no edge is collapsed twice.
"""

from __future__ import annotations

import numpy as np

from .errors import DeckError, Location

#: C3D8 node ``k`` of a collapsed wedge is the wedge's node ``C3D6_AS_C3D8[k]`` (0-based).
C3D6_AS_C3D8 = np.array([0, 1, 2, 2, 3, 4, 5, 5], dtype=np.int64)

#: C3D8 face number of the wedge's faces S1..S5 (index 0 unused).
C3D6_FACES_AS_C3D8 = np.array([0, 1, 2, 3, 4, 6], dtype=np.int64)

#: Number of nodes of a C3D6 element.
C3D6_NODES = 6

# 2x2x2 Gauss points of the unit cube, and the trilinear shape function gradients there.
_G = 0.5 / np.sqrt(3.0)
_POINTS = np.array([[0.5 + a, 0.5 + b, 0.5 + c] for c in (-_G, _G) for b in (-_G, _G)
                    for a in (-_G, _G)])  # fmt: skip
_CORNERS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float
)


def _hex_gradients() -> np.ndarray:
    """``(q, 8, 3)`` reference gradients of the trilinear shape functions (ccx corner order)."""
    sign = 2.0 * _CORNERS - 1.0  # +1 at the far side of each axis
    value = 1.0 - _CORNERS[None] + sign[None] * _POINTS[:, None, :]  # (q, 8, 3) 1D factors
    grads = np.empty((_POINTS.shape[0], 8, 3))
    for axis in range(3):
        others = [a for a in range(3) if a != axis]
        grads[:, :, axis] = sign[None, :, axis] * value[:, :, others[0]] * value[:, :, others[1]]
    return grads


_GRADIENTS = _hex_gradients()


def collapsed_jacobians(coords: np.ndarray) -> np.ndarray:
    """``(e, 8)`` Jacobian determinants of collapsed wedges at the 2x2x2 Gauss points.

    ``coords`` ``(e, 8, 3)``: the collapsed hexahedra's nodes (positive for ccx's node order).
    """
    jac = np.einsum("eki,qkj->eqij", coords, _GRADIENTS)
    return np.linalg.det(jac)


def check_wedge_orientation(
    ids: np.ndarray, coords: np.ndarray, locations: tuple[Location, ...]
) -> None:
    """Refuse wedges whose collapsed hexahedron has a Jacobian <= 0 at a Gauss point.

    ``coords`` ``(e, 8, 3)`` are the collapsed hexahedra's node coordinates, ``ids`` the element
    numbers and ``locations`` their deck lines.
    """
    if ids.size == 0:
        return
    det = collapsed_jacobians(coords)
    bad = np.flatnonzero(np.any(det <= 0.0, axis=1))
    if bad.size:
        k = int(bad[0])
        raise DeckError(
            f"C3D6 element {int(ids[k])} has a Jacobian <= 0 ({det[k].min():.3g}) at an "
            "integration point: its nodes are not in ccx's order (triangle 1-2-3 counter-"
            "clockwise seen from the triangle 4-5-6)",
            locations[k],
        )


def wedge_faces(
    faces: np.ndarray, rotation: np.ndarray, what: str, location: Location
) -> np.ndarray:
    """Face numbers ``faces`` (1-based ccx labels) with those of wedges made the C3D8 faces.

    ``rotation`` is each entry's wedge rotation (-1: not a wedge, see :func:`wedge_rotations`);
    a wedge face number above 5 is refused, naming ``what`` and ``location``.
    """
    is_wedge = rotation >= 0
    if not np.any(is_wedge):
        return faces
    wrong = is_wedge & (faces > 5)
    if np.any(wrong):
        raise DeckError(
            f"{what}: face S{int(faces[wrong][0])} of a C3D6 element (S1..S5)", location
        )
    label = faces[is_wedge]
    side = label >= 3  # quadrilaterals S3..S5 follow the rotation, triangles keep their number
    label = np.where(side, 3 + (label - 3 - rotation[is_wedge]) % 3, label)
    out = np.array(faces, dtype=np.int64)
    out[is_wedge] = C3D6_FACES_AS_C3D8[label]
    return out


def _rotated(row: np.ndarray, rotation: int) -> np.ndarray:
    """The wedge ``row`` (6 nodes) with its corners renumbered cyclically by ``rotation``."""
    turn = (np.arange(3) + rotation) % 3
    return np.concatenate([row[turn], row[3 + turn]])


def wedge_rotations(
    ids: np.ndarray, rows: np.ndarray, locations: tuple[Location, ...]
) -> np.ndarray:
    """Rotation 0..2 of each wedge (rows ``(e, 6)`` in ccx order) for its collapsed hexahedron.

    Wedges stacked on shared triangles are turned together so that they repeat the same corner
    there; no two wedges may collapse onto the same edge (dolfinx cannot build such a mesh).
    Set-up work, once per deck: a plain walk over the stacks.

    Raises:
        DeckError: no rotation avoids a shared collapsed edge (naming the element).
    """
    rotation = np.full(ids.size, -1, dtype=np.int64)
    triangles: dict[frozenset, list[int]] = {}
    for k, row in enumerate(rows.tolist()):
        for tri in (row[:3], row[3:]):
            triangles.setdefault(frozenset(tri), []).append(k)
    stacks: list[list[tuple[dict[int, int], set[frozenset]]]] = []  # per stack, its 3 choices
    for start in range(ids.size):
        if rotation[start] >= 0:
            continue
        choices = []
        for first in range(3):
            chosen = _stack(start, first, rows, triangles)
            edges = [frozenset(_rotated(rows[k], r)[[2, 5]].tolist()) for k, r in chosen.items()]
            if len(set(edges)) == len(edges):
                choices.append((chosen, set(edges)))
        rotation[list(chosen)] = 0  # visited
        stacks.append(choices)
    picks = _pick(stacks)
    if picks is None:
        k = int(next(iter(stacks[0][0][0]))) if stacks and stacks[0] else 0
        raise DeckError(
            f"C3D6 element {int(ids[k])}: no numbering of the wedges' corners keeps their "
            "collapsed edges apart (wedges are read as collapsed C3D8)",
            locations[k],
        )
    for choices, pick in zip(stacks, picks):
        for k, r in choices[pick][0].items():
            rotation[k] = r
    return rotation


def _pick(stacks: list, limit: int = 100000) -> list[int] | None:
    """One choice per stack whose collapsed edges are all distinct (depth-first), or None."""
    picks: list[int] = []
    used: list[set[frozenset]] = []
    steps = 0
    next_choice = 0
    while len(picks) < len(stacks):
        steps += 1
        if steps > limit:
            return None
        taken = set().union(*used) if used else set()
        choices = stacks[len(picks)]
        for c in range(next_choice, len(choices)):
            if not taken & choices[c][1]:
                picks.append(c)
                used.append(choices[c][1])
                next_choice = 0
                break
        else:
            if not picks:
                return None
            next_choice = picks.pop() + 1
            used.pop()
    return picks


def _stack(start: int, first: int, rows: np.ndarray, triangles: dict) -> dict[int, int]:
    """Rotations of the wedges stacked on ``start``'s triangles when ``start`` takes ``first``.

    A neighbour repeats the corner the wedge repeats on their shared triangle.
    """
    chosen = {start: first}
    todo = [start]
    while todo:
        k = todo.pop()
        row = _rotated(rows[k], chosen[k])
        for tri, repeated in ((row[:3], row[2]), (row[3:], row[5])):
            for other in triangles[frozenset(tri.tolist())]:
                if other in chosen:
                    continue
                position = int(np.flatnonzero(rows[other] == repeated)[0]) % 3
                chosen[other] = (position - 2) % 3  # its corner 3 after turning
                todo.append(other)
    return chosen
