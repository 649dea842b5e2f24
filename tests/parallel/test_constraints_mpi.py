"""Linear constraints on several processes give the serial answer (docs/method.md §14.6).

Each process gives the constraints among its own nodes (ghosts included); the union counts each
once. Compared with the same problem solved on ``COMM_SELF`` in the same run.
"""

import itertools

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER_TOP, PUNCH, UPPER_BOTTOM, box_grid, punch_bulk, two_blocks
from helpers.serial_answer import PARTITIONS, solve_step_springs

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.serendipity import serendipity_centres

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD
TILT = 2e-4  # prescribed difference of u_z along y at x = 0.8 between the first two nodes


def test_constraints_given_on_one_process_count_once():
    mesh = dolfinx.mesh.create_unit_cube(COMM, 2, 2, 2, dolfinx.mesh.CellType.hexahedron)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    tie = [ntf.LinearConstraint([0, 1], [2, 2], [1.0, -1.0])] if COMM.rank == 0 else []
    assert ntf.ContactProblem(F, u, [], constraints=tie).elimination.num_constraints == 1
    # the same constraint on every process (each in its own numbering) also counts once
    x = V.tabulate_dof_coordinates()
    ends = [np.flatnonzero(np.isclose(x, p).all(axis=1)) for p in ([0, 0, 0], [0.5, 0, 0])]
    tie = [ntf.LinearConstraint([ends[0][0], ends[1][0]], [0, 0], [1.0, -1.0])]
    held = COMM.allreduce(int(all(e.size for e in ends)))
    problem = ntf.ContactProblem(F, u, [], constraints=tie if all(e.size for e in ends) else [])
    assert held >= 1 and problem.elimination.num_constraints == 1


def test_a_node_outside_one_process_fails_on_all():
    mesh = dolfinx.mesh.create_unit_cube(COMM, 2, 2, 2, dolfinx.mesh.CellType.hexahedron)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    far = V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts
    bad = [ntf.LinearConstraint([0, far], [2, 2], [1.0, -1.0], name="far")]
    with pytest.raises(ValueError, match=r"far: (node|dof)"):
        ntf.ContactProblem(F, u, [], constraints=bad if COMM.rank == COMM.size - 1 else [])


def _top_ties(V):
    """u_z of the punch top tied along x (chains), and along y at x = 0.8 with one tilt.

    Each process ties the pairs of neighbours it holds (owned or ghost): a pair held by two
    processes is given twice and counts once.
    """
    x = V.tabulate_dof_coordinates()
    top = np.flatnonzero(np.isclose(x[:, 2], 0.5))
    position = {tuple(np.round(x[n], 9)): int(n) for n in top}
    grid = np.round(np.linspace(0.2, 0.8, 4), 9)
    ties = []
    for a, b in itertools.pairwise(grid):
        for c in grid:
            for first, second, value in (
                ((a, c), (b, c), 0.0),  # along x
                ((0.8, a), (0.8, b), TILT if a == grid[0] else 0.0),  # along y at x = 0.8
            ):
                i, j = position.get((*first, 0.5)), position.get((*second, 0.5))
                if i is not None and j is not None and (first[0] == a or c == grid[0]):
                    ties.append(ntf.LinearConstraint([i, j], [2, 2], [1.0, -1.0], value))
    return ties


def _solve(comm, partition, ties=_top_ties):
    mesh, _, ft = two_blocks(comm, upper=PUNCH, partition=partition)
    top = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], 0.5))
    u, F, pressure, bcs = punch_bulk(mesh, ft, top)
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(1000.0))
    pair = ntf.ContactPair(ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), law)
    problem = ntf.ContactProblem(F, u, [pair], bcs, constraints=ties(u.function_space))
    increments, nodes, springs = solve_step_springs(comm, problem, pressure, u)
    out = (
        increments,
        nodes,
        springs,
        problem.elimination.num_constraints,
        problem.matrix.getInfo()["mallocs"],
    )
    problem.destroy()
    return out


@pytest.mark.parametrize("partition", PARTITIONS)
def test_tied_punch_gives_the_serial_answer(partition):
    """Ties across partition cuts (dofs owned by different processes), chains and a value."""
    (increments, nodes, springs, count, mallocs) = _solve(COMM, PARTITIONS[partition])
    serial = _solve(MPI.COMM_SELF, None)
    assert count == serial[3] == 15
    assert increments == serial[0]
    scale = np.abs(serial[1][:, 3:]).max()
    np.testing.assert_allclose(nodes, serial[1], rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(springs, serial[2], rtol=1e-10, atol=1e-12)
    assert springs.shape[0] == 16 and mallocs == 0
    # the constraints hold: the top is flat along x, tilted by TILT along y
    top = nodes[np.isclose(nodes[:, 2], 0.5) & (nodes[:, 0] > 0.1) & (nodes[:, 1] > 0.1)]
    uz = {tuple(np.round(r[:2], 9)): r[5] for r in top}
    assert uz[(0.2, 0.4)] == pytest.approx(uz[(0.8, 0.4)], abs=1e-14)
    assert uz[(0.8, 0.2)] - uz[(0.8, 0.4)] == pytest.approx(TILT, abs=1e-14)
    assert uz[(0.8, 0.4)] < -1e-3  # pressed


# ----------------------------------------------------------------- nodes no process holds together

#: The points of two_blocks(upper=PUNCH) in input order: a node's id is its row (input index).
POINTS = np.vstack([box_grid((0, 0, -1), (1, 1, 1), (4, 4, 2))[0], box_grid(*PUNCH)[0]])


def _id(x, y, z):
    (row,) = np.flatnonzero(np.isclose(POINTS, [x, y, z]).all(axis=1))
    return int(row)


def _far_terms():
    """(ids, components, coefficients, value, name): u_x of the lower block's top edges x = 0
    and x = 1 made asymmetric, and a three-term tie of two lower-block corners to a punch node."""
    terms = [
        ([_id(0.0, y, 0.0), _id(1.0, y, 0.0)], [0, 0], [1.0, 1.0], TILT, f"edge y={y}")
        for y in (0.25, 0.5, 0.75)
    ]
    ids = [_id(0.0, 0.0, 0.0), _id(1.0, 1.0, 0.0), _id(0.2, 0.2, 0.25)]
    terms.append((ids, [0, 0, 2], [1.0, -0.5, 1.0], 0.0, "bodies"))
    return terms


def _far_ties(V):
    """The ties of _far_terms by input node ids, given on every process (each counts once)."""
    ties = [ntf.LinearConstraint(*t[:4], name=t[4]) for t in _far_terms()]
    return ntf.global_constraints(V, ties)


@pytest.mark.parametrize("partition", ["cut", "bodies", "empty", "graph"])
def test_ties_between_nodes_no_process_holds_together(partition):
    """Constraints by node ids across processes that share none of their nodes (§14.9)."""
    mesh, _, _ = two_blocks(COMM, upper=PUNCH, partition=PARTITIONS[partition])
    held = set(ntf.input_node_ids(compat.vector_space(mesh, "Lagrange", 1)).tolist())
    apart = [not set(t[0]) <= held for t in _far_terms()]  # this process lacks a node
    apart = np.array(COMM.allreduce([apart], op=MPI.SUM)).all(axis=0)  # ... and so do all others
    # the partition guarantees it: no process holds all nodes of a tie (ghosts included)
    if COMM.size > 1 and partition == "bodies":  # one process holds the lower block only
        assert apart[-1]
    if COMM.size == 2 and partition == "cut":  # on 3, the middle slice's ghosts hold x = 0 to 1
        assert apart.all()
    (increments, nodes, springs, count, mallocs) = _solve(COMM, PARTITIONS[partition], _far_ties)
    serial = _solve(MPI.COMM_SELF, None, _far_ties)
    assert count == serial[3] == 4
    assert increments == serial[0]
    scale = np.abs(serial[1][:, 3:]).max()
    np.testing.assert_allclose(nodes, serial[1], rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(springs, serial[2], rtol=1e-10, atol=1e-12)
    assert mallocs == 0
    u = {tuple(np.round(r[:3], 9)): r[3:] for r in nodes}
    for y in (0.25, 0.5, 0.75):  # the constraints hold to round-off
        assert u[0.0, y, 0.0][0] + u[1.0, y, 0.0][0] == pytest.approx(TILT, abs=1e-14)
    tied = u[0.0, 0.0, 0.0][0] - 0.5 * u[1.0, 1.0, 0.0][0] + u[0.2, 0.2, 0.25][2]
    assert tied == pytest.approx(0.0, abs=1e-14) and abs(u[0.2, 0.2, 0.25][2]) > 1e-3


def test_a_node_id_no_process_holds_fails_on_all():
    mesh = dolfinx.mesh.create_unit_cube(COMM, 2, 2, 2, dolfinx.mesh.CellType.hexahedron)
    V = compat.vector_space(mesh, "Lagrange", 1)
    tie = [ntf.LinearConstraint([0, 10**6], [2, 2], [1.0, -1.0], name="deck.inp:7")]
    with pytest.raises(ValueError, match=r"deck\.inp:7: node 1000000: no node of the mesh"):
        ntf.global_constraints(V, tie if COMM.rank == COMM.size - 1 else [])
    ids = np.zeros_like(ntf.input_node_ids(V))  # every node carries id 0
    tie = [ntf.LinearConstraint([0, 1], [2, 2], [1.0, -1.0], name="same")]
    with pytest.raises(ValueError, match="same: node 0: several nodes carry this id"):
        ntf.global_constraints(V, tie, node_ids=ids)


def test_serendipity_rows_of_all_processes_count_once():
    """C3D20's face-centre rows: a face between two processes' cells counts once (§14.10)."""
    mesh = dolfinx.mesh.create_box(
        COMM, [[0, 0, 0], [1, 1, 1]], [3, 2, 2], dolfinx.mesh.CellType.hexahedron
    )
    V = compat.vector_space(mesh, "Lagrange", 2)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(ufl.grad(u), ufl.grad(v)) * ufl.dx
    problem = ntf.ContactProblem(F, u, [], constraints=ntf.serendipity_constraints(V))
    faces, cells = 4 * 2 * 2 + 3 * 3 * 2 + 3 * 2 * 3, 12
    assert problem.elimination.num_constraints == 3 * (faces + cells)

    def quadratic(x):  # in the serendipity space: the back-substitution reproduces it
        return np.vstack([x[0] ** 2 + x[1] * x[2], x[0] * x[1] - x[2] ** 2, 1 + x[0] + x[1] * x[2]])

    u.interpolate(quadratic)
    exact = u.x.array.copy()
    centres = serendipity_centres(V)
    u.x.array.reshape(-1, 3)[centres] += 1.0  # wrong centre values, owned and ghost
    problem.elimination.back_substitute(compat.petsc_vector(u))
    u.x.scatter_forward()
    assert COMM.allreduce(centres.size) > 0
    assert np.max(np.abs(u.x.array - exact), initial=0.0) < 1e-12
