"""The pairing schedule: the default search keeps nodes on their faces (no ping-pong), CalculiX's
search lets nodes on shared edges flip faces at every re-pairing."""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import (
    LOWER_TOP,
    UPPER_BOTTOM,
    elastic_residual,
    punch_problem,
    solve_increments,
    two_blocks,
)
from scipy.spatial.transform import Rotation

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

pytestmark = pytest.mark.serial


@pytest.mark.parametrize("cell", ["hexahedron", "tetrahedron"])
def test_default_search_changes_no_faces_on_a_tie_deck(cell):
    """The punch's slave nodes lie exactly above master nodes and edges (ties)."""
    changes, iterations = {}, {}
    for stable in (True, False):
        problem, pressure, _ = punch_problem(cell, walk_from_previous_face=stable)
        counts = []
        problem.pairing_callbacks.append(lambda p, counts=counts: counts.append(p.face_changes))
        _, results = solve_increments(problem, pressure)
        changes[stable] = sum(counts)
        iterations[stable] = [r.iterations for r in results]
    assert changes[True] == 0
    assert all(a <= b for a, b in zip(iterations[True], iterations[False]))
    if cell == "tetrahedron":  # hexahedra have no ping-pong in either mode on this deck
        assert changes[False] > 0
        assert max(iterations[True]) < min(iterations[False])


def test_stable_search_is_the_default():
    problem, _, _ = punch_problem("hexahedron")
    assert problem.walk_from_previous_face
    assert isinstance(problem.face_changes, int)
    assert ntf.ContactProblem.__init__.__kwdefaults__["walk_from_previous_face"] is True


@pytest.mark.parametrize("cell", ["hexahedron", "tetrahedron"])
def test_stable_mode_converges_a_linear_law_in_three_iterations(cell):
    """The punch touching the master (d = 0 at the start: the LINEAR law's kink, slope K/2) with
    ties: 3 Newton iterations per increment with the penetration slope at the kink (4 without),
    no node changes face."""
    problem, pressure, _ = punch_problem(cell, contact_start_slope=True)
    counts = []
    problem.pairing_callbacks.append(lambda p: counts.append(p.face_changes))
    _, results = solve_increments(problem, pressure, increments=1)
    assert [r.iterations for r in results] == [3]
    assert sum(counts) == 0
    assert ntf.contact_results(problem)[0].force[:, 2].sum() == pytest.approx(3.6, rel=1e-10)


# A punch placed off-centre on the block (no symmetry of the model), its nodes on every other
# grid line above master grid lines: ties.
OFF_CENTRE = ((0.125, 0.25, 0.0), (0.5, 0.625, 0.5), (4, 5, 2))


def _paired_faces(cell, rotation, shift, stable):
    """Master face (as its sorted reference corner coordinates, mapped back) of every slave node
    (by its reference coordinates, mapped back) at the first pairing of the rotated model."""
    mesh, _, ft = two_blocks(MPI.COMM_SELF, cell=cell, upper=OFF_CENTRE)
    mesh.geometry.x[:] = mesh.geometry.x @ rotation.T + shift
    V = compat.vector_space(mesh, "Lagrange", 1)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = elastic_residual(u, v, ft, dolfinx.fem.Constant(mesh, 0.0))
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(1000.0)),
    )
    problem = ntf.ContactProblem(F, u, [pair], [], walk_from_previous_face=stable)
    problem.pair(record_overlap=True)
    state = problem.states[0]
    back = (problem.current_coordinates() - shift) @ rotation  # reference coordinates, unrotated
    corners = back[state.master_faces.faces[state.spring_face]]
    key = np.round(back[state.slave.nodes[state.spring_slave]], 9)
    order = np.lexsort(key.T[::-1])
    faces = np.sort(np.round(corners, 9).reshape(len(corners), -1, 3), axis=1)
    return key[order], faces[order]


@pytest.mark.parametrize("cell", ["hexahedron", "tetrahedron"])
def test_stable_tie_break_is_the_same_in_a_rotated_model(cell):
    """ContactProblem's stable search picks the same faces in the model rotated and moved; the
    global (x, y, z) order of CalculiX's search does not (the ties matter)."""
    rng = np.random.default_rng(3)
    moved = [
        (Rotation.random(random_state=seed).as_matrix(), rng.uniform(-5.0, 5.0, 3))
        for seed in (0, 1, 2, 3)
    ]
    differ = {}
    for stable in (True, False):
        nodes, faces = _paired_faces(cell, np.eye(3), np.zeros(3), stable)
        assert nodes.shape[0] == 30
        differ[stable] = 0
        for rotation, shift in moved:
            nodes2, faces2 = _paired_faces(cell, rotation, shift, stable)
            np.testing.assert_allclose(nodes2, nodes, atol=1e-8)
            differ[stable] += int(
                np.count_nonzero(np.any(np.abs(faces2 - faces) > 1e-8, axis=(1, 2)))
            )
    assert differ[True] == 0
    assert differ[False] > 0
