"""Cost of J2 plasticity at quadrature points (docs/method.md §21.4).

Prints the time of the numpy return map per point, and on a box of ``--cells`` linear hexahedra
(default 8 000, 2x2x2 Gauss points each, most of them yielding) the time of one
``J2Plasticity.evaluate`` (strain Expression, return map, writing the quadrature Functions) beside
the assembly of the residual and of the Jacobian with the quadrature tangent, and of the elastic
UFL Jacobian of the same mesh for comparison.

Run: ``python benchmarks/plasticity_cost.py [--cells N] [--points N]``.
"""

from __future__ import annotations

import argparse
import time

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.kernels.plasticity import return_map

TABLE = ntf.IsotropicHardening((250.0, 300.0, 320.0), (0.0, 0.002, 0.01))
E, NU = 200e3, 0.3


def _seconds(action) -> float:
    """The best of three wall-clock times of ``action()``."""
    best = np.inf
    for _ in range(3):
        start = time.perf_counter()
        action()
        best = min(best, time.perf_counter() - start)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cells", type=int, default=8_000)
    parser.add_argument("--points", type=int, default=200_000)
    args = parser.parse_args()
    rng = np.random.default_rng(0)
    n = args.points
    strain = rng.normal(size=(n, 6)) * 2e-3
    plastic, alpha = np.zeros((n, 6)), np.zeros(n)
    kernel = _seconds(lambda: return_map(strain, plastic, alpha, E, NU, TABLE))
    share = return_map(strain, plastic, alpha, E, NU, TABLE).plastic.mean()
    print(f"return_map: {n} points ({share:.0%} plastic), {kernel * 1e6 / n:.2f} us per point")

    k = max(1, round(args.cells ** (1 / 3)))
    mesh = dolfinx.mesh.create_box(
        MPI.COMM_SELF, [np.zeros(3), np.ones(3)], [k, k, k], dolfinx.mesh.CellType.hexahedron
    )
    V = compat.vector_space(mesh)
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda x: 3e-3 * np.vstack([x[0] * x[1], x[1] * x[2] - x[0] ** 2, x[2] * x[0]]))
    material = ntf.J2Plasticity(u, E, NU, TABLE)
    v, du = ufl.TestFunction(V), ufl.TrialFunction(V)
    L = dolfinx.fem.form(material.residual(v))
    a = dolfinx.fem.form(material.jacobian(du, v))
    elastic = dolfinx.fem.form(ufl.inner(ntf.small_strain_stress(du, E, NU), ufl.grad(v)) * ufl.dx)
    evaluate = _seconds(material.evaluate)
    strain_only = _seconds(material.strain)

    def matrix(form):
        A = dolfinx.fem.petsc.assemble_matrix(form)
        A.assemble()
        A.destroy()

    def vector():
        dolfinx.fem.petsc.assemble_vector(L).destroy()

    print(
        f"{k**3} hexahedra, {material.equivalent_plastic_strain.size} points "
        f"({material.yielding.mean():.0%} yielding), {V.dofmap.index_map.size_global * 3} dofs: "
        f"evaluate {evaluate:.3f} s (of it the strain Expression {strain_only:.3f} s), residual "
        f"{_seconds(vector):.3f} s, Jacobian {_seconds(lambda: matrix(a)):.3f} s (elastic UFL "
        f"Jacobian {_seconds(lambda: matrix(elastic)):.3f} s)"
    )


if __name__ == "__main__":
    main()
