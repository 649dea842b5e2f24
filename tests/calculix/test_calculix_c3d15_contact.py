"""Contact on C3D15 faces (docs/method.md §38): runs on dolfinx 0.11, refused before it.

The decks are ``tests/data/calculix/c3d15/make_contact.py``'s punch of C3D15 wedges pressed onto
a block of C3D15 wedges (LINEAR law, 2 increments), with 8-node quadrilaterals or 6-node
triangles in contact; the ``.dat.ref`` files are ccx 2.20's output.
"""

from __future__ import annotations

import importlib.util
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx_ntf import compat
from dolfinx_ntf.calculix.ccx import read_sta
from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import read_deck
from dolfinx_ntf.calculix.job import run_job

DATA = Path(__file__).parent.parent / "data" / "calculix" / "c3d15"
ON_011 = compat.DOLFINX_VERSION >= (0, 11)
#: The contact decks: the wedges' axes of punch and block (y: quadrilaterals in contact, z:
#: triangles) and whether the punch's edges are curved.
DECKS = {
    "wedge_punch_quad": (1, 1, False),
    "wedge_punch_tri": (2, 2, False),
    "wedge_punch_quad_on_tri": (1, 2, False),
    "wedge_punch_quad_curved": (1, 1, True),
    "wedge_punch_tri_curved": (2, 2, True),
    "wedge_punch_mixed": ((1, 2), 1, False),  # a slave surface of quadrilaterals and triangles
    "wedge_node_mixed": ((1, 2), 1, False),  # a node-based slave surface (TYPE=NODE)
    "wedge_node_quad": (1, 1, False),  # the node set of the quadrilateral bottom
    "wedge_adjust_set": (1, 1, False),  # ADJUST: the bottom's corner nodes
    "wedge_adjust_distance": (1, 1, False),  # ADJUST=0.005: every slave node
    "wedge_master_mixed": (1, (1, 2), False),  # a master of quadrilaterals and triangles
    "wedge_master_mixed_tri": (2, (1, 2), False),  # the same under triangular slave faces
    "wedge_master_mixed_slide": (1, (1, 2), False),  # friction; nodes slide across the kinds
}
#: The ADJUST decks: the punch 0.002 above the block, ADJUST by node set or distance.
ADJUST = {"wedge_adjust_set": "set", "wedge_adjust_distance": "0.005"}
#: A steady heat transfer deck: heat across the contact springs (docs/method.md §38.7).
HEAT = "wedge_heat_punch"
#: The node-based decks, whose midside nodes take ccx's fallback area held between pairings
#: (docs/method.md §38.5); their ``.sta.ref`` files are ccx 2.20's.
NODE_DECKS = ("wedge_node_mixed", "wedge_node_quad")
#: The sliding deck's second step: 10 increments of 0.1 (the others print 0.5 and 1).
SLIDE = "wedge_master_mixed_slide"
SLIDE_TIMES = (0.5, 1.0, 1.1, 1.2, 1.3, 1.4, 1.5, 1.6, 1.7, 1.8, 1.9, 2.0)
#: The tie decks: the punch tied to the block (quadrilaterals, triangles, both).
TIES = {"wedge_tie_quad": (1, 1), "wedge_tie_tri": (2, 2), "wedge_tie_mixed": ((1, 2), 1)}
#: Master surfaces of triangles and quadrilaterals (the block's columns alternate their wedges'
#: axis, docs/method.md §38.8).
MIXED_MASTERS = ("wedge_master_mixed", "wedge_master_mixed_tri")


def _generator():
    """``make_contact.py`` as a module (it writes the decks)."""
    spec = importlib.util.spec_from_file_location("make_contact", DATA / "make_contact.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _run(tmp_path: Path, job: str, comm: MPI.Comm) -> tuple[list, list]:
    """ccx's stored blocks and ours (rank 0's directory for all processes; both on every one)."""
    root = Path(comm.bcast(str(tmp_path), root=0))
    if comm.rank == 0:
        shutil.copy(DATA / f"{job}.inp", root / f"{job}.inp")
    comm.barrier()
    assert run_job(job, root, comm=comm, progress=False).completed
    comm.barrier()
    return read_dat(DATA / f"{job}.dat.ref"), read_dat(root / f"{job}.dat")


@pytest.mark.mpi
@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
@pytest.mark.parametrize("job", DECKS)
def test_c3d15_contact_matches_ccx(tmp_path, job):
    """U, RF and the contact blocks (CDIS, CSTR, CELS, CNUM) of both increments equal ccx 2.20's
    printed digits, on the same slave nodes (serial and 2 processes).

    ``wedge_punch_quad``: quad8 slave faces (ccx's 1/100, 24/100 shares) on quad8 master faces;
    ``wedge_punch_tri``: tri6 on tri6 (1/999, 332/999); ``wedge_punch_quad_on_tri``: quad8 on
    tri6. Some punch nodes lift off: ccx's open springs (positive clearance) are in CDIS too.
    ``*_curved``: the punch's edges curved, where the quadrilaterals' face areas need ccx's
    2 x 2 points (3 x 3 give CDIS, CSTR, CELS 3e-6 off). ``wedge_punch_mixed``: the slave
    surface holds quadrilaterals and triangles (per-type spring areas). ``wedge_node_mixed``:
    the node set of that bottom (``TYPE=NODE``): the exterior faces touching it, bottom and
    sides, both kinds, the midside nodes with ccx's fallback area (held between pairings);
    ``wedge_node_quad``: the node set of the quadrilateral bottom. ``wedge_adjust_*``: the
    punch 0.002 above the block, ADJUST moves the bottom's corners (a node set) or all its
    nodes (a distance) onto the block; the 18-node geometry's face centres follow them
    (docs/method.md §38.6: without, CDIS and CSTR were 1 % off). ``wedge_master_mixed``,
    ``wedge_master_mixed_tri``: the master holds quadrilaterals and triangles (one search over
    both, springs of 9 and 7 nodes): slave nodes on both kinds, and some 0.005 from the border;
    ``wedge_master_mixed_slide``: with friction, the punch then slid 0.15 in 10 increments,
    slave nodes moving from triangles onto quadrilaterals and back (a friction history across
    the kinds).
    """
    ccx, ours = _run(tmp_path, job, MPI.COMM_WORLD)
    names = ["U", "RF", "CDIS", "CSTR", "CELS", "CNUM"]
    times = SLIDE_TIMES if job == SLIDE else (0.5, 1.0)
    assert [(b.name, b.time) for b in ccx] == [(n, t) for t in times for n in names]
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in ccx]
    worst: dict[str, float] = {}
    for a, b in zip(ccx, ours):
        np.testing.assert_array_equal(b.labels, a.labels)  # the same slave nodes, in ccx order
        scale = np.abs(a.values).max()
        assert scale > 0.0
        worst[a.name] = max(
            worst.get(a.name, 0.0), float(np.abs(a.values - b.values).max() / scale)
        )
    assert all(value < 1e-6 for value in worst.values()), worst


@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
@pytest.mark.parametrize("job", NODE_DECKS)
def test_c3d15_node_surfaces_take_ccx_iterations(tmp_path, job):
    """The node-based decks take ccx's Newton iterations in every increment: the midside nodes'
    fallback area is taken at the first evaluation after each pairing and held (ccx's rule,
    docs/method.md §38.5). With the area taken at every evaluation ``wedge_node_quad`` took 4, 3
    (ccx 4, 2) and printed CSTR 1.2e-6 of the largest off ccx's."""
    ccx = [i.iterations for i in read_sta(DATA / f"{job}.sta.ref")]
    shutil.copy(DATA / f"{job}.inp", tmp_path / f"{job}.inp")
    result = run_job(job, tmp_path, comm=MPI.COMM_SELF, progress=False)
    assert result.completed
    assert [i.iterations for i in result.increments] == ccx
    assert [i.iterations for i in read_sta(tmp_path / f"{job}.sta")] == ccx


@pytest.mark.mpi
@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
@pytest.mark.parametrize("job", TIES)
def test_c3d15_tie_matches_ccx(tmp_path, job):
    """``*TIE`` of the punch's bottom (slave, midside nodes included) to the block's top: U and
    RF equal ccx 2.20's printed digits (serial and 2 processes)."""
    comm = MPI.COMM_WORLD
    ccx, ours = _run(tmp_path, job, comm)
    assert [(b.name, b.time) for b in ccx] == [("U", 1.0), ("RF", 1.0)]
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in ccx]
    for a, b in zip(ccx, ours):
        np.testing.assert_array_equal(b.labels, a.labels)
        assert np.abs(a.values - b.values).max() < 1e-6 * np.abs(a.values).max(), a.name


@pytest.mark.mpi
@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
def test_c3d15_heat_across_contact_matches_ccx(tmp_path):
    """``*HEAT TRANSFER, STEADY STATE`` with the punch on the block: the heat crosses the contact
    springs (quad8 on quad8, ``*GAP CONDUCTANCE`` 30); NT and HFL of both increments equal ccx
    2.20's printed digits (serial and 2 processes)."""
    ccx, ours = _run(tmp_path, HEAT, MPI.COMM_WORLD)
    assert [(b.name, b.time) for b in ccx] == [(n, t) for t in (0.5, 1.0) for n in ("NT", "HFL")]
    assert [(b.name, b.time) for b in ours] == [(b.name, b.time) for b in ccx]
    for a, b in zip(ccx, ours):
        np.testing.assert_array_equal(b.labels, a.labels)
        assert np.abs(a.values - b.values).max() < 1e-6 * np.abs(a.values).max(), a.name


@pytest.mark.skipif(not ON_011, reason="C3D15 needs dolfinx 0.11 (docs/method.md §32.5)")
def test_c3d15_heat_across_contact_depends_on_the_conductance(tmp_path):
    """The springs carry the heat: twice the gap conductance moves the temperatures by more than
    1 % of the largest off ccx's (so the agreement above is the springs')."""
    job = _edited(tmp_path, HEAT, "30., 0.\n30., 1e6", "60., 0.\n60., 1e6")
    assert run_job(job, tmp_path, comm=MPI.COMM_SELF, progress=False).completed
    ccx, ours = read_dat(DATA / f"{HEAT}.dat.ref"), read_dat(tmp_path / f"{job}.dat")
    a, b = ccx[-2], ours[-2]  # NT at the end
    assert a.name == b.name == "NT"
    assert np.abs(a.values - b.values).max() > 1e-2 * np.abs(a.values).max()


def test_c3d15_contact_decks_are_the_generator_s(tmp_path):
    """The stored decks are what ``make_contact.py`` writes, with the faces each names: S3..S5
    (quadrilaterals) or S1, S2 (triangles) in contact."""
    module = _generator()
    decks = {
        **DECKS,
        **{job: (*axes, False) for job, axes in TIES.items()},
        HEAT: (1, 1, False),
    }
    for job, (slave_axis, master_axis, curved) in decks.items():
        nodes = job.startswith("wedge_node")
        module.write(
            tmp_path / f"{job}.inp",
            slave_axis,
            master_axis,
            curved,
            job in TIES,
            nodes,
            adjust=ADJUST.get(job),
            heat=job == HEAT,
            slide=0.15 if job == SLIDE else 0.0,
        )
        assert (tmp_path / f"{job}.inp").read_text() == (DATA / f"{job}.inp").read_text(), job
        deck = read_deck(DATA / f"{job}.inp")
        for name, axes in (("SLAVE", slave_axis), ("MASTER", master_axis)):
            if deck.surfaces[name].type == "NODE":  # the punch's nodes at z = 1
                z = deck.node_coords[deck.node_index(deck.surfaces[name].nodes), 2]
                assert nodes and np.allclose(z, 1.0) and z.size >= 21, (job, z.size)
                continue
            faces = set(deck.surfaces[name].faces.tolist())
            expected = [{1, 2} if axis == 2 else {3, 4, 5} for axis in np.atleast_1d(axes)]
            assert faces <= set().union(*expected), (job, name, faces)
            assert all(faces & kind for kind in expected), (job, name, faces)


@pytest.mark.parametrize("job", MIXED_MASTERS)
def test_mixed_master_references_land_on_both_face_types(job):
    """ccx's springs of the mixed-master decks: slave nodes over the master's triangles (block
    columns 0.5 < x < 1, 1.5 < x < 2) and over its quadrilaterals (0 < x < 0.5, 1 < x < 1.5) in
    both increments, one spring per slave node (CNUM equal to the rows)."""
    deck = read_deck(DATA / f"{job}.inp")
    blocks = read_dat(DATA / f"{job}.dat.ref")
    cdis = [b for b in blocks if b.name == "CDIS"]
    cnum = [b for b in blocks if b.name == "CNUM"]
    assert [b.time for b in cdis] == [0.5, 1.0] == [b.time for b in cnum]
    for springs, count in zip(cdis, cnum):
        assert springs.labels.size == int(count.values.ravel()[0]) == np.unique(springs.labels).size
        x = deck.node_coords[deck.node_index(springs.labels), 0]
        on_triangles = ((x > 0.5) & (x < 1.0)) | (x > 1.5)
        assert 0 < on_triangles.sum() < x.size, (job, springs.time, x)
        assert np.all(springs.values[:, 0] < 0)  # closed springs: penetration


def test_sliding_reference_moves_nodes_across_the_kinds():
    """ccx's springs of ``wedge_master_mixed_slide``: in the sliding step slave nodes change
    from triangles to quadrilaterals and the other way (current x = X + U_x), with slip."""
    deck = read_deck(DATA / f"{SLIDE}.inp")
    blocks = read_dat(DATA / f"{SLIDE}.dat.ref")
    on_triangles = {}
    for time in (1.0, 2.0):
        springs = next(b for b in blocks if b.name == "CDIS" and b.time == time)
        u = next(b for b in blocks if b.name == "U" and b.time == time)
        x = deck.node_coords[deck.node_index(springs.labels), 0]
        x = x + u.values[np.searchsorted(u.labels, springs.labels), 0]
        on_triangles[time] = set(springs.labels[((x > 0.5) & (x < 1.0)) | (x > 1.5)].tolist())
    assert on_triangles[1.0] - on_triangles[2.0] and on_triangles[2.0] - on_triangles[1.0]
    last = next(b for b in blocks if b.name == "CDIS" and b.time == 2.0)
    assert np.abs(last.values[:, 1:]).max() > 0.1  # slipped by most of the 0.15


def _edited(tmp_path: Path, job: str, old: str, new: str) -> str:
    """``job``'s deck with ``old`` replaced by ``new``, written as ``e.inp``: the job name."""
    text = (DATA / f"{job}.inp").read_text()
    assert old in text
    (tmp_path / "e.inp").write_text(text.replace(old, new, 1))
    return "e"


@pytest.mark.skipif(ON_011, reason="dolfinx 0.11 runs C3D15")
def test_c3d15_contact_refused_before_dolfinx_011(tmp_path):
    shutil.copy(DATA / "wedge_punch_quad.inp", tmp_path / "wedge_punch_quad.inp")
    with pytest.raises(
        NotImplementedError, match=r"wedge_punch_quad\.inp:\d+: C3D15 \(element 1\)"
    ):
        run_job("wedge_punch_quad", tmp_path, progress=False)


@pytest.mark.skipif(not ON_011, reason="the refusals of a C3D15 deck on dolfinx 0.11")
def test_c3d15_contact_refusals_name_the_deck_line(tmp_path):
    """What is not built stays refused with the deck line: cyclic symmetry, contact and ties in
    decks with coupled temperature-displacement steps (ties: any thermal step), ADJUST node sets
    with midside nodes (as on C3D20, §11.5), ADJUST and the ``.cel`` file with a master
    surface of triangles and quadrilaterals; a face inside the mesh is an error naming it."""
    cyclic = "*TIE, NAME=T, CYCLIC SYMMETRY"
    job = _edited(tmp_path, "wedge_tie_quad", "*TIE, NAME=T", cyclic)
    (tmp_path / "e.inp").write_text(
        (tmp_path / "e.inp").read_text()
        + "*CYCLIC SYMMETRY MODEL, N=12, TIE=T\n0., 0., 0., 0., 0., 1.\n"
    )
    with pytest.raises(NotImplementedError, match=r"e\.inp:\d+: \*TIE T, CYCLIC SYMMETRY on C3D15"):
        run_job(job, tmp_path, progress=False)
    heat = "*STEP\n*HEAT TRANSFER, STEADY STATE\n*END STEP\n"
    job = _edited(tmp_path, "wedge_tie_quad", "*STEP, INC=100", heat + "*STEP, INC=100")
    with pytest.raises(NotImplementedError, match=r"e\.inp:\d+: ties on C3D15 elements in a deck"):
        run_job(job, tmp_path, progress=False)
    coupled = "*COUPLED TEMPERATURE-DISPLACEMENT, STEADY STATE"
    job = _edited(tmp_path, HEAT, "*HEAT TRANSFER, STEADY STATE", coupled)
    with pytest.raises(
        NotImplementedError, match=r"e\.inp:\d+: contact pairs on C3D15 elements in a deck with"
    ):
        run_job(job, tmp_path, progress=False)
    adjust = "TYPE=NODE TO SURFACE, ADJUST=TOP"
    job = _edited(tmp_path, "wedge_punch_quad", "TYPE=NODE TO SURFACE", adjust)
    with pytest.raises(
        NotImplementedError, match=r"e\.inp:\d+: ADJUST=TOP with node \d+, which is not an element"
    ):
        run_job(job, tmp_path, progress=False)
    job = _edited(tmp_path, "wedge_master_mixed", "NODE TO SURFACE", "NODE TO SURFACE, ADJUST=0.01")
    with pytest.raises(NotImplementedError, match=r"e\.inp:\d+: ADJUST with the master surface"):
        run_job(job, tmp_path, progress=False)
    cel = "*NODE FILE, CONTACT ELEMENTS\nU\n*END STEP"
    job = _edited(tmp_path, "wedge_master_mixed", "*END STEP", cel)
    with pytest.raises(
        NotImplementedError, match=r"e\.inp:\d+: CONTACT ELEMENTS \(the \.cel file\)"
    ):
        run_job(job, tmp_path, progress=False)
    # the block's wedges along z: element 1's top triangle (z = 0.5) is shared by the layer above
    job = _edited(
        tmp_path, "wedge_punch_tri", "*SURFACE, NAME=SLAVE\n", "*SURFACE, NAME=SLAVE\n1, S2\n"
    )
    with pytest.raises(ValueError, match=r"e\.inp:\d+: \*SURFACE SLAVE: face S2 of element 1 lies"):
        run_job(job, tmp_path, progress=False)
