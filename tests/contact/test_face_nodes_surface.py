"""``FaceNodesSurface``: a face-based surface given by its faces' nodes (docs/method.md §38).

The deck runner gives C3D15's surfaces this way (a prism mesh has no facet numbering in dolfinx
0.11); here the same faces as a ``FacetSurface``'s, given by their nodes, must give the same
springs and solution on any mesh, serial and on 2 processes.
"""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import (
    LOWER_TOP,
    PUNCH,
    UPPER_BOTTOM,
    YOUNGS_MODULUS,
    displacement_fields,
    elastic_residual,
    punch_conditions,
    solve_increments,
    two_blocks,
)
from helpers.jacobian_check import directional_derivative

import dolfinx_ntf as ntf
from dolfinx_ntf.contact.pairing import slave_areas
from dolfinx_ntf.fem.surfaces import NO_FACET, resolve_master, resolve_slave
from dolfinx_ntf.kernels.faces import QUAD4, TRI3, TRI6
from dolfinx_ntf.kernels.spring_areas import spring_areas


def _as_nodes(V, surface: ntf.FacetSurface, name: str) -> ntf.FaceNodesSurface:
    """The faces of ``surface`` (this process's, in ccx order) given by their nodes."""
    faces = resolve_master(V, surface)
    return ntf.FaceNodesSurface(faces.face_type, faces.faces, name)


@pytest.mark.mpi
@pytest.mark.parametrize("cell, degree, face_type", [("hexahedron", 1, QUAD4),
                                                     ("tetrahedron", 2, TRI6)])  # fmt: skip
def test_face_nodes_surface_solves_as_the_facet_surface(cell, degree, face_type):
    """The punch pressed in 2 increments: the same springs and displacement to round-off."""
    mesh, _, ft = two_blocks(MPI.COMM_WORLD, cell=cell, upper=PUNCH)
    solutions, springs = [], []
    for by_nodes in (False, True):
        V, u, v, pressure = displacement_fields(mesh, degree)
        slave, master = ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP)
        if by_nodes:
            slave, master = _as_nodes(V, slave, "slave"), _as_nodes(V, master, "master")
            assert master.face_type is face_type
        law = ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS)
        pair = ntf.ContactPair(slave, master, ntf.SurfaceInteraction(law))
        problem = ntf.ContactProblem(
            elastic_residual(u, v, ft, pressure), u, [pair], punch_conditions(V, ft)
        )
        if by_nodes:  # no dolfinx facets behind the faces
            assert np.all(problem.states[0].slave.faces.facets == NO_FACET)
        solve_increments(problem, pressure)
        solutions.append(u.x.array.copy())
        springs.append(problem.total_springs)
        ntf.ContactFields(problem)  # the recovered pressure skips faces without facets
    scale = MPI.COMM_WORLD.allreduce(float(np.abs(solutions[0]).max()), op=MPI.MAX)
    assert scale > 1e-3 and springs[0] > 0
    assert springs[1] == springs[0]
    np.testing.assert_allclose(solutions[1], solutions[0], rtol=0.0, atol=1e-11 * scale)


@pytest.mark.serial
def test_face_nodes_surface_checks_its_faces_and_pairs():
    mesh, _, ft = two_blocks(MPI.COMM_SELF, upper=PUNCH)
    V, u, v, pressure = displacement_fields(mesh)
    with pytest.raises(ValueError, match=r"faces must be an integer array of shape \(F, 4\)"):
        ntf.FaceNodesSurface(QUAD4, np.zeros((2, 3), dtype=np.int32), "bad")
    with pytest.raises(ValueError, match="faces must hold block dofs >= 0, got -1"):
        ntf.FaceNodesSurface(QUAD4, -np.ones((1, 4), dtype=np.int32), "bad")
    with pytest.raises(TypeError, match="face_type must be a FaceType, got str"):
        ntf.FaceNodesSurface("quad4", np.zeros((1, 4), dtype=np.int32), "bad")
    slave = _as_nodes(V, ntf.FacetSurface(ft, UPPER_BOTTOM), "slave")
    master = _as_nodes(V, ntf.FacetSurface(ft, LOWER_TOP), "master")
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS))
    F, bcs = elastic_residual(u, v, ft, pressure), punch_conditions(V, ft)
    outside = ntf.FaceNodesSurface(QUAD4, master.faces + V.dofmap.index_map.size_local, "far")
    with pytest.raises(ValueError, match=r"FaceNodesSurface 'far' has node \d+, outside 0\.\."):
        ntf.ContactProblem(F, u, [ntf.ContactPair(slave, outside, law)], bcs)
    # identical pairs are found by their faces' nodes (faces given by nodes have no facets)
    twice = [ntf.ContactPair(slave, master, law), ntf.ContactPair(slave, master, law)]
    with pytest.raises(ValueError, match="pairs 'pair 1' and 'pair 2' are the same"):
        ntf.ContactProblem(F, u, twice, bcs)
    half = ntf.FaceNodesSurface(QUAD4, master.faces[: master.faces.shape[0] // 2], "half")
    with pytest.warns(UserWarning, match=r"share \d+ slave node\(s\) and master faces"):
        ntf.ContactProblem(
            F, u, [ntf.ContactPair(slave, master, law), ntf.ContactPair(slave, half, law)], bcs
        )


@pytest.mark.serial
def test_face_nodes_surface_of_two_face_types():
    """Triangles beside quadrilaterals (C3D15, docs/method.md §38): a slave surface whose nodes
    collect both types' shares; a master of one type only; each type given once."""
    mesh, _, ft = two_blocks(MPI.COMM_SELF, upper=PUNCH)
    V = displacement_fields(mesh)[0]
    faces = _as_nodes(V, ntf.FacetSurface(ft, UPPER_BOTTOM), "slave").faces
    half = faces.shape[0] // 2
    quads, rest = faces[:half], faces[half:]
    triangles = np.vstack([rest[:, [0, 1, 2]], rest[:, [0, 2, 3]]])  # the other half, split
    mixed = ntf.FaceNodesSurface(QUAD4, quads, "mixed", more=((TRI3, triangles),))
    with pytest.raises(ValueError, match="a face type is given twice"):
        ntf.FaceNodesSurface(QUAD4, quads, "twice", more=((QUAD4, rest),))
    with pytest.raises(TypeError, match=r"more\[0\] must be a \(face_type, faces\) tuple"):
        ntf.FaceNodesSurface(QUAD4, quads, "bad", more=(TRI3,))
    with pytest.raises(NotImplementedError, match="a master surface of one face type only"):
        resolve_master(V, mixed)
    slave = resolve_slave(V, mixed)
    assert [g.face_type for g in slave.face_groups] == [QUAD4, TRI3]
    X = V.tabulate_dof_coordinates()
    areas = slave_areas(slave, X)
    expected = spring_areas(QUAD4, quads, X, slave.nodes) + spring_areas(
        TRI3, triangles, X, slave.nodes
    )
    np.testing.assert_allclose(areas, expected, rtol=1e-14)
    # the nodes' total is the surface's area (0.6 x 0.6), whichever types hold it
    assert areas.sum() == pytest.approx(0.36, rel=1e-12)
    np.testing.assert_array_equal(slave.nodes, np.unique(faces))


def _mixed_punch(comm: MPI.Comm, **options) -> tuple:
    """The punch whose slave faces with x < 0.5 are given as two triangles each: the problem,
    the pressure and the space."""
    mesh, _, ft = two_blocks(comm, upper=PUNCH)
    V, u, v, pressure = displacement_fields(mesh)
    faces = _as_nodes(V, ntf.FacetSurface(ft, UPPER_BOTTOM), "slave").faces
    X = V.tabulate_dof_coordinates()
    split = X[faces].mean(axis=1)[:, 0] < 0.5
    rest = faces[split]
    triangles = np.vstack([rest[:, [0, 1, 2]], rest[:, [0, 2, 3]]])
    slave = ntf.FaceNodesSurface(QUAD4, faces[~split], "mixed", more=((TRI3, triangles),))
    master = ntf.FacetSurface(ft, LOWER_TOP)
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS))
    problem = ntf.ContactProblem(
        elastic_residual(u, v, ft, pressure), u, [ntf.ContactPair(slave, master, law)],
        punch_conditions(V, ft), **options,
    )  # fmt: skip
    assert comm.allreduce(int(np.any(split)), op=MPI.SUM) > 0
    return problem, pressure, V


@pytest.mark.mpi
def test_slave_of_two_face_types_carries_the_punch():
    """A slave surface given half as quadrilaterals, half as triangles (the faces with x < 0.5
    split in two): its springs carry the pressure on the punch (equilibrium) and its areas add
    up to the surface's, serial and on 2 processes (each type's faces sent to their owners)."""
    comm = MPI.COMM_WORLD
    problem, pressure, V = _mixed_punch(comm)
    solve_increments(problem, pressure, load=10.0)
    (result,) = ntf.contact_results(problem)
    total = comm.allreduce(float(result.force[:, 2].sum()), op=MPI.SUM)
    assert total == pytest.approx(10.0 * 0.36, rel=1e-8)  # the pressure on the punch's top
    state = problem.states[0]
    assert len(state.slave.more_faces) == 1 and state.slave.more_faces[0].face_type is TRI3
    owned = state.slave.nodes < V.dofmap.index_map.size_local  # each node once
    areas = slave_areas(state.slave, problem.reference_coordinates)
    assert comm.allreduce(float(areas[owned].sum()), op=MPI.SUM) == pytest.approx(0.36, rel=1e-12)


@pytest.mark.serial
def test_area_tangent_of_two_face_types_is_the_derivative():
    """``linearize_area``: the tangent of the areas of both types' faces (their gradients added)
    equals central differences of the residual."""
    problem, pressure, _ = _mixed_punch(MPI.COMM_SELF, linearize_area=True)
    solve_increments(problem, pressure, increments=1)
    check = directional_derivative(problem, amplitude=1e-3, h=1e-4, seed=1)
    np.testing.assert_allclose(check.product, check.difference, atol=1e-6 * check.contact_scale)
    assert problem.states[0].slave.more_faces  # the check above saw the triangles
