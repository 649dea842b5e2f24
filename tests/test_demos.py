"""The demos are tests too: both run on their coarse meshes and their summaries are checked."""

import importlib.util
from pathlib import Path

import pytest

pytestmark = pytest.mark.serial

DEMOS = Path(__file__).resolve().parents[1] / "demos"


def _demo(name):
    spec = importlib.util.spec_from_file_location(f"_demo_{name}", DEMOS / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_punch_demo_balances_the_load(tmp_path):
    summary = _demo("punch").main(["--coarse", "--output", str(tmp_path)])
    assert summary["passed"]
    assert summary["increments"] >= 4
    assert summary["vertical_error"] < 1e-8
    assert summary["normal_error"] < 1e-8
    assert all(springs > 0 for springs in summary["springs"])
    assert max(summary["iterations"]) <= 6
    assert Path(summary["xdmf"]).exists()


def test_hertz_demo_is_close_to_hertz(tmp_path):
    summary = _demo("hertz_sphere").main(["--coarse", "--output", str(tmp_path)])
    # Measured on the coarse mesh: force of the fitted profile -2.4 %, radius -3.6 %, peak pressure
    # +5.1 %.
    assert summary["equilibrium_error"] < 1e-8
    assert abs(summary["fit_force_error"]) < 0.06
    assert abs(summary["a_error"]) < 0.08
    assert abs(summary["p0_error"]) < 0.10
    assert summary["a_last_closed"] < summary["a_hertz"] < summary["a_first_open"]
    assert Path(summary["xdmf"]).exists() and Path(summary["png"]).exists()
