"""The layer check of ``make lint`` (scripts/check_layers.py): the package and planted faults."""

import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
CHECK = ROOT / "scripts" / "check_layers.py"

pytestmark = pytest.mark.serial


def run_check(package: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, str(CHECK), str(package)], capture_output=True, text=True, check=False
    )


def test_package_imports_only_downwards():
    result = run_check(ROOT / "dolfinx_ntf")
    assert result.returncode == 0, result.stdout
    assert "imports only downwards" in result.stdout


@pytest.mark.parametrize(
    ("module", "planted", "message"),
    [
        ("kernels/laws.py", "import dolfinx.fem", "the numpy kernels import dolfinx.fem"),
        ("kernels/faces.py", "from mpi4py import MPI", "the numpy kernels import mpi4py"),
        (
            "fem/surfaces.py",
            "from dolfinx_ntf.contact import problem",
            "fem (layer 2) imports dolfinx_ntf.contact",
        ),
        (
            "parallel/halo.py",
            "from dolfinx_ntf import calculix",
            "parallel (layer 3) imports dolfinx_ntf.calculix",
        ),
        ("solvers/newton.py", "import dolfinx_ntf.outputs.results", "sibling layer"),
        (
            "solvers/newton_loop.py",
            "import dolfinx.nls.petsc",
            "imports dolfinx.nls.petsc, which dolfinx has removed",
        ),
        ("compat.py", "from dolfinx.nls import petsc", "imports dolfinx.nls, which dolfinx has"),
    ],
)
def test_planted_upward_import_fails(tmp_path, module, planted, message):
    package = tmp_path / "dolfinx_ntf"
    shutil.copytree(ROOT / "dolfinx_ntf", package, ignore=shutil.ignore_patterns("__pycache__"))
    target = package / module
    target.write_text(target.read_text() + f"\n\ndef _planted():\n    {planted}\n")
    result = run_check(package)
    assert result.returncode == 1
    assert message in result.stdout
    assert f"{module}:" in result.stdout.replace("\\", "/")
