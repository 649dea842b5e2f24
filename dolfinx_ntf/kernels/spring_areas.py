"""Face areas and the spring areas ``A_p`` of slave nodes, with their derivatives.

The method is described in docs/method.md §2.2.

``A_p = Σ_{f∋p} w_{p,f} |f|``: every slave face f hands the fraction ``w_{p,f}`` of its area to each
of its nodes p, with the ccx weights ``FaceType.area_weights`` (tri3 1/3, quad4 1/4, tri6 1/999 and
332/999, quad8 1/100 and 24/100; a quad4 face with a repeated corner, a collapsed wedge's
triangle, 1/3 per node as ccx's tri3). ``|f| = Σ_q w_q |q_ξ × q_η|`` uses the face type's area
quadrature and the coordinates passed in (the current configuration ``X + u``; ccx recomputes the
areas at every pairing).

ccx treats ``A_p`` as a constant in the tangent (docs/method.md §6.3); the gradients here serve the
optional ``linearize_area`` extension. Pure numpy, vectorized over faces.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from dolfinx_ntf.kernels.faces import FaceType, face_coords_array

__all__ = [
    "face_area_gradients",
    "face_areas",
    "spring_area_gradients",
    "spring_areas",
]


def _check_face_coords(face_type: FaceType, face_coords: npt.ArrayLike) -> np.ndarray:
    """Return ``face_coords`` as a finite float array of shape (F, n, 3)."""
    coords = face_coords_array(face_type, face_coords)
    bad = ~np.isfinite(coords)
    if bad.any():
        face = int(np.argwhere(bad)[0][0])
        raise ValueError(f"face_coords of face {face} are not finite: {coords[face].tolist()}")
    return coords


def _jacobian_vectors(
    face_type: FaceType, coords: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Tangents q_ξ, q_η and ``m = q_ξ × q_η`` at the quadrature points, each (F, q, 3)."""
    dphi = face_type.shape_derivatives(face_type.quadrature_points)  # (q, n, 2)
    tangents = np.einsum("qjd,fjc->fqdc", dphi, coords)  # (F, q, 2, 3)
    q_xi = tangents[:, :, 0, :]
    q_eta = tangents[:, :, 1, :]
    return q_xi, q_eta, np.cross(q_xi, q_eta)


def face_areas(face_type: FaceType, face_coords: npt.ArrayLike) -> np.ndarray:
    """Areas ``|f| = Σ_q w_q |q_ξ × q_η|`` of faces with node coordinates (F, n, 3) -> (F,).

    Args:
        face_type: Type of every face.
        face_coords: Node coordinates of each face in face-local (CalculiX) order.
    """
    coords = _check_face_coords(face_type, face_coords)
    _, _, m = _jacobian_vectors(face_type, coords)
    return np.linalg.norm(m, axis=-1) @ face_type.quadrature_weights


def face_area_gradients(face_type: FaceType, face_coords: npt.ArrayLike) -> np.ndarray:
    """Derivatives ``∂|f|/∂x_j`` of the face areas by the face node coordinates -> (F, n, 3).

    With ``n = m/|m|``: ``∂|m|/∂x_j = φ_j,ξ (q_η × n) + φ_j,η (n × q_ξ)``, summed with the
    quadrature weights. Where ``|m| = 0`` at a quadrature point (a degenerate face) the point
    contributes nothing, i.e. the zero subgradient is taken.
    """
    coords = _check_face_coords(face_type, face_coords)
    q_xi, q_eta, m = _jacobian_vectors(face_type, coords)
    norm = np.linalg.norm(m, axis=-1, keepdims=True)
    unit = np.divide(m, norm, out=np.zeros_like(m), where=norm > 0.0)  # (F, q, 3)
    dphi = face_type.shape_derivatives(face_type.quadrature_points)  # (q, n, 2)
    w = face_type.quadrature_weights
    by_xi = np.cross(q_eta, unit) * w[None, :, None]  # (F, q, 3)
    by_eta = np.cross(unit, q_xi) * w[None, :, None]
    return np.einsum("qj,fqc->fjc", dphi[..., 0], by_xi) + np.einsum(
        "qj,fqc->fjc", dphi[..., 1], by_eta
    )


def _check_mesh(
    face_type: FaceType,
    faces: npt.ArrayLike,
    coords: npt.ArrayLike,
    slave_nodes: npt.ArrayLike,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate faces (F, n), coords (N, 3) and slave nodes (S,); return them as arrays."""
    faces_arr = np.asarray(faces)
    coords_arr = np.asarray(coords, dtype=float)
    slaves = np.asarray(slave_nodes)
    n = face_type.num_nodes
    if coords_arr.ndim != 2 or coords_arr.shape[1] != 3:
        raise ValueError(f"coords must have shape (num_nodes, 3), got {coords_arr.shape}")
    if faces_arr.size == 0:
        faces_arr = faces_arr.reshape(0, n).astype(np.int64)
    if faces_arr.ndim != 2 or faces_arr.shape[1] != n:
        raise ValueError(
            f"faces must have shape (F, {n}) for {face_type.name} faces, got {faces_arr.shape}"
        )
    if not np.issubdtype(faces_arr.dtype, np.integer):
        raise ValueError(f"faces must hold integer node ids, got dtype {faces_arr.dtype}")
    if slaves.size == 0:
        slaves = slaves.reshape(0).astype(np.int64)
    if slaves.ndim != 1 or not np.issubdtype(slaves.dtype, np.integer):
        raise ValueError(
            f"slave_nodes must be a 1-D integer array, got shape {slaves.shape} and dtype "
            f"{slaves.dtype}"
        )
    num_nodes = coords_arr.shape[0]
    out_of_range = (faces_arr < 0) | (faces_arr >= num_nodes)
    if out_of_range.any():
        face, local = (int(i) for i in np.argwhere(out_of_range)[0])
        raise ValueError(
            f"face {face} has node id {int(faces_arr[face, local])} at local position {local}, "
            f"outside [0, {num_nodes})"
        )
    sorted_slaves = np.sort(slaves)
    repeated = sorted_slaves[1:][np.diff(sorted_slaves) == 0]
    if repeated.size:
        raise ValueError(f"slave_nodes lists node {int(repeated[0])} more than once")
    return faces_arr.astype(np.int64, copy=False), coords_arr, slaves.astype(np.int64, copy=False)


def _slave_index(slaves: np.ndarray, nodes: np.ndarray) -> np.ndarray:
    """Position of each node id in ``slaves`` (any order, unique), or -1 if it is not a slave."""
    index = np.full(nodes.shape, -1, dtype=np.int64)
    if slaves.size == 0:
        return index
    order = np.argsort(slaves, kind="stable")
    sorted_slaves = slaves[order]
    pos = np.minimum(np.searchsorted(sorted_slaves, nodes), sorted_slaves.size - 1)
    found = sorted_slaves[pos] == nodes
    index[found] = order[pos[found]]
    return index


def _area_weights(face_type: FaceType, faces: np.ndarray) -> np.ndarray:
    """``(F, n)`` area weights of each face node: ``face_type.area_weights`` in general.

    A quad4 face with a repeated corner (a collapsed wedge's triangle, docs/method.md §30) gives
    each of its three nodes 1/3, as ccx's triangle does (1/6 in each slot of the repeated node).
    """
    weights = np.broadcast_to(face_type.area_weights, faces.shape).astype(float)
    if face_type.name != "quad4" or faces.shape[0] == 0:
        return weights
    same = faces[:, :, None] == faces[:, None, :]  # (F, 4, 4)
    multiplicity = same.sum(axis=2)  # (F, 4)
    distinct = np.sum(1.0 / multiplicity, axis=1)  # (F,)
    degenerate = distinct < 4.0 - 1e-12
    weights[degenerate] = 1.0 / (distinct[degenerate, None] * multiplicity[degenerate])
    return weights


def spring_areas(
    face_type: FaceType,
    faces: npt.ArrayLike,
    coords: npt.ArrayLike,
    slave_nodes: npt.ArrayLike,
) -> np.ndarray:
    """Spring areas ``A_p = Σ_{f∋p} w_{p,f} |f|`` of the slave nodes (docs/method.md §2.2) -> (S,).

    Args:
        face_type: Type of every slave face.
        faces: (F, n) node ids of the slave faces (rows index ``coords``).
        coords: (num_nodes, 3) node coordinates (current configuration).
        slave_nodes: (S,) unique node ids, in any order; the result follows this order. A slave
            node on none of the faces gets 0 (ccx then falls back to a master-face area).
    """
    faces_arr, coords_arr, slaves = _check_mesh(face_type, faces, coords, slave_nodes)
    areas = face_areas(face_type, coords_arr[faces_arr])  # (F,)
    shares = areas[:, None] * _area_weights(face_type, faces_arr)  # (F, n)
    index = _slave_index(slaves, faces_arr)
    hit = index >= 0
    return np.bincount(index[hit], weights=shares[hit], minlength=slaves.size).astype(float)


def spring_area_gradients(
    face_type: FaceType,
    faces: npt.ArrayLike,
    coords: npt.ArrayLike,
    slave_nodes: npt.ArrayLike,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Derivatives ``∂A_p/∂x_q`` of the spring areas as COO triplets (duplicates summed).

    Arguments as for :func:`spring_areas`.

    Returns:
        ``(slave_index (K,), node (K,), gradient (K, 3))``: ``slave_index`` indexes
        ``slave_nodes``, ``node`` is a node id; pairs are unique and sorted by
        ``(slave_index, node)``. Pairs with no face in common are absent.
    """
    faces_arr, coords_arr, slaves = _check_mesh(face_type, faces, coords, slave_nodes)
    n = face_type.num_nodes
    grads = face_area_gradients(face_type, coords_arr[faces_arr])  # (F, n, 3)
    index = _slave_index(slaves, faces_arr)  # (F, n)
    face_of, local_of = np.nonzero(index >= 0)  # (face, local slave position) pairs
    # every (face, slave a, node b) triple: w_a ∂|f|/∂x_b
    rows = np.repeat(index[face_of, local_of], n)
    cols = faces_arr[face_of].reshape(-1)
    weights = _area_weights(face_type, faces_arr)[face_of, local_of]
    values = (weights[:, None, None] * grads[face_of]).reshape(-1, 3)
    num_nodes = coords_arr.shape[0]
    keys = rows * num_nodes + cols
    unique_keys, inverse = np.unique(keys, return_inverse=True)
    summed = np.stack(
        [np.bincount(inverse, weights=values[:, c], minlength=unique_keys.size) for c in range(3)],
        axis=1,
    )
    return unique_keys // num_nodes, unique_keys % num_nodes, summed
