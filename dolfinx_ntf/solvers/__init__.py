"""Solvers and steps: linear-solver choice, Newton, static, dynamic and multi-step runs.

One module per idea: :mod:`~dolfinx_ntf.solvers.linear_solver` (which linear solver, PETSc
options), :mod:`~dolfinx_ntf.solvers.factor_reuse` (Newton corrections with an earlier
factorization), :mod:`~dolfinx_ntf.solvers.convergence` (CalculiX's force-scaled test, the
divergence rule), :mod:`~dolfinx_ntf.solvers.line_search`, :mod:`~dolfinx_ntf.solvers.errors`,
:mod:`~dolfinx_ntf.solvers.newton_loop` (:class:`NewtonSolver`, dolfinx's Newton loop without
``dolfinx.nls``), :mod:`~dolfinx_ntf.solvers.newton` (:class:`ContactNewtonSolver`, which wires
them on that loop), :mod:`~dolfinx_ntf.solvers.snes` (:class:`ContactSNESSolver`, PETSc's SNES as
the driver),
:mod:`~dolfinx_ntf.solvers.steps` (the step base and :class:`StaticStep`),
:mod:`~dolfinx_ntf.solvers.dynamics`, :mod:`~dolfinx_ntf.solvers.modes` (natural frequencies
with contact), :mod:`~dolfinx_ntf.solvers.modal_dynamics` (modal superposition),
:mod:`~dolfinx_ntf.solvers.analysis`,
:mod:`~dolfinx_ntf.solvers.active_set` and :mod:`~dolfinx_ntf.solvers.nullspace`.

The names below are those of the former ``dolfinx_ntf.solver`` module, which still imports (as
this package, with a ``DeprecationWarning``).
"""

from dolfinx_ntf.logs import log_progress
from dolfinx_ntf.solvers.convergence import (
    CCX_FIELD_CONTROLS,
    DIVERGENCE_GROWTH,
    ITERATIONS_PER_EXTRA_PAIRING,
    MAX_EXTRA_PAIRINGS,
    TIGHT_FIELD_CONTROLS,
)
from dolfinx_ntf.solvers.errors import (
    ContactConvergenceError,
    ContactDivergenceError,
    ContactSolverError,
)
from dolfinx_ntf.solvers.linear_solver import (
    CHOLESKY_MAX_DOFS,
    CHOLESKY_PETSC_OPTIONS,
    DEFAULT_PETSC_OPTIONS,
    DIRECT_MAX_DOFS,
    ITERATIVE_PETSC_OPTIONS,
    LINEAR_SOLVERS,
    SEQUENTIAL_PTAP,
    galerkin_products,
)
from dolfinx_ntf.solvers.newton import ContactNewtonSolver
from dolfinx_ntf.solvers.newton_loop import NewtonSolver
from dolfinx_ntf.solvers.snes import ContactSNESSolver
from dolfinx_ntf.solvers.steps import (
    IncrementResult,
    IncrementSolver,
    LoadControl,
    StaticStep,
    Step,
)

__all__ = [
    "CCX_FIELD_CONTROLS",
    "CHOLESKY_MAX_DOFS",
    "CHOLESKY_PETSC_OPTIONS",
    "DEFAULT_PETSC_OPTIONS",
    "DIRECT_MAX_DOFS",
    "DIVERGENCE_GROWTH",
    "ITERATIONS_PER_EXTRA_PAIRING",
    "ITERATIVE_PETSC_OPTIONS",
    "LINEAR_SOLVERS",
    "MAX_EXTRA_PAIRINGS",
    "SEQUENTIAL_PTAP",
    "TIGHT_FIELD_CONTROLS",
    "ContactConvergenceError",
    "ContactDivergenceError",
    "ContactNewtonSolver",
    "ContactSNESSolver",
    "ContactSolverError",
    "IncrementResult",
    "IncrementSolver",
    "LoadControl",
    "NewtonSolver",
    "StaticStep",
    "Step",
    "galerkin_products",
    "log_progress",
]
