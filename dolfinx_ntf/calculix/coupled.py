"""The increment solver of ``*COUPLED TEMPERATURE-DISPLACEMENT`` steps in the deck runner.

docs/method.md §20.8. :class:`CoupledIncrementSolver` runs the monolithic Newton of
:class:`~dolfinx_ntf.ThermoMechanicalContact` (both fields, the coupling blocks in the Jacobian)
for :class:`~dolfinx_ntf.StaticStep` and gives the job what it reads from its solver (the rows of
the ``.cvg`` file, the largest residual force). The heat problem is a
:class:`~dolfinx_ntf.ThermalContactProblem` on the job's contact problem with ccx's conductance
pressure (``conductance_pressure="ccx"``, §20.1).
"""

from __future__ import annotations

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import ufl

from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.contact.thermal import ThermalContactProblem
from dolfinx_ntf.solvers.coupled import ThermoMechanicalContact

from .model.thermal import ThermalModel

__all__ = ["CoupledIncrementSolver"]


class CoupledIncrementSolver:
    """One Newton on displacement and temperature per increment (the job's solver role).

    Args:
        problem: The job's contact problem (its residual holds the thermal strain).
        residual: The mechanical UFL residual ``problem`` was made from.
        thermal: The deck's temperature field.
    """

    def __init__(self, problem: ContactProblem, residual: ufl.Form, thermal: ThermalModel) -> None:
        #: The heat problem on the springs of ``problem``.
        self.heat = ThermalContactProblem(
            thermal.residual,
            thermal.T,
            problem,
            thermal.conductances,
            thermal.bcs,
            conductance_pressure="ccx",
        )
        #: The monolithic Newton.
        self.coupled = ThermoMechanicalContact(
            residual, self.heat, cell_temperature=thermal.cell_temperature
        )
        self.coupled.coupling_blocks = False  # ccx's iterates (docs/method.md §20.8)
        self.problem = problem
        #: ccx's field controls (kept for the job; the Newton's test is its own, §20.5).
        self.controls: dict[str, float] = {}
        #: ccx's I_P (kept for the job).
        self.relaxation_iteration = 9
        #: Rows of the ``.cvg`` file of the last solve: (iteration, springs, residual norm, 0, 0,
        #: 0).
        self.history: list[tuple[int, int, float, float, float, float]] = []

    @property
    def increment_start(self) -> np.ndarray | None:
        """Displacement at the start of the increment (set by the step)."""
        return self.coupled.increment_start

    @increment_start.setter
    def increment_start(self, value: np.ndarray | None) -> None:
        self.coupled.increment_start = value

    @property
    def residual_norms(self) -> list[float]:
        """Combined residual norms of the last solve."""
        return self.coupled.residual_norms

    @property
    def largest_residual(self) -> float:
        """Largest mechanical residual component of the last iterate, all processes."""
        V = self.problem.u.function_space
        owned = V.dofmap.index_map.size_local * V.dofmap.index_map_bs
        local = np.abs(self.coupled.residual()[:owned])
        comm = self.problem.u.function_space.mesh.comm
        return comm.allreduce(float(local.max()) if local.size else 0.0, op=MPI.MAX)

    def begin_step(self) -> None:
        """A step starts."""
        self.coupled.begin_step()

    def solve(self, u: dolfinx.fem.Function) -> tuple[int, bool]:
        """Newton on both fields from the current state. Collective."""
        try:
            return self.coupled.solve(u)
        finally:
            springs = self.problem.total_springs
            self.history = [
                (i + 1, springs, norm, 0.0, 0.0, 0.0)
                for i, norm in enumerate(self.coupled.residual_norms[1:])
            ]

    def destroy(self) -> None:
        """Destroy the PETSc objects. Collective."""
        self.coupled.destroy()
        self.heat.destroy()
