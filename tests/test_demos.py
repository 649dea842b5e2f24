"""The demos are tests too: both run on their coarse meshes and their summaries are checked.

Serial here; tests/test_parallel.py runs the punch demo on 2 and 3 processes.
"""

import importlib.util
from pathlib import Path

import pytest

pytestmark = pytest.mark.serial

DEMOS = Path(__file__).resolve().parents[1] / "demos"


def _demo(name):
    """Import ``demos/<name>.py`` by path under a name that cannot shadow anything."""
    spec = importlib.util.spec_from_file_location(f"_demo_{name}", DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_punch_demo_balances_the_load(tmp_path):
    summary = _demo("punch").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    assert summary["increments"] == 4
    assert summary["load"][-1] == pytest.approx(100.0 * 40 * 40)
    # Equilibrium of the punch: Σ F_z and Σ p A n_z equal the load; Σ p A exceeds it by the tilt
    # of the master normals only (measured 2.5e-7).
    assert summary["vertical_error"] < 1e-8
    assert summary["normal_error"] < 1e-8
    assert summary["reaction_error"] < 1e-8  # the block bottom carries the load (reaction helper)
    assert 0 < summary["pressure_area_deviation"] < 1e-5
    # All 5 x 5 punch-bottom nodes are in contact from the first increment on; the pressure peaks
    # at the punch edges (measured 2.1 times the mean).
    assert summary["springs"] == [25, 25, 25, 25]
    assert summary["contact_area"] == pytest.approx(40 * 40, rel=1e-3)
    assert summary["max_pressure"] > 1.5 * summary["mean_pressure"]
    # Measured 4, 2, 2, 2 iterations (3-4 on the default mesh).
    assert max(summary["iterations"]) <= 6
    assert Path(summary["xdmf"]).exists() and Path(summary["xdmf"]).with_suffix(".h5").exists()


def test_hertz_demo_is_close_to_hertz(tmp_path):
    summary = _demo("hertz_sphere").main(["--coarse", "--quiet", "--output", str(tmp_path)])
    assert summary["passed"]
    assert summary["equilibrium_error"] < 1e-8
    assert summary["unpaired_penetrations"] == 0
    # Measured on the coarse mesh (about 4 elements across the contact radius): total force
    # 3.61e5 N, force of the fitted profile -2.4 %, contact radius -3.5 %, peak pressure +4.7 %
    # (fit) and +4.2 % (nodal maximum); on the default mesh -0.6 % radius, +2.3 % peak pressure.
    assert summary["force"] == pytest.approx(3.61e5, rel=0.1)
    assert abs(summary["fit_force_error"]) < 0.06
    assert abs(summary["a_error"]) < 0.08
    assert abs(summary["p0_error"]) < 0.10
    assert abs(summary["p_max_error"]) < 0.15
    # Hertz's radius falls between the last closed node and the first open one.
    assert summary["a_last_closed"] < summary["a_hertz"] < summary["a_first_open"]
    # Measured 3-5 Newton iterations per increment, no cutback.
    assert summary["increments"] == 8
    assert max(summary["iterations"]) <= 8
    assert Path(summary["xdmf"]).exists() and Path(summary["png"]).exists()
