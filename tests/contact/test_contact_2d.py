"""Native 2D contact (plane strain, node-to-segment springs) on gmsh triangle meshes.

A patch test (two blocks, uniform pressure transmitted exactly on matching meshes, P1 and P2), the
plane-strain Hertz line contact of a cylinder on a block (half model), and the clear errors for
what 2D does not support yet (friction: test_friction_2d.py, ADJUST: test_adjust_2d.py).
"""

from __future__ import annotations

import gmsh
import numpy as np
import pytest
from helpers.gmsh_blocks_2d import (
    LEFT,
    LOWER_BOTTOM,
    LOWER_TOP,
    UPPER_BOTTOM,
    UPPER_TOP,
    stacked_rectangles,
)

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

pytestmark = pytest.mark.serial

E, NU = 1000.0, 0.3
SYMMETRY = LEFT


def _build_blocks(nx_upper: int, order: int) -> None:
    """A 1 x 0.4 block on a 1 x 0.5 block, touching along y = 0 (separate nodes)."""
    stacked_rectangles(
        "blocks_2d", (0.0, -0.5, 1.0, 0.0, 4, 2), (0.0, 0.0, 1.0, 0.4, nx_upper, 2), order
    )


def _problem(mesh, facet_tags, order, bcs_of, load_form, pair_options=None):
    """Plane-strain elasticity of one material, the slave UPPER_BOTTOM on the master LOWER_TOP."""
    V = compat.vector_space(mesh, "Lagrange", order)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    load = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx + load_form(load, v, ds)
    options = pair_options or {}
    interaction = options.pop("interaction", None) or ntf.SurfaceInteraction(
        ntf.LinearLaw(slope=1e4 * E, tension=E / 70000)
    )
    pair = ntf.ContactPair(
        ntf.FacetSurface(facet_tags, UPPER_BOTTOM),
        options.pop("master", None) or ntf.FacetSurface(facet_tags, LOWER_TOP),
        interaction,
        **options,
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs_of(V))
    return problem, load


def _solve(problem, load, value, increment):
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    step = ntf.StaticStep(lambda t: setattr(load, "value", value * t), initial_increment=increment)
    return step.run(solver, problem.u)


def _blocks_problem(order: int, nx_upper: int = 4, **pair_options):
    mesh, _, facet_tags = mesh_from_gmsh(_build_blocks, gdim=2, nx_upper=nx_upper, order=order)

    def bcs(V):  # rollers: x = 0 for both blocks, y = 0 under the lower one
        return [
            component_bc(V, 0, facet_tags.find(SYMMETRY)),
            component_bc(V, 1, facet_tags.find(LOWER_BOTTOM)),
        ]

    def pressure(load, v, ds):  # pressure `load` on the upper top
        return (
            load
            * ufl.inner(ufl.FacetNormal(v.ufl_function_space().mesh.ufl_domain()), v)
            * ds(UPPER_TOP)
        )

    return _problem(mesh, facet_tags, order, bcs, pressure, pair_options)


@pytest.mark.parametrize("order", [1, 2])
def test_patch_test_uniform_pressure_2d(order: int) -> None:
    """Matching edges: the pressure is uniform to 1e-8 and carries the load (1e-10)."""
    problem, load = _blocks_problem(order)
    results = _solve(problem, load, 10.0, 0.5)
    assert all(r.iterations <= 3 for r in results)
    state = problem.states[0]
    ev = state.evaluation
    assert state.num_springs == 4 * order + 1  # every slave node, corners and midside nodes
    pressure = ev.normal_force / ev.area
    np.testing.assert_allclose(pressure, pressure.mean(), rtol=1e-8)
    assert pressure.mean() == pytest.approx(10.0, rel=1e-2)  # load over the current length
    # The springs' vertical forces on the upper block balance the load on its top (width 1).
    assert -ev.forces[:, -1, 1].sum() == pytest.approx(10.0, rel=1e-10)
    assert ev.forces.shape[-1] == 2 and ev.stiffness.shape[1:] == (2 * (order + 2),) * 2


def test_nonmatching_patch_balances_the_load_2d() -> None:
    """Non-matching edges: one-pass node-to-segment is not uniform, but the resultant balances."""
    problem, load = _blocks_problem(1, nx_upper=3)
    _solve(problem, load, 10.0, 0.5)
    ev = problem.states[0].evaluation
    pressure = ev.normal_force / ev.area
    assert np.ptp(pressure) / pressure.mean() > 1e-2
    assert -ev.forces[:, -1, 1].sum() == pytest.approx(10.0, rel=1e-10)


# Plane-strain Hertz: cylinder radius R on a block, equal materials, half model x >= 0.
RADIUS, BLOCK = 1.0, 4.0
E_STAR = E / (2 * (1 - NU**2))
HALF_WIDTH = 0.05
LINE_LOAD = np.pi * E_STAR * HALF_WIDTH**2 / (4 * RADIUS)  # b = sqrt(4 P R / (pi E*))


def _build_cylinder_on_block(h_contact: float, order: int) -> None:
    """Quarter disc (centre (0, R)) touching the block [0, 4R] x [-4R, 0] at the origin."""
    gmsh.model.add("hertz_2d")
    g = gmsh.model.geo
    corners = [(0, -BLOCK), (BLOCK, -BLOCK), (BLOCK, 0), (0, 0)]
    p = [g.addPoint(x, y, 0) for x, y in corners]
    block = [g.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]
    lower = g.addPlaneSurface([g.addCurveLoop(block)])
    bottom, right, centre = (
        g.addPoint(0, 0, 0),
        g.addPoint(RADIUS, RADIUS, 0),
        g.addPoint(0, RADIUS, 0),
    )
    arc, top, axis = (
        g.addCircleArc(bottom, centre, right),
        g.addLine(right, centre),
        g.addLine(centre, bottom),
    )
    upper = g.addPlaneSurface([g.addCurveLoop([arc, top, axis])])
    g.synchronize()
    model = gmsh.model
    model.addPhysicalGroup(2, [lower], 1)
    model.addPhysicalGroup(2, [upper], 2)
    model.addPhysicalGroup(1, [block[2]], LOWER_TOP)
    model.addPhysicalGroup(1, [arc], UPPER_BOTTOM)
    model.addPhysicalGroup(1, [top], UPPER_TOP)
    model.addPhysicalGroup(1, [block[0]], LOWER_BOTTOM)
    model.addPhysicalGroup(1, [block[3], axis], SYMMETRY)
    field = model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "PointsList", [p[3], bottom])
    threshold = field.add("Threshold")
    field.setNumber(threshold, "InField", distance)
    field.setNumber(threshold, "SizeMin", h_contact)
    field.setNumber(threshold, "SizeMax", 0.3)
    field.setNumber(threshold, "DistMin", 2.5 * HALF_WIDTH)
    field.setNumber(threshold, "DistMax", 1.5)
    field.setAsBackgroundMesh(threshold)
    for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{option}", 0)
    model.mesh.generate(2)
    model.mesh.setOrder(order)


def _hertz_fit(x: np.ndarray, pressure: np.ndarray) -> tuple[float, float]:
    """(b, p0) of p = p0 sqrt(1 - x²/b²) by least squares on p² (the inner 80 % of the width)."""
    inside = pressure > 0.0
    half_width = x[inside].max()
    for _ in range(3):
        chosen = inside & (x < 0.8 * half_width)
        a, c = np.linalg.lstsq(
            np.stack([np.ones(chosen.sum()), x[chosen] ** 2], axis=1),
            pressure[chosen] ** 2,
            rcond=None,
        )[0]
        half_width = np.sqrt(-a / c)
    return float(half_width), float(np.sqrt(a))


def test_hertz_line_contact_plane_strain() -> None:
    """Cylinder on block: b and p0 of Hertz within 1 % and 2 %, contact force = reaction (1e-8)."""
    mesh, _, facet_tags = mesh_from_gmsh(
        _build_cylinder_on_block, gdim=2, h_contact=HALF_WIDTH / 10, order=1
    )

    def bcs(V):
        bottom = facet_tags.find(LOWER_BOTTOM)
        return [
            component_bc(V, 0, facet_tags.find(SYMMETRY)),
            component_bc(V, 0, bottom),
            component_bc(V, 1, bottom),
        ]

    def line_load(load, v, ds):  # half the line load, spread over the top (width R)
        return load / (2 * RADIUS) * v[1] * ds(UPPER_TOP)

    problem, load = _problem(mesh, facet_tags, 1, bcs, line_load)
    results = _solve(problem, load, LINE_LOAD, 0.25)
    assert sum(r.iterations for r in results) <= 40
    state = problem.states[0]
    ev = state.evaluation
    pressure = ev.normal_force / ev.area
    x = problem.current_coordinates()[state.slave.nodes[state.spring_slave], 0]
    half_width, peak = _hertz_fit(x, pressure)
    assert half_width == pytest.approx(HALF_WIDTH, rel=1e-2)
    assert peak == pytest.approx(2 * LINE_LOAD / (np.pi * HALF_WIDTH), rel=2e-2)
    assert np.count_nonzero(pressure > 0) >= 8
    contact_force = -ev.forces[:, -1, 1].sum()  # of the block on the cylinder
    residual = dolfinx.fem.petsc.assemble_vector(problem.L)
    V = problem.u.function_space
    bottom = dolfinx.fem.locate_dofs_topological(V, 1, facet_tags.find(LOWER_BOTTOM))
    reaction = residual.array[2 * bottom + 1].sum()
    assert contact_force == pytest.approx(reaction, rel=1e-8)
    assert contact_force == pytest.approx(LINE_LOAD / 2, rel=1e-8)


@pytest.mark.parametrize(
    "options",
    [
        {"interaction": ntf.SurfaceInteraction(ntf.LinearLaw(1e4, 1e-2), ntf.Friction(0.3, 1e4))},
        {"adjust": 0.01},
    ],
    ids=["friction", "adjust"],
)
def test_rigid_line_refuses_friction_and_adjust_2d(options: dict) -> None:
    """As in 3D: friction and ADJUST need a meshed master; the error names the pair."""
    line = ntf.RigidPlane((0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    with pytest.raises(NotImplementedError, match="pair 1: friction and ADJUST against a rigid"):
        _blocks_problem(1, master=line, **options)
