"""The monolithic temperature-displacement contact problem: :class:`ThermoMechanicalContact`.

docs/method.md §20.5. One Newton on both fields: the residual ``[F_u(u, T); F_T(T, u)]`` with the
Jacobian of four blocks ``[[∂F_u/∂u, ∂F_u/∂T], [∂F_T/∂u, ∂F_T/∂T]]``:

- ∂F_u/∂u: the ContactProblem's (bulk and mechanical springs);
- ∂F_u/∂T: the thermal expansion (UFL);
- ∂F_T/∂T: the ThermalContactProblem's (bulk and the springs' heat flows);
- ∂F_T/∂u: the springs' heat flows by the displacement (projection points and pressures,
  kernels/gap_conductance).

The diagonal blocks are the two problems' own matrices (the contact assembler grows their
patterns); the off-diagonal ones are made per iteration (dolfinx's form,
:func:`~dolfinx_ntf.contact.assembly.coupling_matrix`). The four are joined in a PETSc nest
converted to one AIJ matrix (each process's rows: its displacement dofs, then its temperature
dofs) and solved by LU.
"""

from __future__ import annotations

import logging

from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

from dolfinx_ntf import compat, validation
from dolfinx_ntf.contact.assembly import coupling_matrix
from dolfinx_ntf.contact.thermal import ThermalContactProblem
from dolfinx_ntf.fem.thermal import CellTemperature
from dolfinx_ntf.solvers.errors import ContactConvergenceError, ContactDivergenceError

__all__ = ["ThermoMechanicalContact"]

logger = logging.getLogger("dolfinx_ntf")


class ThermoMechanicalContact:
    """Monolithic Newton for a contact problem and its thermal problem (one Newton, both fields).

    Args:
        F: The mechanical UFL residual of ``thermal.contact`` (the one it was made from), whose
            dependence on ``thermal.T`` (thermal expansion) gives the block ∂F_u/∂T.
        thermal: The heat problem on the contact problem's springs; its residual must not depend on
            the displacement except through the springs.
        cell_temperature: When given, ``F`` holds the thermal strain of the cell mean temperatures
            ``cell_temperature.T_c`` (CalculiX's C3D8) instead of ``T``; they are updated before
            each evaluation and the coupling block is ``∂F_u/∂T_c P``.
        form_compiler_options, jit_options: Passed to dolfinx's form compiler and JIT.
    """

    def __init__(
        self,
        F: ufl.form.Form,
        thermal: ThermalContactProblem,
        *,
        cell_temperature: CellTemperature | None = None,
        form_compiler_options: dict | None = None,
        jit_options: dict | None = None,
    ) -> None:
        owner = "ThermoMechanicalContact"
        validation.check_type(thermal, ThermalContactProblem, f"{owner}: thermal")
        self.thermal = thermal
        self.contact = thermal.contact
        u, T = self.contact.u, thermal.T
        validation.check_residual(F, u, owner)
        if cell_temperature is not None:
            validation.check_type(cell_temperature, CellTemperature, f"{owner}: cell_temperature")
            if cell_temperature.T is not T:
                raise ValueError(f"{owner}: cell_temperature is not made from thermal.T")
            T = cell_temperature.T_c
        #: The cell mean temperatures of the thermal strain, or None (``F`` holds ``T``).
        self.cell_temperature = cell_temperature
        if T not in F.coefficients():
            raise ValueError(
                f"{owner}: F does not depend on the temperature T: give the mechanical residual "
                "with the thermal strain (e.g. thermoelastic_stress(u, T, ...))"
            )
        if u in thermal.residual_form.coefficients():
            raise NotImplementedError(
                f"{owner}: the heat residual depends on the displacement; only the springs may "
                "couple it to u for now"
            )
        if self.contact.constraints or thermal.elimination is not None:
            raise NotImplementedError(f"{owner}: linear constraints are not supported yet")
        options = compat.jit_keywords(form_compiler_options, jit_options)
        Q = T.function_space  # T_c's with cell_temperature
        coupling = ufl.algorithms.expand_derivatives(ufl.derivative(F, T, ufl.TrialFunction(Q)))
        self._a_uT = None if coupling.empty() else dolfinx.fem.form(coupling, **options)
        self._b_u = compat.create_vector(self.contact.L)
        self._b_T = compat.create_vector(thermal.L)
        self._A_uT = None if self._a_uT is None else dolfinx.fem.petsc.create_matrix(self._a_uT)
        self._ksp = PETSc.KSP().create(u.function_space.mesh.comm)
        self._ksp.setOptionsPrefix("ntf_coupled_")
        self._ksp.setType("preonly")
        self._ksp.getPC().setType("lu")
        if PETSc.Sys.hasExternalPackage("mumps"):
            self._ksp.getPC().setFactorSolverType("mumps")
        self._ksp.setFromOptions()
        #: The contact problem (the step's solver role names it ``problem``).
        self.problem = self.contact
        #: Relative tolerance of the combined residual's 2-norm.
        self.rtol = 1e-10
        #: Absolute tolerance of the combined residual's 2-norm.
        self.atol = 1e-12
        #: Raise ``ContactConvergenceError`` after this many iterations.
        self.max_iterations = 30
        #: Whether the Jacobian has the coupling blocks ∂F_u/∂T and ∂F_T/∂u (True, Newton's
        #: method). False leaves them out as CalculiX 2.20 does (its manual on ``*COUPLED
        #: TEMPERATURE-DISPLACEMENT`` couples the fields by updating each after every
        #: iteration): the same solution, reached by ccx's iterates (the pairings of its
        #: iterations follow them), at a linear rate.
        self.coupling_blocks = True
        #: Displacement at the start of the increment (set by a step before each attempt).
        self.increment_start: np.ndarray | None = None
        self._increment_key: np.ndarray | None = None
        self._T_start = thermal.T.x.array.copy()
        self._bc_mask = compat.create_vector(thermal.L)  # 0 at prescribed temperatures, else 1
        self._bc_mask.set(1.0)
        dolfinx.fem.petsc.set_bc(self._bc_mask, thermal.bcs, None, 0.0)
        #: Newton iterations of the last :meth:`solve`.
        self.iterations = 0
        #: Norms of the combined residual at each iterate of the last :meth:`solve`.
        self.residual_norms: list[float] = []

    # -- residual and Jacobian ---------------------------------------------------------------------

    def evaluate(self) -> None:
        """Evaluate both fields' springs and residuals at the current ``u`` and ``T``."""
        x_u = compat.petsc_vector(self.contact.u)
        if self.cell_temperature is not None:
            self.cell_temperature.update()
        self.contact.form(x_u)
        self.contact.F(x_u, self._b_u)
        self._thermal_residual()

    def _thermal_residual(self) -> None:
        x_T = compat.petsc_vector(self.thermal.T)
        self.thermal.form(x_T, coupling=True, mechanics=False)
        self.thermal.F(x_T, self._b_T)

    def residual(self) -> np.ndarray:
        """The owned entries of the combined residual ``[F_u; F_T]`` of the last evaluation."""
        return np.concatenate([self._b_u.array_r, self._b_T.array_r])

    def jacobian(self) -> PETSc.Mat:
        """The combined Jacobian at the last evaluation, as one AIJ matrix (new). Collective.

        Each process's rows are its displacement dofs, then its temperature dofs, in the order of
        :meth:`residual`.
        """
        x_u, x_T = compat.petsc_vector(self.contact.u), compat.petsc_vector(self.thermal.T)
        A_uu = self.contact.ensure_matrix()
        self.contact.assemble_jacobian(x_u, A_uu)
        A_TT = self.thermal.ensure_matrix()
        self.thermal.J(x_T, A_TT)
        A_Tu, A_uT = None, None
        if self.coupling_blocks:
            A_Tu = coupling_matrix(
                self.thermal.assembler, self.contact.assembler, self.thermal.coupling_blocks
            )
            A_uT = self._A_uT
        if A_uT is not None:
            A_uT.zeroEntries()
            dolfinx.fem.petsc.assemble_matrix(
                A_uT, self._a_uT, list(self.contact.bcs) + list(self.thermal.bcs)
            )
            A_uT.assemble()
            if self.cell_temperature is not None:  # dF_u/dT = dF_u/dT_c P, prescribed T left out
                A_uT = A_uT.matMult(self.cell_temperature.P)
                A_uT.diagonalScale(None, self._bc_mask)
        nest = PETSc.Mat().createNest([[A_uu, A_uT], [A_Tu, A_TT]], comm=A_uu.getComm())
        A = nest.convert("aij", PETSc.Mat())  # a new matrix (without ``out``: in place)
        nest.destroy()
        if A_Tu is not None:
            A_Tu.destroy()
        if A_uT is not None and A_uT is not self._A_uT:
            A_uT.destroy()
        return A

    # -- Newton --------------------------------------------------------------------------------

    def begin_step(self) -> None:
        """A new step starts (the StaticStep solver role): nothing to reset."""

    def solve(self, u: dolfinx.fem.Function | None = None) -> tuple[int, bool]:
        """Newton on both fields from the current ``u`` and ``T`` at the current pairing.

        The increment solver of a :class:`~dolfinx_ntf.StaticStep` (which pairs at the increment
        start and commits at its end); :meth:`solve_increment` does one increment alone.
        Converged when the combined residual's 2-norm is below :attr:`rtol` times the first one
        or below :attr:`atol`. A retried attempt of the same increment (cutback) restarts ``T``
        from the increment start, as the step restarts ``u``. Collective.

        Args:
            u: The contact problem's displacement (the step passes it; default that one).

        Returns:
            ``(iterations, True)``.

        Raises:
            ContactConvergenceError: No convergence within :attr:`max_iterations`.
            ContactDivergenceError: A non-finite residual.
        """
        contact = self.contact
        if u is not None and u is not contact.u:
            raise ValueError("ThermoMechanicalContact.solve: u is not the contact problem's")
        T = self.thermal.T
        if self.increment_start is None or self.increment_start is not self._increment_key:
            self._increment_key, self._T_start = self.increment_start, T.x.array.copy()
        else:  # a cutback: the step restored u, we restore T
            T.x.array[:] = self._T_start
            T.x.scatter_forward()
        x_u, x_T = compat.petsc_vector(contact.u), compat.petsc_vector(T)
        self.evaluate()
        self.residual_norms = [self._norm()]
        self.iterations = 0
        while self.residual_norms[-1] > max(self.rtol * self.residual_norms[0], self.atol):
            if not np.isfinite(self.residual_norms[-1]):
                raise ContactDivergenceError(
                    f"ThermoMechanicalContact: non-finite residual at iteration {self.iterations}"
                )
            if self.iterations == self.max_iterations:
                raise ContactConvergenceError(
                    f"ThermoMechanicalContact: no convergence in {self.max_iterations} "
                    f"iterations (residual {self.residual_norms[-1]:.3e}, first "
                    f"{self.residual_norms[0]:.3e})"
                )
            pairings = contact.pairings
            contact.start_iteration(x_u)  # re-pairs on schedule (and re-assembles F_u)
            if contact.pairings != pairings:
                self._thermal_residual()
            A = self.jacobian()
            b, dx = A.createVecs()
            b.array[:] = self.residual()
            self._ksp.setOperators(A)
            self._ksp.solve(b, dx)
            n_u = self._b_u.getLocalSize()
            for x, part in ((x_u, dx.array_r[:n_u]), (x_T, dx.array_r[n_u:])):
                x.array[:] -= part
                x.ghostUpdate(addv=PETSc.InsertMode.INSERT, mode=PETSc.ScatterMode.FORWARD)
            for obj in (A, b, dx):
                obj.destroy()
            self.iterations += 1
            self.evaluate()
            self.residual_norms.append(self._norm())
            logger.info(
                "coupled Newton iteration %d: residual %.3e",
                self.iterations,
                self.residual_norms[-1],
            )
        return self.iterations, True

    def solve_increment(self) -> int:
        """One increment alone: pair at the current state, :meth:`solve`, commit. Collective.

        Returns:
            The Newton iterations.
        """
        self.contact.begin_increment(1.0)
        self.increment_start = None
        iterations, _ = self.solve()
        self.contact.end_increment()
        return iterations

    def _norm(self) -> float:
        """The 2-norm of the combined residual over all processes."""
        return float(np.hypot(self._b_u.norm(), self._b_T.norm()))

    def destroy(self) -> None:
        """Destroy the PETSc objects this object created. Collective."""
        for obj in (self._b_u, self._b_T, self._A_uT, self._ksp, self._bc_mask):
            if obj is not None:
                obj.destroy()
