"""Surface ties: each slave node tied to its projection on a master face (docs/method.md §19.1).

CalculiX's ``*TIE`` (tied contact) makes every slave node follow the point of the master surface
it projects onto: ``u_s = Σ_i N_i(ξ) u_i`` over the nodes of that face, three linear constraints
per slave node. A slave node is tied when its distance to that point is at most the position
tolerance (ccx: orthogonal distance, and the projection within the face or not farther than the
tolerance parallel to it); the default tolerance is "2.5 % of the typical element size" (ccx's
manual), here a quarter of the mean edge of the master's sub-triangles, which reproduces the
tolerance ccx 2.20 prints for square master faces to all digits (docs/method.md §19.1). Nothing
here is about the *ties* of the contact search (equal distances, ``tie_frame``).

The face is found by the triangle walk of the contact search (:class:`~dolfinx_ntf.kernels.search.
MasterSurface`, its bounding planes loosened by the tolerance), then the closest point of the face
by :func:`~dolfinx_ntf.kernels.projection.project_points`; a node the walk leaves without a face
(e.g. beyond the rim) is projected on the faces around its nearest sub-triangle's face instead.

Pure numpy; node ids index rows of a coordinate array.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from dolfinx_ntf.kernels.faces import FaceType, face_points
from dolfinx_ntf.kernels.projection import project_points
from dolfinx_ntf.kernels.search import MasterSurface

__all__ = [
    "DEFAULT_TOLERANCE_FRACTION",
    "TieProjection",
    "default_tolerance",
    "project_on_master",
    "tie_rows",
]

DEFAULT_TOLERANCE_FRACTION = 0.025
"""ccx's default position tolerance: this fraction of the typical element size."""
TYPICAL_SIZE_FRACTION = 0.25
"""The typical element size: this fraction of the mean sub-triangle edge (ccx 2.20's printed
tolerance on square faces of side h is 0.025 * 0.25 * (2 + sqrt 2) / 3 * h)."""


@dataclass(frozen=True)
class TieProjection:
    """Where each slave point lands on the master surface.

    Attributes:
        face: ``(S,)`` master face of each point (row of the master's faces), -1 for none.
        xi: ``(S, 2)`` parameters of the closest point on that face.
        weights: ``(S, n)`` shape functions ``N_i(ξ)`` of the face's nodes there.
        points: ``(S, 3)`` the closest points ``q(ξ)``.
        distance: ``(S,)`` distance of each slave point to its closest point (inf for none).
        tolerance: The position tolerance used.
    """

    face: np.ndarray
    xi: np.ndarray
    weights: np.ndarray
    points: np.ndarray
    distance: np.ndarray
    tolerance: float

    @property
    def tied(self) -> np.ndarray:
        """``(S,)`` whether each point is within the tolerance of the master surface."""
        return (self.face >= 0) & (self.distance <= self.tolerance)


def default_tolerance(face_type: FaceType, faces: np.ndarray, coords: np.ndarray) -> float:
    """ccx's default position tolerance: 2.5 % of a quarter of the mean sub-triangle edge.

    ccx 2.20 prints 0.0071129449 h for square faces of side h (this formula's value to all
    digits); on rectangles its value depends on their orientation in the global axes
    (docs/method.md §19.1).

    Args:
        face_type: Type of the master faces.
        faces: ``(F, n)`` node ids of the master faces.
        coords: ``(num_nodes, 3)`` node coordinates.
    """
    x = np.asarray(coords, dtype=float)[np.asarray(faces)[:, face_type.triangles]]  # (F, t, 3, 3)
    edges = np.linalg.norm(np.roll(x, -1, axis=2) - x, axis=3)
    return DEFAULT_TOLERANCE_FRACTION * TYPICAL_SIZE_FRACTION * float(edges.mean())


def project_on_master(
    master: MasterSurface, coords: np.ndarray, points: np.ndarray, tolerance: float
) -> TieProjection:
    """The closest point of the master surface to each slave point, for a tie.

    Args:
        master: The master surface (updated at ``coords``).
        coords: ``(num_nodes, 3)`` node coordinates the master's ids index.
        points: ``(S, 3)`` slave positions.
        tolerance: Position tolerance (> 0): also how far outside a face, parallel to it, the
            walk accepts a point.

    Returns:
        The :class:`TieProjection`; points farther than ``tolerance`` are not ``tied``.
    """
    if not tolerance > 0.0:
        raise ValueError(f"tie position tolerance must be > 0, got {tolerance}")
    coords = np.asarray(coords, dtype=float)
    points = np.asarray(points, dtype=float).reshape(-1, 3)
    face_type, faces = master.face_type, master.faces
    n = points.shape[0]
    face = master.locate(points, tolerance) if n else np.zeros(0, np.int64)
    face = np.where(face >= 0, face, -1)
    xi = np.zeros((n, 2))
    distance = np.full(n, np.inf)
    walked = np.flatnonzero(face >= 0)
    if walked.size:
        xi[walked], distance[walked] = _closest(
            face_type, coords[faces[face[walked]]], points[walked]
        )
    # the walk found no face (or one too far): the faces around the nearest triangle's face
    lost = np.flatnonzero(~(distance <= tolerance))
    if lost.size and master.num_faces:
        _, triangle = master.nearest_centroid(points[lost])
        which, patch = master.face_patches(master.triangle_faces[triangle])
        cand_xi, cand_d = _closest(face_type, coords[faces[patch]], points[lost][which])
        best = np.full(lost.size, np.inf)
        np.minimum.at(best, which, cand_d)
        first = np.flatnonzero(cand_d == best[which])
        keep = first[np.unique(which[first], return_index=True)[1]]
        better = best[which[keep]] < distance[lost[which[keep]]]
        rows = lost[which[keep]][better]
        face[rows] = patch[keep][better]
        xi[rows], distance[rows] = cand_xi[keep][better], cand_d[keep][better]
    held = face >= 0
    weights = np.zeros((n, face_type.num_nodes))
    weights[held] = face_type.shape_functions(xi[held])
    closest = np.zeros((n, 3))
    closest[held] = face_points(face_type, coords[faces[face[held]]], xi[held])
    return TieProjection(face, xi, weights, closest, distance, float(tolerance))


def _closest(face_type: FaceType, face_coords: np.ndarray, points: np.ndarray):
    """Parameters of the closest point of each face to its point, and the distance."""
    xi = project_points(face_type, face_coords, points)
    distance = np.linalg.norm(points - face_points(face_type, face_coords, xi), axis=1)
    return xi, distance


def tie_rows(
    slaves: np.ndarray, face_nodes: np.ndarray, weights: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The constraints ``u_s - Σ_i N_i u_i = 0``, one per slave node and component.

    Args:
        slaves: ``(S,)`` slave node ids.
        face_nodes: ``(S, n)`` node ids of each slave's master face.
        weights: ``(S, n)`` shape functions ``N_i`` at the slave's projection.

    Returns:
        ``(nodes, components, coefficients)``, each ``(3 S, 1 + n)``: row ``3 k + c`` ties
        component ``c`` of slave ``k``, its slave term first (the dependent dof).
    """
    slaves = np.asarray(slaves, dtype=np.int64).reshape(-1, 1)
    face_nodes = np.asarray(face_nodes, dtype=np.int64)
    nodes = np.repeat(np.hstack([slaves, face_nodes]), 3, axis=0)
    components = np.broadcast_to(np.tile(np.arange(3), slaves.shape[0])[:, None], nodes.shape)
    terms = np.hstack([np.ones((slaves.shape[0], 1)), -np.asarray(weights, dtype=float)])
    return nodes, components.copy(), np.repeat(terms, 3, axis=0)
