"""Random master faces and slave nodes for the spring-kernel tests (pure numpy)."""

from __future__ import annotations

import numpy as np

from dolfinx_ntf.kernels.faces import FaceType, face_points, face_tangents

__all__ = [
    "CASES",
    "CASE_IDS",
    "SIZE",
    "interior_params",
    "penetrating",
    "random_faces",
    "rotation",
    "unit_normal",
]

SIZE = 2.0  # element size of the test faces

# (face type, out-of-plane warp of the nodes relative to SIZE)
CASES = [
    ("tri3", 0.0),
    ("quad4", 0.0),
    ("quad4", 0.15),
    ("tri6", 0.1),
    ("quad8", 0.1),
    ("quad9", 0.1),
]
CASE_IDS = [f"{name}-{'warped' if warp else 'flat'}" for name, warp in CASES]


def rotation(rng: np.random.Generator) -> np.ndarray:
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    return q if np.linalg.det(q) > 0 else -q


def random_faces(ft: FaceType, num: int, warp: float, rng: np.random.Generator) -> np.ndarray:
    """(num, n, 3) randomly distorted, warped, rotated and translated faces of size ~SIZE."""
    params = ft.node_parameters * (SIZE if ft.is_triangle else SIZE / 2)
    coords = np.zeros((num, ft.num_nodes, 3))
    coords[:, :, :2] = params + 0.08 * SIZE * rng.uniform(-1, 1, (num, ft.num_nodes, 2))
    coords[:, :, 2] = warp * SIZE * rng.uniform(-1, 1, (num, ft.num_nodes))
    rot = np.stack([rotation(rng) for _ in range(num)])
    shift = rng.uniform(-5, 5, (num, 1, 3))
    return np.einsum("nij,nkj->nki", rot, coords) + shift


def interior_params(ft: FaceType, num: int, rng: np.random.Generator) -> np.ndarray:
    if ft.is_triangle:
        bary = rng.dirichlet(np.ones(3), num)
        bary = 0.15 + 0.55 * bary  # stay away from the edges
        bary /= bary.sum(axis=1, keepdims=True)
        return bary[:, 1:]
    return rng.uniform(-0.6, 0.6, (num, 2))


def unit_normal(ft: FaceType, coords: np.ndarray, xi: np.ndarray) -> np.ndarray:
    t1, t2 = face_tangents(ft, coords, xi)
    m = np.cross(t1, t2)
    return m / np.linalg.norm(m, axis=-1, keepdims=True)


def penetrating(ft: FaceType, warp: float, num: int, seed: int):
    """Faces and slave nodes below them (d > 0) whose closest point is interior."""
    rng = np.random.default_rng(seed)
    coords = random_faces(ft, num, warp, rng)
    xi = interior_params(ft, num, rng)
    depth = rng.uniform(0.002, 0.05, num) * SIZE
    slave = face_points(ft, coords, xi) - depth[:, None] * unit_normal(ft, coords, xi)
    areas = rng.uniform(0.5, 2.0, num)
    return coords, slave, areas, xi, depth
