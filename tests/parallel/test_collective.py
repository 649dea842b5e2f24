"""Wrong uses found on one process fail on every process (no process continues alone into a
collective call and hangs). Run in serial and by ``make test`` on 2 processes."""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER_TOP, UPPER, UPPER_BOTTOM, punch_problem, two_blocks

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.contact import pairing as pairing_module
from dolfinx_ntf.fem.surfaces import resolve_master, resolve_slave
from dolfinx_ntf.kernels import springs
from dolfinx_ntf.kernels.search import MasterSurface
from dolfinx_ntf.parallel import master_exchange
from dolfinx_ntf.validation import raise_collectively

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD


def test_an_error_of_one_process_is_raised_on_all():
    raise_collectively(COMM, None)
    with pytest.raises(ValueError, match="found on rank 0"):
        raise_collectively(COMM, ValueError("found on rank 0") if COMM.rank == 0 else None)


@pytest.fixture(scope="module")
def blocks():
    mesh, cell_tags, ft = two_blocks(COMM)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u = dolfinx.fem.Function(V)
    F = ufl.inner(ufl.grad(u), ufl.grad(ufl.TestFunction(V))) * ufl.dx
    return mesh, cell_tags, ft, u, F


def test_contact_pairs_run_on_every_process_count(blocks):
    """Each process holds the slave nodes it owns; over all processes, each node once."""
    _, _, ft, u, F = blocks
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(1000.0))
    pair = ntf.ContactPair(ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), law)
    problem = ntf.ContactProblem(F, u, [pair])
    assert COMM.allreduce(problem.states[0].slave.nodes.size) == 25  # the 5 x 5 bottom nodes
    assert problem.states[0].master.num_faces == 16  # the whole master on every process
    problem.destroy()
    ntf.ContactProblem(F, u, [])  # no pairs: a plain nonlinear problem


def test_missing_tag_value_fails_everywhere(blocks):
    _, _, ft, u, _ = blocks
    V = u.function_space
    with pytest.raises(ValueError, match=r"facet tag value\(s\) \[99\] not found"):
        resolve_master(V, ntf.FacetSurface(ft, 99))
    # A value present on any process is found, even where this process holds none of its facets.
    assert COMM.allreduce(resolve_master(V, ntf.FacetSurface(ft, LOWER_TOP)).faces.shape[0]) > 0


def test_node_surface_held_by_one_process(blocks):
    """Vertices located on one process only: the other processes hold an empty NodeSurface, which
    is fine; vertices out of range on rank 0 only fail on all processes."""
    mesh, cell_tags, _, u, _ = blocks
    V = u.function_space
    bad = np.array([10**7]) if COMM.rank == 0 else np.empty(0, dtype=np.int32)
    with pytest.raises(ValueError, match=r"vertex index 10000000 \(entry 0\) is outside"):
        resolve_slave(V, ntf.NodeSurface(bad))
    with pytest.raises(ValueError, match="has no vertices"):
        resolve_slave(V, ntf.NodeSurface(np.empty(0, dtype=np.int32)))
    # The upper block's bottom vertices (the lower block's top has vertices at z = 0 too).
    upper = compat.incident_entities(mesh, cell_tags.find(UPPER), 3, 0)
    bottom = dolfinx.mesh.locate_entities(mesh, 0, lambda x: np.isclose(x[2], 0.0))
    candidates = np.intersect1d(upper, bottom)  # dolfinx 0.11 may put the upper block on rank 1
    holder = COMM.allreduce(COMM.rank if candidates.size else COMM.size, op=MPI.MIN)
    mine = candidates if COMM.rank == holder else np.empty(0, dtype=np.int32)
    slave = resolve_slave(V, ntf.NodeSurface(mine))
    assert COMM.allreduce(slave.nodes.size) > 0


def test_writer_path_errors_everywhere(blocks, tmp_path_factory):
    u, F = blocks[3:5]
    problem = ntf.ContactProblem(F, u, [])
    folder = COMM.bcast(str(tmp_path_factory.mktemp("out")) if COMM.rank == 0 else None)
    with pytest.raises(FileNotFoundError, match="does not exist"):
        ntf.ContactWriter(problem, f"{folder}/missing/out.xdmf")
    with ntf.ContactWriter(problem, f"{folder}/ok.xdmf") as writer:
        writer.write(0.0)


def test_law_warnings_print_once():
    """A law's warning is the same on every process: only rank 0 shows it."""
    import warnings

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ntf.LinearLaw.with_ccx_defaults(2.1e5, slope=-1.0)
        ntf.Friction.with_ccx_defaults(0.3, None, 2.1e5)
    assert len(caught) == (2 if COMM.rank == 0 else 0)
    assert COMM.allreduce(len(caught)) == 2


@pytest.mark.parametrize("pc_type", ["gamg", "lu"])
def test_sequential_galerkin_products_only_for_serial_gamg(pc_type):
    """The faster PtAP algorithm is set for a serial GAMG solve only, and never over the user's."""
    from petsc4py import PETSc

    from dolfinx_ntf.solvers.linear_solver import SEQUENTIAL_PTAP, galerkin_products

    ksp = PETSc.KSP().create(COMM)
    ksp.getPC().setType(pc_type)
    options = PETSc.Options()
    expected = SEQUENTIAL_PTAP if pc_type == "gamg" and COMM.size == 1 else None
    with galerkin_products(ksp):
        assert (options.getString("matptap_via") if options.hasName("matptap_via") else None) == (
            expected
        )
    assert not options.hasName("matptap_via")
    options["matptap_via"] = "scalable"
    try:
        with galerkin_products(ksp):
            assert options.getString("matptap_via") == "scalable"
        assert options.getString("matptap_via") == "scalable"
    finally:
        options.delValue("matptap_via")
    ksp.destroy()


@pytest.fixture
def no_hang():
    """A pairing test that would hang ends the run after a while instead (mpirun stops all)."""
    import faulthandler

    faulthandler.dump_traceback_later(120, exit=True)
    yield
    faulthandler.cancel_dump_traceback_later()


FAILING = min(1, COMM.size - 1)  # the one process whose pairing fails


#: Where a pairing fails; a master patch (the master exchanged by boxes, §14.8) exists on several
#: processes only.
FAILURES = [
    ("search", {}),
    ("search", {"walk_from_previous_face": False}),  # no collective before the block's end
    ("areas", {}),
    ("projection", {}),
    *([("patch search", {}), ("patch enlargement", {})] if COMM.size > 1 else []),
    ("face lookup", {}),  # the faces around a face, reserved in a new matrix
]


@pytest.mark.parametrize(("where", "options"), FAILURES)
def test_a_pairing_error_on_one_process_is_raised_on_all(where, options, monkeypatch, no_hang):
    """docs/method.md §14.4: the search, the areas, the projection, the master patch or the
    lookup of face patches failing on one process only makes every process raise it, and the
    next pairing still runs."""
    if where.startswith("patch"):
        monkeypatch.setattr(master_exchange, "EXCHANGE_ABOVE_FACES", 0)
    problem, _, _ = punch_problem(comm=COMM, **options)
    expected = problem.pair()

    def failing(function):
        def wrapper(*args, **kwargs):
            if COMM.rank == FAILING:
                raise ArithmeticError(f"{where} failed on rank {FAILING}")
            return function(*args, **kwargs)

        return wrapper

    target = {
        "search": (MasterSurface, "locate"),
        "areas": (pairing_module, "slave_areas"),
        "projection": (springs, "evaluate_springs"),
        "patch search": (master_exchange.MasterPatch, "locate"),
        "patch enlargement": (master_exchange.MasterPatch, "next_margin"),
        "face lookup": (MasterSurface, "face_patches"),
    }[where]

    def new_matrix():
        if problem.matrix is not None:
            problem.matrix.destroy()
            problem.matrix = None
        return problem.ensure_matrix()

    action = new_matrix if where == "face lookup" else problem.pair
    with monkeypatch.context() as patch:
        patch.setattr(*target, failing(getattr(*target)))
        if where == "patch enlargement":  # every process asks for a larger patch
            patch.setattr(master_exchange, "enlarge", _always_enlarge(master_exchange.enlarge))
        with pytest.raises(ArithmeticError, match=f"{where} failed on rank {FAILING}"):
            action()
    assert problem.pair() == expected  # every process still at the same collective call
    assert problem.ensure_matrix() is not None
    problem.destroy()


def _always_enlarge(enlarge):
    def wrapper(master, face, coordinates):
        return enlarge(master, np.full_like(face, -2), coordinates)  # search.NOT_HELD everywhere

    return wrapper
