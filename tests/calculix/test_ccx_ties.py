"""CalculiX's choice on exact ties (docs/method.md §3.6): the deck runner's ``.cel`` sets against
ccx 2.20's on a tie deck, and the floating-point nearest centroid of the ccx-mode search."""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

from dolfinx_ntf.calculix.cel import compare_cel
from dolfinx_ntf.calculix.job import run_job
from dolfinx_ntf.kernels.faces import QUAD4
from dolfinx_ntf.kernels.rigid import RigidPlane, rigid_master
from dolfinx_ntf.kernels.search import MasterSurface

TIES = Path(__file__).resolve().parents[1] / "data" / "calculix" / "ties"
import make_tie_deck  # noqa: E402

pytestmark = pytest.mark.serial


@pytest.mark.parametrize("job", sorted(make_tie_deck.DECKS))
def test_stored_tie_decks_are_the_generators(job):
    """Same cards; the rotated deck's coordinates may differ in the last digit between numpy
    builds (the stored file is the one ccx ran)."""
    stored = (TIES / f"{job}.inp").read_text().splitlines()
    made = make_tie_deck.deck_text(job).splitlines()
    assert len(stored) == len(made)
    for a, b in zip(stored, made):
        if a != b:
            x, y = (np.array([float(v) for v in line.split(",")]) for line in (a, b))
            np.testing.assert_allclose(x, y, rtol=1e-15, atol=0)


@pytest.mark.parametrize("job", sorted(make_tie_deck.DECKS))
def test_deck_runner_pairs_a_tie_deck_like_ccx(tmp_path, job):
    """21 of the 25 slave nodes are ties between two master faces; ccx 2.20's ``.cel`` is stored.

    Iteration 1 pairs the undeformed mesh: every node gets ccx's face (the position order alone
    gives 21 of them another face on ``tie_grid``). Later pairings also agree, except possibly at
    the centre node 63: above the master node on both symmetry planes of the deck, its tie
    persists under load and the round-off of each code's displacement decides it.
    """
    shutil.copy(TIES / f"{job}.inp", tmp_path)
    result = run_job(job, tmp_path, comm=MPI.COMM_SELF, progress=False)
    assert [inc.iterations for inc in result.increments] == [3]
    first, *later = compare_cel(TIES / f"{job}.cel", tmp_path / f"{job}.cel")
    assert first.set.endswith("_it1") and first.count == 0
    assert [d.set[-3:] for d in later] == ["it2", "it3"]
    assert all(d.count == len(d.other_face) and set(d.other_face) <= {63} for d in later)


def _grid(offset: float) -> MasterSurface:
    """2 x 2 unit quads facing +z (corners counterclockwise), shifted by ``offset`` in x and y."""
    xy = np.array([(i, j) for j in range(3) for i in range(3)], dtype=float) + offset
    coords = np.column_stack([xy, np.zeros(9)])
    faces = [[i + 3 * j, i + 1 + 3 * j, i + 1 + 3 * (j + 1), i + 3 * (j + 1)]
             for j in range(2) for i in range(2)]  # fmt: skip
    return MasterSurface(QUAD4, np.array(faces), coords=coords)


def test_ccx_ties_follow_the_floating_point_distance():
    """Above the middle node, the centroids of the SW and NE faces' corner triangles are equally
    near; in floating point (ccx's sums) the NE one is nearer by an ulp, and ccx 2.20 takes it."""
    surface = _grid(0.0)
    point = np.array([[1.0, 1.0, 0.0]])
    assert surface.locate(point, 1e-3, ccx_ties=True)[0] == 3  # NE, as ccx
    assert surface.locate(point, 1e-3)[0] == 0  # SW: first in position order


def test_ccx_ties_equal_in_floating_point_fall_back_to_the_position_order():
    surface = _grid(-1.0)  # symmetric about the origin: the sums are exact
    centroids = surface.triangle_centroids
    np.testing.assert_array_equal(centroids[1], -centroids[6])
    point = np.zeros((1, 3))
    assert surface.locate(point, 1e-3, ccx_ties=True)[0] == 0
    assert surface.locate(point, 1e-3)[0] == 0


def test_rigid_masters_take_the_ccx_search_option():
    """The deck runner's search passes ``ccx_ties`` to every master, rigid ones included."""
    _, master = rigid_master(RigidPlane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0)), lambda: 1.0)
    points = np.array([[0.0, 0.0, -0.1], [1.0, 2.0, 0.5]])
    np.testing.assert_array_equal(master.locate(points, 1e-3, ccx_ties=True), [0, 0])
