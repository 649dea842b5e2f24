"""A clamped-free elastic bar held to axial motion: the 1D wave guide of the modal tests."""

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.elasticity import component_bc, small_strain_stress


def axial_bar(length: float, E: float, *, tie_end: bool = False):
    """A clamped-free bar (Q2, nu = 0, 16 cells, 0.1 x 0.1) held to axial motion.

    With ``tie_end`` the u_x of every node of the free end is tied to the corner's (the end cell's
    nodes: one process); the ties change no axial mode, they exercise the elimination of
    constraints. Returns the problem and, with ``tie_end``, the end's dofs (else None).
    """
    mesh = dolfinx.mesh.create_box(
        MPI.COMM_WORLD,
        [[0, 0, 0], [length, 0.1, 0.1]],
        [16, 1, 1],
        dolfinx.mesh.CellType.hexahedron,
    )
    V = compat.vector_space(mesh, "Lagrange", 2)
    u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
    F = ufl.inner(small_strain_stress(u, E, 0.0), ufl.grad(v)) * ufl.dx
    every = dolfinx.mesh.locate_entities(mesh, 2, lambda x: np.full(x.shape[1], True))
    clamped = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[0], 0.0))
    bcs = [component_bc(V, 0, clamped), component_bc(V, 1, every), component_bc(V, 2, every)]
    constraints = []
    if tie_end:
        x = V.tabulate_dof_coordinates()
        end = np.flatnonzero(np.isclose(x[:, 0], length))
        corner = end[np.isclose(x[end, 1], 0.0) & np.isclose(x[end, 2], 0.0)][:1]
        constraints = [  # none on a process without the end cell
            ntf.LinearConstraint([node, corner[0]], [0, 0], [1.0, -1.0], name=f"tie {node}")
            for node in end
            if node != corner[0]
        ]
    return ntf.ContactProblem(F, u, [], bcs, constraints=constraints), end if tie_end else None
