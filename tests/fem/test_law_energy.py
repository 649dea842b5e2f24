"""The plasticity laws' strain energy density and internal variables (docs/method.md §36).

A homogeneous strain path (stretch and shear past yield, partly unloaded) on a hexahedral mesh:
every point's ``strain_energy_density`` is the trapezoidal sum of the kernels' stress and strain
of the same path, an attempt that is rejected adds nothing, and ``state_variables`` holds the
committed equivalent plastic strain and plastic strain (``(I - Cp^-1)/2`` for the finite-strain
law); serial and on 2 processes.
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np
import pytest
from helpers import box_grid

import dolfinx.fem

from dolfinx_ntf import compat
from dolfinx_ntf.fem.finite_plasticity import FiniteStrainJ2Plasticity
from dolfinx_ntf.fem.plasticity import J2Plasticity
from dolfinx_ntf.kernels.finite_plasticity import finite_return_map
from dolfinx_ntf.kernels.plasticity import (
    IsotropicHardening,
    mandel_from_tensor,
    return_map,
    tensor_from_mandel,
)
from dolfinx_ntf.kernels.strain_energy import green_lagrange_pair, trapezoidal_energy

E, NU = 5000.0, 0.3
TABLE = IsotropicHardening((50.0, 80.0, 90.0), (0.0, 0.01, 0.05))
#: Homogeneous displacement gradients of the path: loading past yield, then partly unloading.
PATH = [s * np.array([[1.0, 0.3, 0.0], [0.0, -0.3, 0.1], [0.0, 0.0, -0.3]]) for s in
        (0.005, 0.01, 0.02, 0.03, 0.025)]  # fmt: skip


def _law(kind: type):
    points, hexes = box_grid((0, 0, 0), (2, 1, 1), (2, 1, 1))
    comm = MPI.COMM_WORLD
    if comm.rank != 0:
        points, hexes = np.empty((0, 3)), np.empty((0, 8), dtype=np.int64)
    mesh = compat.create_mesh(comm, hexes.astype(np.int64), points,
                              compat.coordinate_element("hexahedron"))  # fmt: skip
    u = dolfinx.fem.Function(compat.vector_space(mesh))
    return u, kind(u, E, NU, TABLE)


def _expected(kind: type) -> tuple[float, np.ndarray]:
    """The kernels' energy and internal variables at the path's end (one point)."""
    energy = np.zeros(1)
    old = (np.zeros((1, 3, 3)), np.zeros((1, 3, 3)))
    if kind is J2Plasticity:
        ep, alpha = np.zeros((1, 6)), np.zeros(1)
    else:
        cp, alpha = np.eye(3)[None], np.zeros(1)
    for H in PATH:
        if kind is J2Plasticity:
            e = 0.5 * (H + H.T)[None]
            r = return_map(mandel_from_tensor(e), ep, alpha, E, NU, TABLE)
            ep, alpha = r.plastic_strain, r.equivalent_plastic_strain
            new = (tensor_from_mandel(r.stress), e)
        else:
            F = (np.eye(3) + H)[None]
            r = finite_return_map(F, cp, alpha, E, NU, TABLE)
            cp, alpha = r.inverse_plastic_metric, r.equivalent_plastic_strain
            new = green_lagrange_pair(F, r.first_piola)
        energy = trapezoidal_energy(energy, old[0], new[0], old[1], new[1])
        old = new
    if kind is J2Plasticity:
        tensor = tensor_from_mandel(ep)
    else:
        tensor = 0.5 * (np.eye(3) - cp)
    rows, cols = (0, 1, 2, 0, 0, 1), (0, 1, 2, 1, 2, 2)
    return float(energy[0]), np.concatenate([alpha, tensor[0, rows, cols]])


@pytest.mark.mpi
@pytest.mark.parametrize("kind", [J2Plasticity, FiniteStrainJ2Plasticity])
def test_energy_and_state_variables_of_a_homogeneous_path(kind: type) -> None:
    u, law = _law(kind)
    assert np.all(law.strain_energy_density == 0.0)
    for k, H in enumerate(PATH):
        u.interpolate(lambda x, H=H: H @ x)
        if k == 2:  # an attempt past this one, rejected: it adds nothing
            u.interpolate(lambda x, H=H: 3 * H @ x)
            law.evaluate()
            law.increment_rejected()
            u.interpolate(lambda x, H=H: H @ x)
        law.increment_converged()
    energy, variables = _expected(kind)
    assert variables[0] > 0.01  # past yield
    n = law.strain_energy_density.size
    np.testing.assert_allclose(law.strain_energy_density, np.full(n, energy), rtol=1e-10)
    np.testing.assert_allclose(law.state_variables(), np.tile(variables, (n, 1)), atol=1e-12)
    cells = law.cells
    if cells.size:
        per_cell = law.cell_strain_energy_densities(cells[:1])
        assert per_cell.shape == (1, 8)
        assert law.cell_state_variables(cells[:1]).shape == (1, 8, 7)
