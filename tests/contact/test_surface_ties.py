"""Surface ties between non-matching meshes (dolfinx_ntf.contact.ties, ccx *TIE; method §19.1).

Serial and on 2 ranks: every check compares scalars or fields of one mesh with an exact field.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER_TOP, UPPER_BOTTOM, box_grid, two_blocks

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.contact.ties import Tie, tie_constraints
from dolfinx_ntf.fem.elasticity import small_strain_stress
from dolfinx_ntf.kernels.cyclic_symmetry import CyclicMatch, cyclic_rows
from dolfinx_ntf.kernels.faces import face_type_from_num_nodes
from dolfinx_ntf.kernels.search import MasterSurface
from dolfinx_ntf.kernels.surface_tie import default_tolerance, project_on_master, tie_rows

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD
E, NU, STRAIN = 1000.0, 0.3, 1e-3
CCX_TOLERANCE = 7.1129449216106146e-3  # ccx 2.20's default *TIE tolerance, unit square faces

# ----------------------------------------------------------------------------- kernels


def test_projection_weights_reproduce_the_point_and_far_nodes_are_not_tied():
    quad = face_type_from_num_nodes(4)
    coords = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [1, 1, 0], [2, 1, 0.2]], float)
    faces = np.array([[0, 1, 4, 3], [1, 2, 5, 4]])
    master = MasterSurface(quad, faces, coords=coords)
    points = np.array([[0.3, 0.7, 0.001], [1.6, 0.4, 0.2], [0.5, 0.5, 0.5], [2.005, 0.5, 0.1]])
    # ccx 2.20 prints this tolerance for a master of unit square faces
    assert default_tolerance(quad, faces[:1], coords) == pytest.approx(CCX_TOLERANCE, rel=1e-15)
    tolerance = default_tolerance(quad, faces, coords)
    projection = project_on_master(master, coords, points, tolerance)
    assert projection.face.tolist()[:2] == [0, 1]
    assert projection.tied.tolist() == [True, False, False, True]  # 1, 2: above; 3: beyond the rim
    # the weights interpolate the face: the tied points' projections, and rows sum to one
    x = np.einsum("sn,snc->sc", projection.weights, coords[faces[projection.face]])
    np.testing.assert_allclose(x, projection.points, atol=1e-14)
    np.testing.assert_allclose(projection.weights.sum(axis=1), 1.0)
    assert projection.distance[0] == pytest.approx(0.001)
    nodes, components, coefficients = tie_rows([9], faces[:1], projection.weights[:1])
    assert nodes.shape == (3, 5) and components[:, 0].tolist() == [0, 1, 2]
    assert np.all(components == components[:, :1]) and np.all(coefficients[:, 0] == 1.0)


def test_cyclic_rows_hold_for_a_cyclic_symmetric_field_and_not_for_a_uniform_one():
    """Faces of a 40 degree sector about the axis (1, 1, 0) + t (0, 0, 1): a radial field satisfies
    ``u_s = R^T u_m``, a uniform translation along x does not."""
    axis_point = np.array([1.0, 1.0, 0.0])
    radius, height = np.meshgrid([0.5, 1.0, 2.0], [0.0, 0.3], indexing="ij")
    r, h = radius.ravel(), height.ravel()
    angle = np.radians(40.0)
    master_x = axis_point + np.column_stack([r, np.zeros_like(r), h])
    slave_x = axis_point + np.column_stack([r * np.cos(angle), r * np.sin(angle), h])
    order = np.arange(r.size)[::-1]  # any numbering
    match = CyclicMatch(
        slave_x, master_x[order], axis_point, axis_point + np.array([0.0, 0.0, 2.0]), 9, 1e-9
    )
    np.testing.assert_array_equal(order[match.master], np.arange(r.size))
    assert match.angle == pytest.approx(-angle) and match.angle_error < 1e-12
    nodes, components, coefficients = cyclic_rows(np.arange(r.size), r.size + match.master,
                                                   match.rotation)  # fmt: skip
    x = np.vstack([slave_x, master_x[order]])

    def residual(u):
        return np.einsum("kj,kj->k", coefficients, u[nodes, components])

    radial = 0.01 * (x - axis_point) * [1.0, 1.0, 0.0] + [0.0, 0.0, 0.002]
    assert np.abs(residual(radial)).max() < 1e-15
    assert np.abs(residual(np.tile([0.01, 0.0, 0.0], (x.shape[0], 1)))).max() > 1e-3
    with pytest.raises(ValueError, match="the two points of the axis coincide"):
        CyclicMatch(slave_x, master_x, axis_point, axis_point, 9, 1e-9)


# ----------------------------------------------------------------------------- two blocks


def _blocks_problem(lower_div, upper_div, direction, *, tolerance=None, gap=0.0):
    """Two blocks stacked along z, tied (upper bottom to lower top), under uniaxial strain."""
    mesh, _, ft = two_blocks(
        lower=((0, 0, -1), (1, 1, 1), lower_div), upper=((0, 0, 0), (1, 1, 1), upper_div), gap=gap
    )
    V = compat.vector_space(mesh, "Lagrange", 1)
    tie = Tie(ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), tolerance)
    constraints, tied = tie_constraints(V, tie)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx
    top = 1.0 + gap
    bcs = []
    for c in range(3):  # symmetry planes x = 0, y = 0, z = -1; the far face pulled along c
        Vc, _ = compat.component_space(V, c)
        planes = [(c, -1.0 if c == 2 else 0.0, 0.0)]
        if c == direction:
            planes.append((c, top if c == 2 else 1.0, STRAIN * (2.0 + gap if c == 2 else 1.0)))
        for axis, position, value in planes:
            facets = dolfinx.mesh.locate_entities_boundary(
                mesh, 2, lambda x, a=axis, p=position: np.isclose(x[a], p)
            )
            dofs = dolfinx.fem.locate_dofs_topological((V.sub(c), Vc), 2, facets)
            g = dolfinx.fem.Function(Vc)
            g.x.array[:] = value
            bcs.append(dolfinx.fem.dirichletbc(g, dofs, V.sub(c)))
    return ntf.ContactProblem(F, u, [], bcs, constraints=constraints), tied


def _solve(problem):
    solver = ntf.ContactNewtonSolver(problem.u.function_space.mesh.comm, problem)
    ntf.StaticStep(lambda t: None, initial_increment=1.0, fixed=True).run(solver, problem.u)


def _uniaxial_error(problem, direction):
    """Largest nodal difference from the exact uniaxial field (over all processes)."""
    V = problem.u.function_space
    X = V.tabulate_dof_coordinates()[: V.dofmap.index_map.size_local]
    shifted = X - np.array([0.0, 0.0, -1.0])
    exact = -NU * STRAIN * shifted
    exact[:, direction] = STRAIN * shifted[:, direction]
    u = problem.u.x.array.reshape(-1, 3)[: X.shape[0]]
    return COMM.allreduce(float(np.abs(u - exact).max(initial=0.0)), op=MPI.MAX)


@pytest.mark.parametrize("divisions", [((2, 2, 2), (3, 3, 2)), ((3, 3, 2), (2, 2, 2))])
def test_patch_test_along_the_interface_is_exact_on_non_matching_meshes(divisions):
    """Tension along x: no traction on the tied plane z = 0, the linear field is exact."""
    problem, tied = _blocks_problem(*divisions, direction=0)
    _solve(problem)
    assert _uniaxial_error(problem, 0) < 1e-12 * STRAIN
    assert COMM.allreduce(tied.slaves.size) == (divisions[1][0] + 1) * (divisions[1][1] + 1)


def test_patch_test_across_the_interface_is_exact_when_slave_faces_nest_in_master_faces():
    """Tension along z through the tie: exact when every slave face lies in one master face
    (the slave's nodal forces then integrate the master shape functions exactly, §19.1)."""
    problem, _ = _blocks_problem((2, 2, 2), (4, 4, 2), direction=2)
    _solve(problem)
    assert _uniaxial_error(problem, 2) < 1e-12 * STRAIN
    # a slave mesh that does not nest: not exact (one-pass node-to-face ties, as ccx's)
    problem, _ = _blocks_problem((2, 2, 2), (3, 3, 2), direction=2)
    _solve(problem)
    assert 1e-3 * STRAIN < _uniaxial_error(problem, 2) < 0.1 * STRAIN


def test_adjust_moves_slave_nodes_onto_the_master_and_a_far_node_is_named():
    h = 1.0 / 3.0
    problem, tied = _blocks_problem((3, 3, 2), (2, 2, 2), direction=0, gap=0.005 * h)
    assert tied.tolerance == pytest.approx(CCX_TOLERANCE * h, rel=1e-14)
    assert np.allclose(tied.distance, 0.005 * h)
    V = problem.u.function_space
    X = V.mesh.geometry.x
    assert COMM.allreduce(int(np.sum(np.isclose(X[:, 2], 0.0, atol=1e-15)))) > 0
    assert not np.any(np.isclose(X[:, 2], 0.005 * h))  # every slave node moved down to z = 0
    _solve(problem)
    assert _uniaxial_error(problem, 0) < 1e-12 * STRAIN
    with pytest.raises(ValueError, match=r"tie 'tie': 9 slave node\(s\) have no master face .* "
                       r"node\(s\) \d+ at \(0, 0, 0\.05\)"):  # fmt: skip
        _blocks_problem((3, 3, 2), (2, 2, 2), direction=0, gap=0.05)


# ----------------------------------------------------------------------------- cantilever


def _one_piece(divisions):
    points, cells = box_grid((0, 0, -2), (1, 1, 4), divisions)
    if COMM.rank:
        points, cells = np.empty((0, 3)), np.empty((0, 8), dtype=np.int64)
    element = compat.coordinate_element("hexahedron", 1)
    return compat.create_mesh(COMM, cells.astype(np.int64), points, element)


def _tip_deflection(mesh, ties=()):
    """Mean x-displacement of the top z = 2 of a column clamped at z = -2, sheared at its top."""
    V = compat.vector_space(mesh, "Lagrange", 1)
    constraints = [c for tie in ties for c in tie_constraints(V, tie)[0]]
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    top = np.sort(dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], 2.0)))
    tags = dolfinx.mesh.meshtags(mesh, 2, top.astype(np.int32), np.ones(top.size, np.int32))
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=tags)
    load = ufl.as_vector([0.01, 0.0, 0.0])
    F = ufl.inner(small_strain_stress(u, E, NU), ufl.grad(v)) * ufl.dx - ufl.inner(load, v) * ds(1)
    bottom = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], -2.0))
    clamp = dolfinx.fem.locate_dofs_topological(V, 2, bottom)
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), clamp, V)]
    _solve(ntf.ContactProblem(F, u, [], bcs, constraints=constraints))
    value = dolfinx.fem.assemble_scalar(dolfinx.fem.form(u[0] * ds(1)))
    return mesh.comm.allreduce(value, op=MPI.SUM)


def test_tied_cantilever_against_the_one_piece_solution():
    coarse, fine = _tip_deflection(_one_piece((2, 2, 8))), _tip_deflection(_one_piece((4, 4, 16)))
    assert 0.0 < coarse < fine

    def tied(upper):
        mesh, _, ft = two_blocks(lower=((0, 0, -2), (1, 1, 2), (2, 2, 4)), upper=upper)
        tie = Tie(ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP))
        return _tip_deflection(mesh, [tie])

    # matching meshes: the tie is the one-piece mesh's continuity, to round-off
    assert tied(((0, 0, 0), (1, 1, 2), (2, 2, 4))) == pytest.approx(coarse, rel=1e-12)
    # a finer upper part: between the coarse and the fine one-piece solutions (C3D8 locks less)
    for upper_divisions in ((3, 3, 4), (3, 3, 6)):
        assert coarse < tied(((0, 0, 0), (1, 1, 2), upper_divisions)) < fine


def test_bad_arguments_are_clear_errors():
    _, _, ft = two_blocks()
    with pytest.raises(TypeError, match="Tie 'tie': master"):
        Tie(ntf.FacetSurface(ft, UPPER_BOTTOM), ft)
    with pytest.raises(ValueError, match="position_tolerance must be a finite number > 0"):
        Tie(ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), -1.0)
    with pytest.raises(ValueError, match="untied must be"):
        Tie(ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), untied="warn")
