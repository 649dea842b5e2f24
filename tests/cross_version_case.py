"""Contact solves whose results are stored per dolfinx version and compared across versions.

``python tests/cross_version_case.py`` (from the repository root, with the project's .venv) writes
``tests/data/cross_version/dolfinx-<major>.<minor>.npz`` for the installed dolfinx; the test
``test_cross_version.py`` solves the same cases and compares with every stored file, so a run on
Debian 12 (dolfinx 0.5.2) checks the results of Debian 13 (dolfinx 0.9) and sid (dolfinx 0.11), and
each of those checks the others. In a chroot of another release (``scripts/other_release.sh``), run
it with that release's .venv and copy the file back.
Nodes are matched by their coordinates, since the two versions number dofs differently.
"""

from __future__ import annotations

from pathlib import Path

from mpi4py import MPI

import numpy as np
from helpers import punch_problem

import dolfinx_ntf as ntf
from dolfinx_ntf import compat

DATA = Path(__file__).parent / "data" / "cross_version"
CASES = {
    "hex_p1_linear": ("hexahedron", 1, "linear"),
    "tet_p2_exponential": ("tetrahedron", 2, "exponential"),
}
LOAD = 10.0


def solve(case: str) -> dict[str, np.ndarray]:
    """Solve one case; node data sorted by reference coordinates (rounded to 1e-9)."""
    cell, degree, law_name = CASES[case]
    law = ntf.ExponentialLaw(c0=1e-3, p0=5.0) if law_name == "exponential" else None
    # The punch's nodes lie above no master node, edge or face diagonal: which of two faces holds
    # a node on their shared edge depends on the numbering, which differs between versions.
    problem, pressure, _ = punch_problem(
        cell,
        ((0.23, 0.17, 0.0), (0.6, 0.6, 0.5), (3, 3, 2)),
        degree=degree,
        law=law,
        comm=MPI.COMM_SELF,
    )
    u = problem.u
    V = u.function_space
    # The stored results were made before the round-off floor (issue 21): the same test here.
    solver = ntf.ContactNewtonSolver(V.mesh.comm, problem, roundoff_floor=False)
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
