"""A master surface of two face types in the Python API (docs/method.md §38.8).

A hexahedral mesh has one face type, but a ``FaceNodesSurface`` may give its flat quadrilaterals
either as they are or split into two triangles each: the block's top as a master of quad4 and
tri3 faces (the faces with x < 0.5 split), one search over both and one pair state per type.
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
from dolfinx_ntf.fem.surfaces import resolve_master
from dolfinx_ntf.kernels.faces import QUAD4, TRI3


def _problem(comm: MPI.Comm, *, mixed: bool, friction: bool = False, **options) -> tuple:
    """The punch on the block whose top is a master of quadrilaterals and (``mixed``) triangles:
    the problem, the pressure and the space."""
    mesh, _, ft = two_blocks(comm, upper=PUNCH)
    V, u, v, pressure = displacement_fields(mesh)
    top = resolve_master(V, ntf.FacetSurface(ft, LOWER_TOP))
    X = V.tabulate_dof_coordinates()
    split = X[top.faces].mean(axis=1)[:, 0] < 0.5 if mixed else np.zeros(len(top.faces), bool)
    rest = top.faces[split]
    triangles = np.vstack([rest[:, [0, 1, 2]], rest[:, [0, 2, 3]]])
    master = ntf.FaceNodesSurface(QUAD4, top.faces[~split], "top", more=((TRI3, triangles),))
    law = ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS)
    interaction = ntf.SurfaceInteraction(law, ntf.Friction(0.3, 1e4) if friction else None)
    pair = ntf.ContactPair(ntf.FacetSurface(ft, UPPER_BOTTOM), master, interaction)
    problem = ntf.ContactProblem(
        elastic_residual(u, v, ft, pressure), u, [pair], punch_conditions(V, ft), **options
    )
    if mixed:
        assert comm.allreduce(int(np.any(split)), op=MPI.SUM) > 0
    return problem, pressure, V


@pytest.mark.mpi
def test_master_of_two_face_types_carries_the_punch():
    """Springs on both types, which together carry the pressure on the punch (equilibrium);
    both states report as the one pair; the same slave nodes in contact (by position) as on the
    all-quad4 master, serial and on 2 processes. The displacements are not compared: the
    triangles' linear functions spread the spring forces over the master nodes differently."""
    comm = MPI.COMM_WORLD
    nodes = []
    for mixed in (False, True):
        problem, pressure, V = _problem(comm, mixed=mixed)
        solve_increments(problem, pressure, load=10.0)
        results = ntf.contact_results(problem)
        total = comm.allreduce(sum(float(r.force[:, 2].sum()) for r in results), op=MPI.SUM)
        assert total == pytest.approx(10.0 * 0.36, rel=1e-8)  # the pressure on the punch's top
        force = float(ntf.contact_force(problem, pair=0)[2])  # collective: all processes
        assert force == pytest.approx(total, rel=1e-12)
        mine = np.concatenate([r.node for r in results])
        owned = mine < V.dofmap.index_map.size_local
        X = V.tabulate_dof_coordinates()
        gathered = comm.allgather(X[mine[owned]].round(9))
        nodes.append(np.unique(np.vstack([g.reshape(-1, 3) for g in gathered]), axis=0))
    states = problem.states
    assert [s.master_faces.face_type for s in states] == [QUAD4, TRI3]
    assert len({r.pair for r in results}) == 1 and problem.pairing.pair_numbers == [0, 0]
    for state in states:  # springs on both types
        assert comm.allreduce(state.num_springs, op=MPI.SUM) > 0
    np.testing.assert_array_equal(nodes[1], nodes[0])


@pytest.mark.serial
@pytest.mark.parametrize("friction", [False, True])
def test_tangent_with_a_master_of_two_face_types_is_the_derivative(friction):
    """The Jacobian of the springs of both types (blocks of 5 and 4 nodes here, of 9 and 7 on
    quad8 and tri6 faces), with friction too, equals central differences of the residual."""
    problem, pressure, _ = _problem(MPI.COMM_SELF, mixed=True, friction=friction)
    solve_increments(problem, pressure, increments=1)
    assert all(s.num_springs > 0 for s in problem.states) and len(problem.states) == 2
    # with friction a sticking spring lies within a step of 1e-7 of the slip threshold (the
    # difference of 1e-7 steps is 1.3e-4 off, of 1e-8 steps 5.9e-10): the smaller step
    check = directional_derivative(problem, amplitude=1e-3, h=1e-5 if friction else 1e-4, seed=1)
    np.testing.assert_allclose(check.product, check.difference, atol=1e-6 * check.contact_scale)


@pytest.mark.serial
def test_adjust_with_a_master_of_two_face_types_is_refused():
    mesh, _, ft = two_blocks(MPI.COMM_SELF, upper=PUNCH)
    V, u, v, pressure = displacement_fields(mesh)
    top = resolve_master(V, ntf.FacetSurface(ft, LOWER_TOP))
    triangles = np.vstack([top.faces[:1, [0, 1, 2]], top.faces[:1, [0, 2, 3]]])
    master = ntf.FaceNodesSurface(QUAD4, top.faces[1:], "top", more=((TRI3, triangles),))
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(YOUNGS_MODULUS))
    pair = ntf.ContactPair(ntf.FacetSurface(ft, UPPER_BOTTOM), master, law, adjust=1e-3)
    with pytest.raises(NotImplementedError, match="ADJUST with a master surface of several face"):
        ntf.ContactProblem(elastic_residual(u, v, ft, pressure), u, [pair], punch_conditions(V, ft))
