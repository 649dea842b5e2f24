"""The contact-phase benchmark's plates in 2D and 3D: every slave node gets a compressed spring."""

from __future__ import annotations

import contact_phases
import pytest


@pytest.mark.parametrize("dim, slave_nodes", [(2, 40), (3, 36)])
def test_benchmark_plates_run_every_phase(dim: int, slave_nodes: int) -> None:
    result = contact_phases.run_size(slave_nodes, repeat=1, solver="mumps", dim=dim, log=print)
    assert result["slave_nodes"] == slave_nodes
    assert result["springs"] == slave_nodes
    assert result["dofs"] > dim * 2 * slave_nodes
    assert contact_phases.contact_share(result) > 0.0  # a timing: its size is the benchmark's
    assert "contact share" in contact_phases.report([result], 1)
