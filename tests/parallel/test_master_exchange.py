"""Master surfaces exchanged by bounding boxes give the serial answer (docs/method.md §14.8).

The threshold is lowered so that the punch's small master surface is exchanged instead of
allgathered; a small margin makes the patches partial and forces enlargements. Every run is
compared with the same problem solved on ``COMM_SELF`` (and with the allgather, §14.1). In serial
nothing is exchanged and the comparisons are trivial.
"""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER_TOP, PUNCH, UPPER_BOTTOM, punch_bulk, punch_problem
from helpers import two_blocks as blocks
from helpers.decks import (
    deck_with_requests,
    first_differing_file,
    run_serial_and_parallel,
    run_summary,
)
from helpers.serial_answer import (
    PARTITIONS,
    assert_same_friction,
    assert_same_punch,
    cut_along_x,
    friction_analysis,
    serial_friction_analysis,
    serial_punch,
    solve_punch,
    sorted_rows,
)

import dolfinx_ntf as ntf
from dolfinx_ntf.fem.surfaces import resolve_master
from dolfinx_ntf.kernels.faces import FACE_TYPES
from dolfinx_ntf.kernels.search import NOT_HELD, MasterSurface
from dolfinx_ntf.parallel import master_exchange
from dolfinx_ntf.parallel.halo import NodeHalo

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD


@pytest.fixture
def exchanges(monkeypatch):
    """Every master surface exchanged; records (exchanges, faces, core faces, complete) per call."""
    monkeypatch.setattr(master_exchange, "EXCHANGE_ABOVE_FACES", 0)
    calls = []
    exchange = master_exchange.MasterPatch.exchange

    def recorded(self, coords, margin):
        exchange(self, coords, margin)
        calls.append(
            (self.exchanges, self.faces.faces.shape[0], int(self._core.sum()), self.complete)
        )

    monkeypatch.setattr(master_exchange.MasterPatch, "exchange", recorded)
    return calls


def _partial(calls):
    """Some process searched on a part of the master surface only."""
    return COMM.allreduce(any(not complete for *_, complete in calls), op=MPI.LOR)


def _enlarged(calls):
    return COMM.allreduce(max((c[0] for c in calls), default=0), op=MPI.MAX) > 1


@pytest.mark.parametrize("partition", PARTITIONS)
@pytest.mark.parametrize("margin", [2.0, 0.0])
def test_punch_gives_the_serial_answer(exchanges, monkeypatch, partition, margin):
    """Default margin; no margin (every first search enlarges); idle and empty processes."""
    monkeypatch.setattr(master_exchange, "MARGIN", margin)
    run = solve_punch(COMM, "hexahedron", PARTITIONS[partition])
    assert_same_punch(run, serial_punch("hexahedron"))
    assert run.mallocs == 0
    if COMM.size > 1:
        assert exchanges
        if margin == 0.0:
            assert _enlarged(exchanges)
            assert partition in ("idle", "empty", "bodies") or _partial(exchanges)


def test_tetrahedra_cut_through_the_contact_zone(exchanges, monkeypatch):
    monkeypatch.setattr(master_exchange, "MARGIN", 0.0)
    run = solve_punch(COMM, "tetrahedron", cut_along_x)
    assert_same_punch(run, serial_punch("tetrahedron"))


def _fine_punch_problem(comm, partition, options):
    """The problem of :func:`_fine_punch` with its load constant; the caller destroys it."""
    lower = ((0, 0, -1), (1, 1, 1), (12, 12, 1))
    mesh, _, ft = blocks(comm, lower=lower, upper=PUNCH, partition=partition)
    u, F, pressure, bcs = punch_bulk(mesh, ft)
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(1000.0))
    pair = ntf.ContactPair(ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), law)
    problem = ntf.ContactProblem(F, u, [pair], bcs, **options)
    return problem, pressure


def _fine_punch(comm, partition, options):
    """The punch on a finer master (12 x 12 faces): the default margin leaves patches partial."""
    problem, pressure = _fine_punch_problem(comm, partition, options)
    u, V = problem.u, problem.u.function_space
    solver = ntf.ContactNewtonSolver(comm, problem)
    pairings = []
    problem.pairing_callbacks.append(
        lambda p: pairings.append(
            sorted_rows(
                comm,
                np.hstack(
                    [
                        p.current_coordinates()[p.states[0].element_nodes[:, -1]],
                        p.current_coordinates()[p.states[0].element_nodes[:, :-1]].mean(axis=1),
                    ]
                ),
            )
        )
    )
    step = ntf.StaticStep(lambda t: setattr(pressure, "value", 20.0 * t), initial_increment=0.5)
    results = step.run(solver, u)
    owned = V.dofmap.index_map.size_local
    rows = np.hstack([problem.reference_coordinates[:owned], u.x.array.reshape(-1, 3)[:owned]])
    found = problem.states[0].found_face
    faces = problem.states[0].master_faces.faces[found[found >= 0]]
    located = sorted_rows(comm, np.hstack([problem.reference_coordinates[faces].mean(axis=1)]))
    out = (
        [(r.iterations, r.springs) for r in results],
        pairings,
        sorted_rows(comm, rows),
        located,
        problem.matrix.getInfo()["mallocs"],
    )
    solver.destroy()
    problem.destroy()
    return out


@pytest.mark.parametrize("partition", ["cut", "empty"])
def test_tie_frame_is_that_of_the_whole_surface(exchanges, monkeypatch, partition):
    """The stable search's tie frame (§3.2) from a patch: the moments of the whole master."""
    monkeypatch.setattr(master_exchange, "MARGIN", 0.0)
    moments = []
    for threshold in (0, 10**9):  # exchanged, allgathered
        monkeypatch.setattr(master_exchange, "EXCHANGE_ABOVE_FACES", threshold)
        problem, _ = _fine_punch_problem(COMM, PARTITIONS[partition], {})
        problem.pair()
        moments.append(problem.states[0].master.surface_moments())
        problem.destroy()
    if COMM.size > 1:
        assert _partial(exchanges)
    (origin, m), (origin_all, m_all) = moments
    np.testing.assert_allclose(origin, origin_all, rtol=0, atol=1e-14)
    np.testing.assert_allclose(m, m_all, rtol=1e-12, atol=1e-14 * np.abs(m_all).max())


@pytest.mark.parametrize("partition", ["graph", "cut", "idle"])
@pytest.mark.parametrize("options", [{}, {"walk_from_previous_face": False}])
def test_partial_patches_give_the_allgather_answer(exchanges, monkeypatch, partition, options):
    """Same iterations, springs at every pairing, faces found, displacements: serial, allgather."""
    serial = _fine_punch(MPI.COMM_SELF, None, options)
    run = _fine_punch(COMM, PARTITIONS[partition], options)
    monkeypatch.setattr(master_exchange, "EXCHANGE_ABOVE_FACES", 10**9)
    gathered = _fine_punch(COMM, PARTITIONS[partition], options)
    for other in (serial, gathered):
        assert run[0] == other[0]
        assert len(run[1]) == len(other[1])
        for a, b in zip(run[1], other[1]):
            assert a.shape == b.shape
            np.testing.assert_allclose(a, b, rtol=0, atol=1e-12)
        np.testing.assert_allclose(run[2], other[2], rtol=0, atol=1e-10 * np.abs(other[2]).max())
        np.testing.assert_allclose(run[3], other[3], rtol=0, atol=1e-12)  # every face found
    assert run[4] == 0 and serial[1][-1].shape[0] == 16
    if COMM.size > 1:
        assert _partial(exchanges)


@pytest.mark.parametrize("margin", [2.0, 0.0])
@pytest.mark.parametrize("partition", ["cut", "bodies", "idle"])
def test_sliding_with_friction_gives_the_serial_answer(exchanges, monkeypatch, margin, partition):
    """The punch dragged across the master: nodes leave their boxes, patches are exchanged again."""
    monkeypatch.setattr(master_exchange, "MARGIN", margin)
    run = friction_analysis(COMM, PARTITIONS[partition])
    assert_same_friction(run, serial_friction_analysis())
    assert run.mallocs == 0
    if COMM.size > 1 and margin == 0.0:
        assert _enlarged(exchanges)


def test_walk_off_the_patch_is_not_held():
    """A walk that steps onto a triangle marked not held ends there with NOT_HELD, not -1."""
    quad = FACE_TYPES["quad4"]
    x = np.array([[i, j, 0.0] for j in range(2) for i in range(3)], dtype=float)
    faces = np.array([[0, 1, 4, 3], [1, 2, 5, 4]])
    surface = MasterSurface(quad, faces)
    per_face = len(quad.triangles)
    surface.mark_not_held(np.arange(per_face, 2 * per_face))
    surface.update(x)
    point = np.array([[1.5, 0.5, 0.1]])
    assert surface.locate(point, 0.0, start_faces=np.array([0]))[0] == NOT_HELD
    assert surface.locate(np.array([[0.5, 0.5, 0.1]]), 0.0, start_faces=np.array([0]))[0] == 0
    outside = np.array([[-0.5, 0.5, 0.1]])  # beyond the surface's own boundary: no face
    assert surface.locate(outside, 0.0, start_faces=np.array([0]))[0] == -1


@pytest.mark.parametrize("name", ["hex_two_pairs", "hex_sliding_block", "hex_adjust_gap"])
def test_deck_runner_gives_the_serial_files(exchanges, monkeypatch, name, tmp_path_factory):
    """Two pairs, *CLOAD; slip, *CHANGE FRICTION, *MODEL CHANGE; ADJUST: the serial files."""
    monkeypatch.setattr(master_exchange, "MARGIN", 0.0)
    folder = COMM.bcast(tmp_path_factory.mktemp("decks") if COMM.rank == 0 else None)
    path = deck_with_requests(name, folder)
    serial, parallel, serial_dir = run_serial_and_parallel(path)
    serial = COMM.bcast(serial and run_summary(serial), root=0)
    summary = run_summary(parallel)
    assert summary["iterations"] == serial["iterations"]
    assert summary["contact"] == serial["contact"]
    u, u_ref = parallel.last.displacement, serial["displacement"]
    assert np.max(np.abs(u - u_ref)) <= 1e-10 * np.max(np.abs(u_ref))
    error = first_differing_file(path, serial_dir) if COMM.rank == 0 else None
    error = COMM.bcast(error, root=0)
    assert error is None, error
    if COMM.size > 1:
        assert exchanges


@pytest.mark.parametrize("margin", [0.0, 0.3, 1.0, 10.0])
def test_nearest_centroid_check(monkeypatch, margin):
    """On one process: a node whose nearest centroid may lie outside its request box (grown by
    the margin) is NOT_HELD, the others get the whole surface's face."""
    monkeypatch.setattr(master_exchange, "MARGIN", margin)
    problem, _, ft = punch_problem(comm=MPI.COMM_SELF)
    V = problem.u.function_space
    state = problem.states[0]
    own = resolve_master(V, ntf.FacetSurface(ft, LOWER_TOP), what="master")
    coords = problem.current_coordinates()
    patch = master_exchange.MasterPatch(
        NodeHalo(V), own, state.slave.nodes, coords[: V.dofmap.index_map.size_local], "patch"
    )
    patch.update(coords)
    state.master.update(coords)
    points = coords[state.slave.nodes] + np.array([0.0, 0.0, 0.01])
    centroids, diagonal = state.master.triangle_centroids, np.sqrt(2) / 4  # 4 x 4 unit squares
    faces, whole = patch.locate(points, 0.0), state.master.locate(points, 0.0)
    held = faces != NOT_HELD
    assert np.array_equal(faces[held], whole[held]) and np.all(whole >= 0)
    assert patch.complete == (margin >= 1.0)  # the box then holds the whole master surface
    # margin 0: the box of the flat slave surface has no thickness, no ball fits in it; 0.3 face
    # diagonals (0.106): only where the nearest centroid is nearer than the node to the box's face
    radius = np.sqrt(((points[:, None, :] - centroids[None]) ** 2).sum(axis=2)).min(axis=1)
    room = np.minimum(points - patch._region[0], patch._region[1] - points).min(axis=1)
    assert np.array_equal(held, radius + 1e-6 < room) and np.isclose(
        patch.margin, margin * diagonal
    )
    assert held.all() if margin >= 1.0 else (held.any() if margin > 0.0 else not held.any())
    problem.destroy()
