"""The increment solvers of the thermal steps in the deck runner.

``*HEAT TRANSFER`` steps (docs/method.md §20.9): :class:`HeatIncrementSolver`, Newton on the
temperature alone with the springs of the undeformed state. Coupled steps without contact whose
temperature space has constraints (C3D15, §39): :class:`SequentialIncrementSolver`, the heat
Newton then the mechanical one (exact: without springs the coupling is one way).

docs/method.md §20.8. :class:`CoupledIncrementSolver` runs the monolithic Newton of
:class:`~dolfinx_ntf.ThermoMechanicalContact` (both fields, the coupling blocks in the Jacobian)
for :class:`~dolfinx_ntf.StaticStep` and gives the job what it reads from its solver (the rows of
the ``.cvg`` file, the largest residual force). The heat problem is a
:class:`~dolfinx_ntf.ThermalContactProblem` on the job's contact problem with ccx's conductance
pressure (``conductance_pressure="ccx"``, §20.1).
"""

from __future__ import annotations

import typing

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.contact.thermal import ThermalContactProblem
from dolfinx_ntf.solvers.coupled import ThermoMechanicalContact
from dolfinx_ntf.solvers.errors import ContactConvergenceError, ContactDivergenceError

from .model.thermal import ThermalModel

__all__ = [
    "CoupledIncrementSolver",
    "HeatIncrementSolver",
    "MechanicalSolver",
    "SequentialIncrementSolver",
]


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
        self.heat.nodal_loads = thermal.flux  # *CFLUX, *DFLUX (docs/method.md §39)
        self.heat.element_terms += [term for term, _ in thermal.films]  # *FILM on C3D15
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


class HeatIncrementSolver:
    """Newton on the temperature alone per increment (the job's solver role, ``*HEAT TRANSFER``).

    The displacement is never solved for: the springs are those the contact problem pairs at
    the undeformed state (as ccx 2.20's heat transfer step, docs/method.md §20.9), their heat
    flows are :class:`~dolfinx_ntf.ThermalContactProblem`'s with ccx's conductance pressure.
    C3D15's face centres are eliminated (the reduced Jacobian is factorized), ``*CFLUX`` and
    ``*DFLUX`` are the problem's nodal loads and ``*FILM`` its element terms (§39).

    Args:
        problem: The job's contact problem (its displacement stays as it is).
        thermal: The deck's temperature field.
    """

    def __init__(self, problem: ContactProblem, thermal: ThermalModel) -> None:
        #: The heat problem on the springs of ``problem``.
        self.heat = ThermalContactProblem(
            thermal.residual,
            thermal.T,
            problem,
            thermal.conductances,
            thermal.bcs,
            conductance_pressure="ccx",
            constraints=thermal.constraints,  # C3D15's face centres (docs/method.md §39)
        )
        self.heat.nodal_loads = thermal.flux  # *CFLUX, *DFLUX (docs/method.md §39)
        self.heat.element_terms += [term for term, _ in thermal.films]  # *FILM on C3D15
        self.problem = problem
        #: Relative and absolute tolerances of the heat residual's 2-norm.
        self.rtol, self.atol = 1e-10, 1e-12
        #: Raise ``ContactConvergenceError`` after this many iterations.
        self.max_iterations = 30
        #: ccx's field controls and I_P (kept for the job; the test is the Newton's own).
        self.controls: dict[str, float] = {}
        self.relaxation_iteration = 9
        #: Displacement at the start of the increment (set by the step; marks a cutback).
        self.increment_start: np.ndarray | None = None
        self._increment_key: np.ndarray | None = None
        self._T_start = thermal.T.x.array.copy()
        #: Heat residual norms of the last solve.
        self.residual_norms: list[float] = []
        #: Rows of the ``.cvg`` file of the last solve: (iteration, springs, residual norm, 0, 0,
        #: 0).
        self.history: list[tuple[int, int, float, float, float, float]] = []
        self._b = compat.create_vector(self.heat.L)
        self._ksp = PETSc.KSP().create(problem.u.function_space.mesh.comm)
        self._ksp.setOptionsPrefix("ntf_heat_")
        self._ksp.setType("preonly")
        self._ksp.getPC().setType("lu")
        if PETSc.Sys.hasExternalPackage("mumps"):
            self._ksp.getPC().setFactorSolverType("mumps")
        self._ksp.setFromOptions()

    @property
    def largest_residual(self) -> float:
        """Largest heat residual component of the last iterate, all processes."""
        local = np.abs(self._b.array_r)
        comm = self.problem.u.function_space.mesh.comm
        return comm.allreduce(float(local.max()) if local.size else 0.0, op=MPI.MAX)

    def begin_step(self) -> None:
        """A step starts: nothing to reset."""

    def _residual(self, x: PETSc.Vec, *, mechanics: bool) -> float:
        self.heat.form(x, mechanics=mechanics)
        self.heat.F(x, self._b)
        return self._b.norm()

    def solve(self, u: dolfinx.fem.Function) -> tuple[int, bool]:
        """Newton on ``T`` at the current pairing, ``u`` unchanged. Collective.

        A retried attempt of the same increment restarts ``T`` from the increment start.

        Raises:
            ContactConvergenceError: No convergence within :attr:`max_iterations`.
            ContactDivergenceError: A non-finite residual.
        """
        T = self.heat.T
        if self.increment_start is None or self.increment_start is not self._increment_key:
            self._increment_key, self._T_start = self.increment_start, T.x.array.copy()
        else:
            T.x.array[:] = self._T_start
            T.x.scatter_forward()
        x = compat.petsc_vector(T)
        self.residual_norms = [self._residual(x, mechanics=True)]
        iterations = 0
        try:
            while self.residual_norms[-1] > max(self.rtol * self.residual_norms[0], self.atol):
                if not np.isfinite(self.residual_norms[-1]):
                    raise ContactDivergenceError(
                        f"heat transfer: non-finite residual at iteration {iterations}"
                    )
                if iterations == self.max_iterations:
                    raise ContactConvergenceError(
                        f"heat transfer: no convergence in {self.max_iterations} iterations "
                        f"(residual {self.residual_norms[-1]:.3e}, first "
                        f"{self.residual_norms[0]:.3e})"
                    )
                A = self.heat.ensure_matrix()
                self.heat.J(x, A)
                dx = A.createVecLeft()
                reduced = self.heat.reduced_matrix  # with constraints (§13.1)
                self._ksp.setOperators(A if reduced is None else reduced)
                self._ksp.solve(self._b, dx)
                x.array[:] -= dx.array_r
                x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
                dx.destroy()
                iterations += 1
                self.residual_norms.append(self._residual(x, mechanics=False))
        finally:
            springs = self.problem.total_springs
            self.history = [
                (i + 1, springs, norm, 0.0, 0.0, 0.0)
                for i, norm in enumerate(self.residual_norms[1:])
            ]
        return iterations, True

    def destroy(self) -> None:
        """Destroy the PETSc objects. Collective."""
        self._b.destroy()
        self._ksp.destroy()
        self.heat.destroy()


class MechanicalSolver(typing.Protocol):
    """The role of the job's mechanical Newton (:class:`~dolfinx_ntf.ContactNewtonSolver`)."""

    controls: dict[str, float]
    relaxation_iteration: int
    increment_start: np.ndarray | None
    history: list
    residual_norms: list[float]

    @property
    def largest_residual(self) -> float:
        """Largest residual component of the last iterate."""

    def begin_step(self) -> None:
        """A step starts."""

    def solve(self, u: dolfinx.fem.Function) -> tuple[int, bool]:
        """Newton from the current state."""

    def destroy(self) -> None:
        """Free the PETSc objects."""


class SequentialIncrementSolver:
    """The temperature, then the displacement at it, per increment (the job's solver role).

    A coupled step without contact springs is coupled one way: the heat residual does not
    depend on the displacement, so solving the heat problem first and the mechanics at its
    temperature gives the monolithic solution (docs/method.md §39). Used where the monolithic
    Newton cannot run: constraints on the temperature (C3D15's face centres).

    Args:
        heat: The heat Newton (its springs: none).
        mechanics: The mechanical Newton; its residual holds the thermal strain of ``T``.
        thermal: The deck's temperature field (its cell temperatures updated between the two).
    """

    def __init__(
        self, heat: HeatIncrementSolver, mechanics: MechanicalSolver, thermal: ThermalModel
    ) -> None:
        if heat.problem.states:
            raise NotImplementedError(
                "SequentialIncrementSolver: contact springs couple the heat problem to the "
                "displacement; solve it monolithically (CoupledIncrementSolver)"
            )
        self.heat, self.mechanics, self.thermal = heat, mechanics, thermal
        self.problem = heat.problem

    @property
    def controls(self) -> dict[str, float]:
        """ccx's field controls of the mechanical Newton."""
        return self.mechanics.controls

    @controls.setter
    def controls(self, value: dict[str, float]) -> None:
        self.mechanics.controls = value

    @property
    def relaxation_iteration(self) -> int:
        """ccx's I_P of the mechanical Newton."""
        return self.mechanics.relaxation_iteration

    @relaxation_iteration.setter
    def relaxation_iteration(self, value: int) -> None:
        self.mechanics.relaxation_iteration = value

    @property
    def increment_start(self) -> np.ndarray | None:
        """Displacement at the start of the increment (set by the step), for both solvers."""
        return self.mechanics.increment_start

    @increment_start.setter
    def increment_start(self, value: np.ndarray | None) -> None:
        self.heat.increment_start = self.mechanics.increment_start = value

    @property
    def history(self) -> list:
        """The mechanical Newton's ``.cvg`` rows of the last solve."""
        return self.mechanics.history

    @property
    def residual_norms(self) -> list[float]:
        """The mechanical Newton's residual norms of the last solve."""
        return self.mechanics.residual_norms

    @property
    def largest_residual(self) -> float:
        """The mechanical Newton's largest residual force of the last iterate."""
        return self.mechanics.largest_residual

    def begin_step(self) -> None:
        """A step starts."""
        self.heat.begin_step()
        self.mechanics.begin_step()

    def solve(self, u: dolfinx.fem.Function) -> tuple[int, bool]:
        """The heat Newton, then the mechanical one at the new temperature. Collective."""
        self.heat.solve(u)
        self.thermal.cell_temperature.update()
        return self.mechanics.solve(u)

    def destroy(self) -> None:
        """Destroy the PETSc objects. Collective."""
        self.heat.destroy()
        self.mechanics.destroy()
