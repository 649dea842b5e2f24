"""Friction on several processes gives the serial answer (docs/method.md §14.6).

A punch pressed onto a block, dragged (stick, then slip), then dragged on with a larger friction
coefficient (``ChangeFriction``), each step of several increments. Every run is compared with the
same analysis solved on ``COMM_SELF`` in the same run: the Newton iterates, iteration counts,
pairings and the friction outputs of every spring. In serial the comparisons are trivial.
"""

from mpi4py import MPI

import numpy as np
import pytest
from helpers.serial_answer import (
    PARTITIONS,
    assert_same_friction,
    cut_along_x,
    friction_analysis,
    serial_friction_analysis,
)

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD


def _mixed(serial):
    """The serial analysis really sticks and slips."""
    sliding = [table[:, 10] for table in serial.outputs]
    assert any(s.size and not s.any() for s in sliding)  # all springs stick (press, early drag)
    assert any(s.size and s.all() for s in sliding)  # all slip (late drag)
    assert serial.springs.shape[0] >= 8 and np.abs(serial.springs[:, 4:7]).max() > 0.5


@pytest.mark.parametrize("partition", PARTITIONS)
def test_frictional_analysis_gives_the_serial_answer(partition):
    """Every partition, one body per process and an idle process included; no hang."""
    serial = serial_friction_analysis()
    _mixed(serial)
    run = friction_analysis(COMM, PARTITIONS[partition])
    assert_same_friction(run, serial)
    assert run.mallocs == 0


@pytest.mark.parametrize(
    "options",
    [
        {"cell": "tetrahedron"},
        {
            "friction_tangent": "ccx",
            "reset_friction_on_separation": False,
            "friction_in_tension": True,
            "symmetric": True,
        },
    ],
    ids=["tetrahedra", "calculix-options"],
)
def test_friction_options_give_the_serial_answer(options):
    """Tetrahedra; CalculiX's tangent, stale state and friction in tension (the deck runner's)."""
    options = dict(options)
    cell = options.pop("cell", "hexahedron")
    run = friction_analysis(COMM, cut_along_x, cell, **options)
    assert_same_friction(run, serial_friction_analysis(cell, **options))
