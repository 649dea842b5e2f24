"""ADJUST on several processes gives the serial answer (docs/method.md §14.6).

A punch 0.003 above the block: ADJUST by distance moves its whole bottom onto the block, ADJUST by a
node set (given on every process, each naming the vertices it holds) half of it. The moved nodes'
copies on other processes (ghosts of the mesh, halo nodes of the contact) move with them. Compared
with the same analysis on ``COMM_SELF`` in the same run.
"""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER_TOP, PUNCH, UPPER_BOTTOM, punch_bulk, two_blocks
from helpers.serial_answer import PARTITIONS, solve_step, sorted_rows

import dolfinx.fem
import dolfinx.mesh

import dolfinx_ntf as ntf

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD
GAP = 0.003


def _solve(comm, partition, kind):
    mesh, _, ft = two_blocks(comm, upper=PUNCH, gap=GAP, partition=partition)
    top = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], 0.5 + GAP))
    u, F, pressure, bcs = punch_bulk(mesh, ft, top)
    adjust = 0.005
    if kind == "node set":  # the punch bottom's vertices with x < 0.5
        vertices = dolfinx.mesh.locate_entities(
            mesh, 0, lambda x: np.isclose(x[2], GAP) & (x[0] < 0.5) & (x[0] > 0.1) & (x[1] > 0.1)
        )
        adjust = ntf.NodeSurface(vertices)
    friction = ntf.Friction(0.2, 500.0)
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(1000.0), friction)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), law, adjust=adjust
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    increments, nodes, table = solve_step(comm, problem, pressure, u)
    geometry = sorted_rows(comm, mesh.geometry.x[: mesh.geometry.index_map().size_local])
    springs = sorted_rows(
        comm, np.column_stack([table.position, table.area, table.pressure, table.shear])
    )
    out = (increments, nodes, geometry, springs)
    problem.destroy()
    return out


@pytest.mark.parametrize("kind", ["distance", "node set"])
@pytest.mark.parametrize("partition", PARTITIONS)
def test_adjust_gives_the_serial_answer(partition, kind):
    increments, nodes, geometry, springs = _solve(COMM, PARTITIONS[partition], kind)
    serial = _solve(MPI.COMM_SELF, None, kind)
    assert increments == serial[0]
    scale = np.abs(serial[1][:, 3:]).max()
    np.testing.assert_allclose(nodes[:, :3], serial[1][:, :3], rtol=0, atol=1e-15)
    np.testing.assert_allclose(nodes[:, 3:], serial[1][:, 3:], rtol=0, atol=1e-10 * scale)
    np.testing.assert_allclose(geometry, serial[2], rtol=0, atol=1e-15)
    assert springs.shape == serial[3].shape == (16, 8)
    np.testing.assert_allclose(springs, serial[3], rtol=1e-10, atol=1e-12)
    # what moved: the whole bottom (distance) or the nodes with x < 0.5 (node set)
    grid = np.isin(np.round(serial[1][:, :2], 9), [0.2, 0.4, 0.6, 0.8]).all(axis=1)
    bottom = serial[1][grid & (serial[1][:, 2] < 0.01)]
    moved = np.isclose(bottom[:, 2], 0.0, atol=1e-15)
    assert bottom.shape[0] == 16
    assert moved.sum() == (16 if kind == "distance" else 8)
    assert np.all(moved == ((bottom[:, 0] < 0.5) | (kind == "distance")))
