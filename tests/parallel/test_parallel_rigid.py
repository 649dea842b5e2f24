"""Rigid analytical masters on several processes give the serial answer (docs/method.md §14.6).

The punch of helpers pressed onto a rigid sphere under its centre (the lower block takes no part):
the contact spreads from the four middle nodes.
Compared with the same analysis on ``COMM_SELF`` in the same run.
"""

from mpi4py import MPI

import numpy as np
import pytest
from helpers import PUNCH, UPPER_BOTTOM, punch_bulk, two_blocks
from helpers.serial_answer import PARTITIONS, solve_step_springs

import dolfinx_ntf as ntf

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD
RADIUS = 4.0


def _solve(comm, partition):
    mesh, _, ft = two_blocks(comm, upper=PUNCH, partition=partition)
    u, F, pressure, bcs = punch_bulk(mesh, ft)
    # the four middle nodes of the punch bottom (0.1 sqrt 2 off the axis) touch the sphere
    sphere = ntf.RigidSphere((0.5, 0.5, -np.sqrt(RADIUS**2 - 0.02)), RADIUS)
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(1000.0))
    pair = ntf.ContactPair(ntf.FacetSurface(ft, UPPER_BOTTOM), sphere, law)
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    increments, nodes, springs = solve_step_springs(comm, problem, pressure, u)
    out = (
        increments,
        nodes,
        springs,
        ntf.contact_force(problem),
        problem.matrix.getInfo()["mallocs"],
    )
    problem.destroy()
    return out


@pytest.mark.parametrize("partition", PARTITIONS)
def test_punch_on_a_rigid_sphere_gives_the_serial_answer(partition):
    increments, nodes, springs, force, mallocs = _solve(COMM, PARTITIONS[partition])
    serial = _solve(MPI.COMM_SELF, None)
    assert increments == serial[0]
    scale = np.abs(serial[1][:, 3:]).max()
    np.testing.assert_allclose(nodes, serial[1], rtol=0, atol=1e-10 * scale)
    # positions, areas (complete at partition cuts) and pressures of every spring
    assert springs.shape == serial[2].shape and serial[2].shape[0] > 4
    np.testing.assert_allclose(springs, serial[2], rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(force, serial[3], rtol=0, atol=1e-10 * np.abs(serial[3]).max())
    # the load reaches the sphere: its force balances the pressure on the punch top (0.6 x 0.6)
    assert force[2] == pytest.approx(20.0 * 0.36, rel=1e-8) and mallocs == 0
