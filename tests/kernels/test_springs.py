"""Tests of the spring element residual and tangent (dolfinx_ntf.kernels.springs), pure numpy."""

from __future__ import annotations

import numpy as np
import pytest
from helpers.spring_differences import nodal_differences, relative_error
from helpers.spring_faces import CASE_IDS, CASES, SIZE
from helpers.spring_faces import penetrating as _penetrating
from helpers.spring_faces import random_faces as _faces
from helpers.spring_faces import unit_normal as _unit_normal

from dolfinx_ntf.kernels.faces import FACE_TYPES, FaceType, face_points, face_tangents
from dolfinx_ntf.kernels.laws import ExponentialLaw, LinearLaw
from dolfinx_ntf.kernels.springs import evaluate_springs

LINEAR = LinearLaw(slope=1.0e3, tension=0.5, c0=1e-3)
EXPONENTIAL = ExponentialLaw(c0=0.2, p0=3.0)


def _finite_difference(ft, coords, slave, areas, law, h, **kwargs) -> np.ndarray:
    """Central finite differences of the forces, (N, 3(n+1), 3(n+1))."""
    nodes = np.concatenate([coords, slave[:, None, :]], axis=1)

    def forces(x: np.ndarray) -> np.ndarray:
        return evaluate_springs(ft, x[:, :-1], x[:, -1], areas, law, tangent=False, **kwargs).forces

    return nodal_differences(forces, (nodes,), h)


@pytest.mark.parametrize("law", [LINEAR, EXPONENTIAL], ids=["linear", "exponential"])
@pytest.mark.parametrize(("name", "warp"), CASES, ids=CASE_IDS)
def test_tangent_matches_finite_differences(name: str, warp: float, law) -> None:
    ft = FACE_TYPES[name]
    coords, slave, areas, xi, depth = _penetrating(ft, warp, 8, seed=1)
    ev = evaluate_springs(ft, coords, slave, areas, law)
    np.testing.assert_allclose(ev.xi, xi, atol=1e-9)
    np.testing.assert_allclose(ev.overclosure, depth, rtol=1e-9)
    assert np.all(ev.normal_force > 0)
    fd = _finite_difference(ft, coords, slave, areas, law, h=1e-7 * SIZE)
    error = relative_error(ev.stiffness, fd)
    assert error.max() <= 1e-6, error
    # With an interior projection the forces are the gradient of the spring energy A P(d(x))
    # (P' = p, since ∂g/∂x_p = n and ∂g/∂x_j = −φ_j n): the exact tangent is symmetric.
    asym = relative_error(ev.stiffness, ev.stiffness.transpose(0, 2, 1))
    assert asym.max() <= 1e-12


@pytest.mark.parametrize(("name", "warp"), CASES, ids=CASE_IDS)
def test_symmetric_option(name: str, warp: float) -> None:
    ft = FACE_TYPES[name]
    coords, slave, areas, _, _ = _penetrating(ft, warp, 5, seed=2)
    full = evaluate_springs(ft, coords, slave, areas, LINEAR).stiffness
    sym = evaluate_springs(ft, coords, slave, areas, LINEAR, symmetric=True).stiffness
    np.testing.assert_allclose(sym, 0.5 * (full + full.transpose(0, 2, 1)), rtol=0, atol=1e-12)
    np.testing.assert_array_equal(sym, sym.transpose(0, 2, 1))


@pytest.mark.parametrize(("name", "warp"), CASES, ids=CASE_IDS)
def test_equilibrium(name: str, warp: float) -> None:
    ft = FACE_TYPES[name]
    coords, slave, areas, _, _ = _penetrating(ft, warp, 10, seed=3)
    ev = evaluate_springs(ft, coords, slave, areas, EXPONENTIAL)
    scale = np.abs(ev.forces).max()
    np.testing.assert_allclose(ev.forces.sum(axis=1), 0.0, atol=1e-13 * scale)
    # Interior projection: r ∥ n, so the moments about the origin balance too.
    nodes = np.concatenate([coords, slave[:, None, :]], axis=1)
    moments = np.cross(nodes, ev.forces).sum(axis=1)
    np.testing.assert_allclose(moments, 0.0, atol=1e-11 * scale * np.abs(nodes).max())
    # The forces sum to zero for every configuration, so do the rows of K; a rigid translation
    # changes nothing, so do the columns.
    k = ev.stiffness.reshape(len(coords), ft.num_nodes + 1, 3, ft.num_nodes + 1, 3)
    kscale = np.abs(k).max()
    np.testing.assert_allclose(k.sum(axis=1), 0.0, atol=1e-11 * kscale)
    np.testing.assert_allclose(k.sum(axis=3), 0.0, atol=1e-11 * kscale)
    assert ev.forces.shape == (10, ft.num_nodes + 1, 3)
    assert ev.stiffness.shape == (10, 3 * (ft.num_nodes + 1), 3 * (ft.num_nodes + 1))


@pytest.mark.parametrize("name", ["tri3", "quad4", "quad8"])
def test_slave_above_flat_face(name: str) -> None:
    """A penetrating slave node of a flat face in z = 0 gets f_p = −A p(d) n, n = e_z."""
    ft = FACE_TYPES[name]
    scale = SIZE if ft.is_triangle else SIZE / 2
    coords = np.zeros((3, ft.num_nodes, 3))
    coords[:, :, :2] = ft.node_parameters * scale
    xi = np.array([[0.2, 0.3], [0.1, 0.1], [0.25, 0.5]])
    depth = np.array([1e-3, 0.0, 0.02])
    slave = face_points(ft, coords, xi) - depth[:, None] * np.array([0, 0, 1.0])
    areas = np.array([0.7, 1.0, 1.3])
    ev = evaluate_springs(ft, coords, slave, areas, LINEAR)
    np.testing.assert_allclose(ev.xi, xi, atol=1e-12)
    np.testing.assert_allclose(ev.normal, np.tile([0.0, 0.0, 1.0], (3, 1)), atol=1e-15)
    np.testing.assert_allclose(ev.gap, -depth, atol=1e-15)
    expected = areas * LINEAR.pressure(depth)
    np.testing.assert_allclose(ev.normal_force, expected, rtol=1e-13)
    np.testing.assert_allclose(ev.forces[:, -1], -expected[:, None] * ev.normal, rtol=1e-13)
    np.testing.assert_allclose(
        ev.forces[:, :-1],
        ev.phi[:, :, None] * expected[:, None, None] * ev.normal[:, None],
        rtol=1e-12,
        atol=1e-15,
    )
    np.testing.assert_allclose(ev.phi, ft.shape_functions(xi), atol=1e-12)
    np.testing.assert_allclose(ev.force_per_area, ev.forces / areas[:, None, None], rtol=1e-14)
    # d = 0 with the linear law still carries the smoothing term: F_N = A K d/2 at d = 0 is 0.
    assert ev.normal_force[1] == pytest.approx(0.0, abs=1e-14)


def test_gap_shift() -> None:
    ft = FACE_TYPES["quad4"]
    coords, slave, areas, _, depth = _penetrating(ft, 0.15, 6, seed=4)
    shift = np.linspace(-0.01, 0.01, 6)
    ev = evaluate_springs(ft, coords, slave, areas, EXPONENTIAL, gap_shift=shift)
    np.testing.assert_allclose(ev.gap, -depth, rtol=1e-9)
    np.testing.assert_allclose(ev.overclosure, depth + shift, rtol=1e-9)
    f_expected, _ = EXPONENTIAL.spring_force(depth + shift, areas)
    np.testing.assert_allclose(ev.normal_force, f_expected, rtol=1e-9)
    # Scalar shift equal to a spring's own gap cancels its overclosure.
    ev0 = evaluate_springs(ft, coords[:1], slave[:1], areas[:1], LINEAR, gap_shift=-depth[0])
    assert ev0.overclosure[0] == pytest.approx(0.0, abs=1e-15)
    # The shift is constant: the tangent still matches finite differences.
    fd = _finite_difference(ft, coords, slave, areas, EXPONENTIAL, h=1e-7 * SIZE, gap_shift=shift)
    assert relative_error(ev.stiffness, fd).max() <= 1e-6


def _outside(ft: FaceType, where: str, num: int, seed: int):
    """Slave nodes beside an edge ("edge") or a corner ("corner"), below the face plane.

    The in-plane offset r_t is chosen so that (r·q_ξ, r·q_η) = Σ λ_i c_i with multipliers
    λ_i > 0 of the active edges (outward parametric normals c_i): the closest point is then on
    the boundary at ``xi`` with strictly active constraints.
    """
    rng = np.random.default_rng(seed)
    coords = _faces(ft, num, 0.0, rng)
    if ft.is_triangle:
        # Edge 1-2 (η = 0) or corner 2 (ξ = 1, η = 0).
        xi = np.stack([rng.uniform(0.2, 0.8, num), np.zeros(num)], axis=1)
        normals = [np.array([0.0, -1.0])]
        if where == "corner":
            xi[:] = [1.0, 0.0]
            normals.append(np.array([1.0, 1.0]))
    else:
        # Edge ξ = 1 or corner (1, 1).
        xi = np.stack([np.ones(num), rng.uniform(-0.5, 0.5, num)], axis=1)
        normals = [np.array([1.0, 0.0])]
        if where == "corner":
            xi[:] = [1.0, 1.0]
            normals.append(np.array([0.0, 1.0]))
    jac = np.stack(face_tangents(ft, coords, xi), axis=2)  # (N, 3, 2)
    grad = sum(rng.uniform(0.02, 0.1, (num, 1)) * c for c in normals) * SIZE**2
    offset = np.einsum("nia,nab,nb->ni", jac, np.linalg.inv(jac.transpose(0, 2, 1) @ jac), grad)
    depth = rng.uniform(0.002, 0.05, num) * SIZE
    n = _unit_normal(ft, coords, xi)
    slave = face_points(ft, coords, xi) + offset - depth[:, None] * n
    return coords, slave, rng.uniform(0.5, 2.0, num), xi, depth


@pytest.mark.parametrize("where", ["edge", "corner"])
@pytest.mark.parametrize("name", ["tri3", "quad4", "tri6", "quad8", "quad9"])
def test_clamped_projection_tangent(name: str, where: str) -> None:
    """Slave beside the face: the constrained-projection tangent is exact."""
    ft = FACE_TYPES[name]
    coords, slave, areas, xi, depth = _outside(ft, where, 6, seed=5)
    ev = evaluate_springs(ft, coords, slave, areas, EXPONENTIAL)
    np.testing.assert_allclose(ev.xi, xi, atol=1e-9)
    np.testing.assert_allclose(ev.overclosure, depth, rtol=1e-8)
    fd = _finite_difference(ft, coords, slave, areas, EXPONENTIAL, h=1e-7 * SIZE)
    error = relative_error(ev.stiffness, fd)
    assert error.max() <= 1e-6, error
    # Still in equilibrium (forces), but r is not ∥ n: the moments do not balance and the forces
    # are no longer the gradient of A P(d), so the exact tangent is unsymmetric.
    np.testing.assert_allclose(ev.forces.sum(axis=1), 0.0, atol=1e-12 * np.abs(ev.forces).max())
    nodes = np.concatenate([coords, slave[:, None, :]], axis=1)
    moments = np.linalg.norm(np.cross(nodes, ev.forces).sum(axis=1), axis=1)
    assert np.all(moments > 1e-6 * np.abs(ev.forces).max())
    asym = relative_error(ev.stiffness, ev.stiffness.transpose(0, 2, 1))
    assert asym.min() > 1e-4
    # A start point does not change the result.
    ev0 = evaluate_springs(ft, coords, slave, areas, EXPONENTIAL, xi0=ft.clamp(xi + 0.05))
    np.testing.assert_allclose(ev0.xi, ev.xi, atol=1e-12)
    scale = np.abs(ev.stiffness).max()
    np.testing.assert_allclose(ev0.stiffness, ev.stiffness, rtol=1e-9, atol=1e-9 * scale)


@pytest.mark.parametrize("where", ["edge", "corner"])
@pytest.mark.parametrize("name", ["tri3", "quad4", "quad8"])
def test_interior_projection_tangent_is_calculix_s(name: str, where: str) -> None:
    """``interior_projection``: the forces stay; the tangent changes only at clamped projections,
    where it takes the interior formula (CalculiX's) instead of the exact constrained one."""
    ft = FACE_TYPES[name]
    coords, slave, areas, _, _ = _outside(ft, where, 6, seed=5)
    exact = evaluate_springs(ft, coords, slave, areas, EXPONENTIAL)
    ccx = evaluate_springs(ft, coords, slave, areas, EXPONENTIAL, interior_projection=True)
    np.testing.assert_array_equal(ccx.forces, exact.forces)
    fd = _finite_difference(ft, coords, slave, areas, EXPONENTIAL, h=1e-7 * SIZE)
    assert relative_error(ccx.stiffness, fd).min() > 1e-3  # not the derivative there
    inside, other, inside_areas, _ = _penetrating(ft, 0.0, 6, seed=7)[:4]
    exact = evaluate_springs(ft, inside, other, inside_areas, EXPONENTIAL)
    ccx = evaluate_springs(ft, inside, other, inside_areas, EXPONENTIAL, interior_projection=True)
    np.testing.assert_array_equal(ccx.stiffness, exact.stiffness)


def test_tangent_flag_and_area_fallback() -> None:
    ft = FACE_TYPES["quad4"]
    coords, slave, areas, _, depth = _penetrating(ft, 0.0, 4, seed=6)
    assert evaluate_springs(ft, coords, slave, areas, LINEAR, tangent=False).stiffness is None
    areas[1] = 0.0
    ev = evaluate_springs(ft, coords, slave, areas, LINEAR)
    t1, t2 = face_tangents(ft, coords[1], ev.xi[1])
    assert ev.area[1] == pytest.approx(4.0 * np.linalg.norm(np.cross(t1, t2)), rel=1e-13)
    np.testing.assert_array_equal(ev.area[[0, 2, 3]], areas[[0, 2, 3]])
    off = evaluate_springs(ft, coords, slave, areas, LINEAR, area_fallback=False)
    assert off.normal_force[1] == 0.0
    np.testing.assert_array_equal(off.forces[1], 0.0)
    expected = -LINEAR.pressure(depth[1]) * off.normal[1]
    np.testing.assert_allclose(off.force_per_area[1, -1], expected, rtol=1e-9)
    np.testing.assert_allclose(off.force_per_area[1, :-1], -off.phi[1, :, None] * expected)
    # tri3: A = |m|/2.
    tri = FACE_TYPES["tri3"]
    coords, slave, _, _, _ = _penetrating(tri, 0.0, 1, seed=7)
    ev = evaluate_springs(tri, coords, slave, np.zeros(1), LINEAR)
    t1, t2 = face_tangents(tri, coords[0], ev.xi[0])
    assert ev.area[0] == pytest.approx(0.5 * np.linalg.norm(np.cross(t1, t2)), rel=1e-13)


def test_bad_input() -> None:
    ft = FACE_TYPES["quad4"]
    coords, slave, areas, _, _ = _penetrating(ft, 0.0, 3, seed=8)
    with pytest.raises(ValueError, match="master_coords"):
        evaluate_springs(ft, coords[:, :3], slave, areas, LINEAR)
    with pytest.raises(ValueError, match="slave_coords"):
        evaluate_springs(ft, coords, slave[:2], areas, LINEAR)
    with pytest.raises(ValueError, match="areas"):
        evaluate_springs(ft, coords, slave, areas[:2], LINEAR)
    with pytest.raises(ValueError, match="areas must be >= 0"):
        evaluate_springs(ft, coords, slave, -areas, LINEAR)
    with pytest.raises(ValueError, match="gap_shift"):
        evaluate_springs(ft, coords, slave, areas, LINEAR, gap_shift=np.zeros(2))
    bad = slave.copy()
    bad[2, 0] = np.nan
    with pytest.raises(ValueError, match=r"slave_coords is not finite at springs \[2\]"):
        evaluate_springs(ft, coords, bad, areas, LINEAR)
    collapsed = coords.copy()
    collapsed[1] = collapsed[1, 0]
    with pytest.raises(ValueError, match=r"degenerate.*1"):
        evaluate_springs(ft, collapsed, slave, areas, LINEAR)


def test_empty_batch() -> None:
    ft = FACE_TYPES["tri6"]
    ev = evaluate_springs(ft, np.zeros((0, 6, 3)), np.zeros((0, 3)), np.zeros(0), LINEAR)
    assert ev.forces.shape == (0, 7, 3)
    assert ev.stiffness.shape == (0, 21, 21)


def test_large_batch() -> None:
    """10^4 quad4 springs, residual + tangent (timing: benchmarks/contact_phases.py)."""
    ft = FACE_TYPES["quad4"]
    num = 10_000
    rng = np.random.default_rng(9)
    params = ft.node_parameters * SIZE / 2
    coords = np.zeros((num, 4, 3))
    coords[:, :, :2] = params + 0.05 * rng.uniform(-1, 1, (num, 4, 2))
    coords[:, :, 2] = 0.05 * rng.uniform(-1, 1, (num, 4))
    xi = rng.uniform(-0.8, 0.8, (num, 2))
    slave = face_points(ft, coords, xi) - 0.01 * _unit_normal(ft, coords, xi)
    ev = evaluate_springs(ft, coords, slave, np.ones(num), LINEAR)
    assert ev.stiffness.shape == (num, 15, 15)
    assert np.all(ev.normal_force > 0)
