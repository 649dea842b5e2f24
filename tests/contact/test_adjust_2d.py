"""ADJUST on a 2D mesh: slave nodes moved onto the master edges at the first pairing (§11.5).

The upper block of the 2D patch test starts GAP above the lower one. ADJUST by a distance moves its
whole bottom onto the lower block's top (strain-free: the mesh geometry moves), so the press gives
the patch test's uniform pressure, to 1e-8, as if there had been no gap; ADJUST by a node set moves
the named vertices only. On several processes the serial answer, node by node.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from helpers.blocks_2d import PARTITIONS, PRESSURE, patch_problem, solve_patch
from helpers.serial_answer import sorted_rows

import dolfinx.mesh

import dolfinx_ntf as ntf

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD
GAP = 0.003


def _left_bottom(mesh):
    """The upper block's bottom vertices with x < 0.5, as a node set (each process its own)."""
    vertices = dolfinx.mesh.locate_entities(mesh, 0, lambda x: np.isclose(x[1], GAP) & (x[0] < 0.5))
    return ntf.NodeSurface(vertices, name="left")


def _solve(comm, partition, kind, degree=1):
    adjust = 0.005 if kind == "distance" else _left_bottom
    problem, pressure, _ = patch_problem(
        comm, partition=partition, gap=GAP, adjust=adjust, degree=degree
    )
    mesh = problem.u.function_space.mesh
    results = solve_patch(problem, pressure)
    owned = mesh.geometry.index_map().size_local
    geometry = sorted_rows(comm, mesh.geometry.x[:owned, :2])
    (table,) = ntf.contact_results(problem)
    springs = sorted_rows(
        comm, np.column_stack([table.position, table.area, table.pressure, table.clearance])
    )
    force = ntf.contact_force(problem)
    problem.destroy()
    return [(r.iterations, r.springs) for r in results], geometry, springs, force


@pytest.mark.parametrize("kind", ["distance", "node set"])
@pytest.mark.parametrize("partition", sorted(PARTITIONS))
def test_adjust_2d_gives_the_serial_answer(partition, kind):
    increments, geometry, springs, force = _solve(COMM, PARTITIONS[partition], kind)
    serial = _solve(MPI.COMM_SELF, None, kind)
    assert increments == serial[0]
    np.testing.assert_allclose(geometry, serial[1], rtol=0, atol=1e-15)
    assert springs.shape == serial[2].shape == (5, 5)
    np.testing.assert_allclose(springs, serial[2], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(force, serial[3], rtol=0, atol=1e-10 * abs(serial[3][1]))
    # what moved: the whole bottom (distance) or its vertices with x < 0.5 (node set)
    bottom = geometry[np.isclose(geometry[:, 1], 0.0, atol=1e-15)]
    lifted = geometry[np.isclose(geometry[:, 1], GAP, atol=1e-15)]
    lower_top = 5  # the lower block's top nodes stay at y = 0
    if kind == "distance":
        assert bottom.shape[0] == lower_top + 5 and lifted.shape[0] == 0
    else:
        assert bottom.shape[0] == lower_top + 2 and lifted.shape[0] == 3
        assert np.all(lifted[:, 0] >= 0.5)


@pytest.mark.parametrize("degree", [1, 2])
def test_adjust_2d_closes_the_gap_for_the_patch_test(degree):
    """ADJUST by distance: zero clearance at the start, then the uniform pressure to 1e-8."""
    if degree == 2:  # P2 on a P1 mesh: the midside nodes have no geometry node to move
        with pytest.raises(NotImplementedError, match="ADJUST"):
            _solve(COMM, None, "distance", degree=2)
        return
    increments, _, springs, force = _solve(COMM, None, "distance")
    assert all(iterations <= 3 for iterations, _ in increments)
    pressure = springs[:, 3]
    np.testing.assert_allclose(pressure, pressure.mean(), rtol=1e-8)
    assert force[1] == pytest.approx(PRESSURE, rel=1e-10)  # on the upper block, width 1
    # without ADJUST the gap stays: the block falls onto the lower one before it is pressed
    problem, pressure_constant, _ = patch_problem(COMM, gap=GAP)
    with pytest.raises(ntf.ContactSolverError, match="no contact springs"):
        solve_patch(problem, pressure_constant)
    problem.destroy()
