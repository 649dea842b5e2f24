"""Contact solves whose results are stored per dolfinx version and compared across versions.

``python tests/cross_version_case.py`` (from the repository root, with the project's .venv) writes
``tests/data/cross_version/dolfinx-<major>.<minor>.npz`` for the installed dolfinx; the test
``test_cross_version.py`` solves the same cases and compares with every stored file, so a run on
Debian 12 (dolfinx 0.5.2) checks the results of Debian 13 (dolfinx 0.9) and the other way round.
Nodes are matched by their coordinates, since the two versions number dofs differently.
"""

from __future__ import annotations

import sys
from pathlib import Path

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

sys.path.insert(0, str(Path(__file__).parent))
from conftest import LOWER_BOTTOM, LOWER_TOP, UPPER_BOTTOM, UPPER_TOP, two_blocks

DATA = Path(__file__).parent / "data" / "cross_version"
CASES = {
    "hex_p1_linear": ("hexahedron", 1, "linear"),
    "tet_p2_exponential": ("tetrahedron", 2, "exponential"),
}
E, NU, LOAD = 1000.0, 0.3, 10.0


def solve(case: str) -> dict[str, np.ndarray]:
    """Solve one case; node data sorted by reference coordinates (rounded to 1e-9)."""
    cell, degree, law_name = CASES[case]
    # The punch's nodes lie above no master node, edge or face diagonal: which of two faces holds
    # a node on their shared edge depends on the numbering, which differs between versions.
    mesh, _, ft = two_blocks(
        MPI.COMM_SELF, cell=cell, upper=((0.23, 0.17, 0.0), (0.6, 0.6, 0.5), (3, 3, 2))
    )
    V = compat.vector_space(mesh, "Lagrange", degree)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    pressure = dolfinx.fem.Constant(mesh, 0.0)
    ds = ufl.Measure("ds", domain=mesh, subdomain_data=ft)
    sigma = ntf.small_strain_stress(u, E, NU)
    F = ufl.inner(sigma, ufl.grad(v)) * ufl.dx + pressure * ufl.inner(
        ufl.FacetNormal(mesh), v
    ) * ds(UPPER_TOP)
    bottom = dolfinx.fem.locate_dofs_topological(V, 2, ft.find(LOWER_BOTTOM))
    bcs = [
        dolfinx.fem.dirichletbc(np.zeros(3), bottom, V),
        ntf.component_bc(V, 0, ft.find(UPPER_TOP)),
        ntf.component_bc(V, 1, ft.find(UPPER_TOP)),
    ]
    law = (
        ntf.LinearLaw.with_ccx_defaults(E)
        if law_name == "linear"
        else ntf.ExponentialLaw(c0=1e-3, p0=5.0)
    )
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(law),
    )
    problem = ntf.ContactProblem(F, u, [pair], bcs)
    solver = ntf.ContactNewtonSolver(mesh.comm, problem)
    step = ntf.StaticStep(
        lambda t: setattr(pressure, "value", LOAD * t), initial_increment=0.5, fixed=True
    )
    increments = step.run(solver, u)

    X = V.tabulate_dof_coordinates().reshape(-1, 3)
    order = np.lexsort(np.round(X, 9).T[::-1])
    result = ntf.contact_results(problem)[0]
    slave_order = np.lexsort(np.round(X[result.node], 9).T[::-1])
    return {
        "coordinates": X[order],
        "displacement": u.x.array.reshape(-1, 3)[order],
        "slave_coordinates": X[result.node][slave_order],
        "pressure": result.pressure[slave_order],
        "clearance": result.clearance[slave_order],
        "iterations": np.array([inc.iterations for inc in increments]),
    }


def reference_path(version: tuple[int, int] = compat.DOLFINX_VERSION) -> Path:
    """The stored results of a dolfinx version."""
    return DATA / f"dolfinx-{version[0]}.{version[1]}.npz"


def main() -> None:
    results = {f"{case}/{key}": value for case in CASES for key, value in solve(case).items()}
    DATA.mkdir(parents=True, exist_ok=True)
    np.savez_compressed(reference_path(), **results)
    print(f"wrote {reference_path()}")


if __name__ == "__main__":
    main()
