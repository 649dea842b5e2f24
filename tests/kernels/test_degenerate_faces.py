"""quad4 faces with a repeated corner (C3D6 triangles read as collapsed C3D8, docs/method.md §30).

Oracle: the same triangle as a tri3 face, which is what ccx uses for a wedge's triangle.
"""

import numpy as np
import pytest

from dolfinx_ntf.kernels.faces import FACE_TYPES
from dolfinx_ntf.kernels.laws import LinearLaw
from dolfinx_ntf.kernels.search import MasterSurface
from dolfinx_ntf.kernels.spring_areas import spring_area_gradients, spring_areas
from dolfinx_ntf.kernels.springs import evaluate_springs

TRI3, QUAD4 = FACE_TYPES["tri3"], FACE_TYPES["quad4"]
LAW = LinearLaw(slope=1.0e3, tension=0.5, c0=1e-3)


def _patch() -> tuple[np.ndarray, np.ndarray]:
    """A curved, triangulated 3 x 2 patch: node coordinates (N, 3) and tri3 faces (F, 3)."""
    u, v = np.meshgrid(np.arange(4.0), np.arange(3.0), indexing="ij")
    rng = np.random.default_rng(3)
    x = np.column_stack([u.ravel(), v.ravel(), 0.1 * np.sin(u.ravel() + 2 * v.ravel())])
    x[:, :2] += 0.1 * rng.uniform(-1, 1, (x.shape[0], 2))
    faces = []
    for i in range(3):
        for j in range(2):
            a, b, c, d = 3 * i + j, 3 * (i + 1) + j, 3 * (i + 1) + j + 1, 3 * i + j + 1
            faces += [[a, b, c], [a, c, d]] if (i + j) % 2 == 0 else [[a, b, d], [b, c, d]]
    return x, np.array(faces)


def _collapsed(faces: np.ndarray, slot: int) -> np.ndarray:
    """The tri3 faces as quad4 faces whose corner ``slot`` (0..2) is repeated after itself."""
    out = np.insert(faces, slot + 1, faces[:, slot], axis=1)
    return out


@pytest.mark.parametrize("slot", [0, 1, 2])
def test_master_surface_of_collapsed_faces_is_the_triangles(slot):
    x, tri = _patch()
    quad = _collapsed(tri, slot)
    as_tri = MasterSurface(TRI3, tri, coords=x)
    as_quad = MasterSurface(QUAD4, quad, coords=x)
    np.testing.assert_allclose(as_quad.nodal_normals, as_tri.nodal_normals, atol=1e-14)
    assert np.array_equal(as_quad.triangle_faces, np.arange(tri.shape[0]))
    rng = np.random.default_rng(5)
    points = np.column_stack(
        [rng.uniform(-0.2, 3.2, 200), rng.uniform(-0.2, 2.2, 200), rng.uniform(-0.3, 0.3, 200)]
    )
    tolerances = np.full(points.shape[0], 1e-3)
    found = as_quad.locate(points, tolerances)
    assert np.array_equal(found, as_tri.locate(points, tolerances))
    assert np.sum(found >= 0) > 100


def test_master_surface_refuses_a_face_with_two_repeats():
    x, tri = _patch()
    quad = _collapsed(tri, 0)
    quad[0] = [tri[0, 0], tri[0, 0], tri[0, 0], tri[0, 1]]
    with pytest.raises(ValueError, match="repeats a node"):
        MasterSurface(QUAD4, quad, coords=x)


@pytest.mark.parametrize("slot", [0, 2])
def test_springs_on_a_collapsed_face_equal_the_triangle_springs(slot):
    x, tri = _patch()
    face = tri[:1]
    quad = _collapsed(face, slot)[0]
    rng = np.random.default_rng(7)
    bary = rng.dirichlet([2.0, 2.0, 2.0], size=6)  # points well inside the triangle
    normal = np.cross(x[face[0, 1]] - x[face[0, 0]], x[face[0, 2]] - x[face[0, 0]])
    normal /= np.linalg.norm(normal)
    slaves = bary @ x[face[0]] - 1e-3 * rng.uniform(0.5, 1.5, (6, 1)) * normal
    areas = np.full(6, 0.3)
    on_tri = evaluate_springs(TRI3, np.repeat(x[face], 6, axis=0), slaves, areas, LAW)
    on_quad = evaluate_springs(QUAD4, np.repeat(x[quad][None], 6, axis=0), slaves, areas, LAW)
    np.testing.assert_allclose(on_quad.gap, on_tri.gap, rtol=1e-9, atol=1e-15)
    np.testing.assert_allclose(on_quad.normal, on_tri.normal, atol=1e-9)
    np.testing.assert_allclose(on_quad.normal_force, on_tri.normal_force, rtol=1e-8)
    # the quad's slots [0..3, slave] to the triangle's [0..2, slave]: the repeat adds up
    to_tri = np.zeros((5, 4))
    for k, node in enumerate([*quad, -1]):
        to_tri[k, [*face[0], -1].index(node)] = 1.0
    np.testing.assert_allclose(
        np.einsum("kt,nkc->ntc", to_tri, on_quad.forces), on_tri.forces, atol=1e-12
    )
    project = np.kron(to_tri, np.eye(3))  # (15, 12) dofs
    reduced = np.einsum("ia,nij,jb->nab", project, on_quad.stiffness, project)
    np.testing.assert_allclose(reduced, on_tri.stiffness, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("slot", [0, 1, 2])
def test_springs_at_the_repeated_corner_equal_the_triangle_springs(slot):
    """A slave node beside the repeated corner projects onto it, where q_xi x q_eta = 0: the
    frame is taken just inside (docs/method.md §32); the triangle's corner is the oracle."""
    x, tri = _patch()
    face = tri[:1]
    quad = _collapsed(face, slot)[0]
    corner = x[face[0, slot]]
    normal = np.cross(x[face[0, 1]] - x[face[0, 0]], x[face[0, 2]] - x[face[0, 0]])
    normal /= np.linalg.norm(normal)
    outward = corner - x[face[0]].mean(axis=0)  # beyond the corner, in the plane
    outward -= (outward @ normal) * normal
    slaves = corner + 1e-2 * outward / np.linalg.norm(outward) - 1e-3 * normal
    slaves = np.vstack([slaves, corner - 1e-3 * normal])  # and right below it
    areas = np.full(2, 0.3)
    on_tri = evaluate_springs(TRI3, np.repeat(x[face], 2, axis=0), slaves, areas, LAW)
    on_quad = evaluate_springs(QUAD4, np.repeat(x[quad][None], 2, axis=0), slaves, areas, LAW)
    np.testing.assert_allclose(on_quad.gap, on_tri.gap, rtol=1e-9)  # as inside the face
    np.testing.assert_allclose(on_quad.normal, on_tri.normal, atol=1e-9)
    to_tri = np.zeros((5, 4))
    for k, node in enumerate([*quad, -1]):
        to_tri[k, [*face[0], -1].index(node)] = 1.0
    np.testing.assert_allclose(
        np.einsum("kt,nkc->ntc", to_tri, on_quad.forces), on_tri.forces, atol=1e-12
    )
    # beside the corner both hold the projection there (a corner of the domain): one tangent
    project = np.kron(to_tri, np.eye(3))
    reduced = np.einsum("ia,nij,jb->nab", project, on_quad.stiffness, project)
    np.testing.assert_allclose(reduced[0], on_tri.stiffness[0], rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("slot", [0, 1, 2])
def test_springs_near_the_repeated_corner_equal_the_triangle_springs(slot):
    """Inside the triangle, 1e-4 to 5e-3 of the way from the repeated corner: the collapsed
    square squeezes the parameter there, and a projection started elsewhere (a previous
    iterate) stopped with ``r`` sloping in the plane and an indefinite Hessian ("singular
    projection"); it is polished from the triangle's barycentric coordinates (§32.3)."""
    x, tri = _patch()
    face = tri[:1]
    quad = _collapsed(face, slot)[0]
    normal = np.cross(x[face[0, 1]] - x[face[0, 0]], x[face[0, 2]] - x[face[0, 0]])
    normal /= np.linalg.norm(normal)
    rng = np.random.default_rng(11)
    near = np.array([1e-4, 1e-3, 5e-3, 1e-4, 1e-3, 5e-3])
    bary = rng.dirichlet([1.0, 1.0], size=6) * near[:, None]  # the other two corners' shares
    weights = np.insert(bary, slot, 1.0 - near, axis=1)
    slaves = weights @ x[face[0]] - 1e-3 * normal
    areas = np.full(6, 0.3)
    on_tri = evaluate_springs(TRI3, np.repeat(x[face], 6, axis=0), slaves, areas, LAW)
    to_tri = np.zeros((5, 4))
    for k, node in enumerate([*quad, -1]):
        to_tri[k, [*face[0], -1].index(node)] = 1.0
    project = np.kron(to_tri, np.eye(3))
    for start in (None, (0.9, 0.9), (-0.9, 0.9), (0.9, -0.9)):
        xi0 = None if start is None else np.tile(start, (6, 1))
        on_quad = evaluate_springs(
            QUAD4, np.repeat(x[quad][None], 6, axis=0), slaves, areas, LAW, xi0=xi0
        )
        np.testing.assert_allclose(on_quad.gap, on_tri.gap, rtol=1e-9)
        np.testing.assert_allclose(on_quad.normal, on_tri.normal, atol=1e-9)
        np.testing.assert_allclose(
            np.einsum("kt,nkc->ntc", to_tri, on_quad.forces), on_tri.forces, atol=1e-12
        )
        reduced = np.einsum("ia,nij,jb->nab", project, on_quad.stiffness, project)
        np.testing.assert_allclose(reduced, on_tri.stiffness, rtol=1e-6, atol=1e-6)


@pytest.mark.parametrize("slot", [0, 1, 2])
def test_spring_areas_of_collapsed_faces_are_the_triangle_shares(slot):
    x, tri = _patch()
    quad = _collapsed(tri, slot)
    slaves = np.arange(x.shape[0])
    np.testing.assert_allclose(
        spring_areas(QUAD4, quad, x, slaves), spring_areas(TRI3, tri, x, slaves), rtol=1e-12
    )
    rows_q, nodes_q, grads_q = spring_area_gradients(QUAD4, quad, x, slaves)
    rows_t, nodes_t, grads_t = spring_area_gradients(TRI3, tri, x, slaves)
    assert np.array_equal(rows_q, rows_t) and np.array_equal(nodes_q, nodes_t)
    np.testing.assert_allclose(grads_q, grads_t, atol=1e-12)
