"""C3D6 wedges read as C3D8 hexahedra with one collapsed edge (docs/method.md §30).

ccx's wedge ``1..6`` (triangle ``1-2-3`` below ``4-5-6``) becomes the hexahedron
``1, 2, 3, 3, 4, 5, 6, 6``: its face S5 (``3-3-6-6``) collapses into the edge ``3-6``, its faces
S1 and S2 are the wedge's triangles with corner 3 (6) twice, and S3, S4, S6 are the wedge's
quadrilaterals S3, S4, S5. The model then treats the wedge as any C3D8 (2x2x2 Gauss points, all
in the element's interior, where the Jacobian stays positive).

dolfinx 0.5.2 corrupts its memory when two cells collapse onto the same edge (measured), and a
triangle two wedges share is one facet only if both repeat the same corner. Each wedge is therefore
first turned (its corners renumbered cyclically, ``rotation`` 0..2, which keeps the element):
wedges that share triangles repeat the same corner there, and no edge is collapsed twice. The
numpy work is ``kernels/collapsed_wedges.py``, which the gmsh reader shares.
"""

from __future__ import annotations

import numpy as np

from dolfinx_ntf.kernels.collapsed_wedges import WEDGE_AS_HEXAHEDRON, WedgeRotationError
from dolfinx_ntf.kernels.collapsed_wedges import collapsed_jacobians as collapsed_jacobians
from dolfinx_ntf.kernels.collapsed_wedges import wedge_rotations as wedge_rotations_of_rows

from .errors import DeckError, Location

#: C3D8 node ``k`` of a collapsed wedge is the wedge's node ``C3D6_AS_C3D8[k]`` (0-based).
C3D6_AS_C3D8 = WEDGE_AS_HEXAHEDRON

#: C3D8 face number of the wedge's faces S1..S5 (index 0 unused).
C3D6_FACES_AS_C3D8 = np.array([0, 1, 2, 3, 4, 6], dtype=np.int64)

#: Number of nodes of a C3D6 element.
C3D6_NODES = 6


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
    try:
        return wedge_rotations_of_rows(rows)
    except WedgeRotationError as error:
        raise DeckError(
            f"C3D6 element {int(ids[error.index])}: no numbering of the wedges' corners keeps "
            "their collapsed edges apart (wedges are read as collapsed C3D8)",
            locations[error.index],
        ) from None
