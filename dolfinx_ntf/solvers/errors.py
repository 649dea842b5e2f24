"""The failures of a solve, by what the step driver can do about them.

:class:`ContactConvergenceError` (and its :class:`ContactDivergenceError`) let the step cut the
increment back; :class:`ContactSolverError` stops at once. The helpers word the messages that
name the cause (a non-finite input, a body with no support).
"""

from __future__ import annotations

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

from dolfinx_ntf import compat
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.solvers import nullspace

__all__ = [
    "ContactConvergenceError",
    "ContactDivergenceError",
    "ContactSolverError",
    "free_rigid_motion",
    "linear_solve_failure",
    "no_support_hint",
    "non_finite_input",
    "non_finite_residual",
    "singular_hint",
    "unsupported_bodies",
]


class ContactConvergenceError(RuntimeError):
    """A Newton solve or a whole step failed to converge; a smaller increment may succeed."""


class ContactDivergenceError(ContactConvergenceError):
    """The Newton iterates diverge (growing or non-finite residual, failed linear solve)."""


class ContactSolverError(RuntimeError):
    """A failure that no smaller increment can fix; :class:`StaticStep` raises it at once.

    Non-finite input, or a linear solver that cannot factor the first Jacobian.
    """


def non_finite_input(problem: ContactProblem) -> str:
    """Message for a residual that is not finite before any Newton update."""
    values = problem.u.x.array
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        node = bad[0] // problem.u.function_space.dofmap.index_map_bs  # 3, or 2 on a 2D mesh
        position = problem.reference_coordinates[node]
        return (
            f"the displacement has {bad.size} non-finite value(s) at the start of the increment "
            f"(first at node {node}, reference position ({position[0]:.6g}, {position[1]:.6g}, "
            f"{position[2]:.6g})): check the initial values and prescribed displacements"
        )
    for number, bc in enumerate(problem.bcs):
        prescribed = _prescribed_values(bc)
        if not np.isfinite(prescribed).all():
            bad = int(np.count_nonzero(~np.isfinite(prescribed)))
            return (
                f"Dirichlet condition {number} (of {len(problem.bcs)}) prescribes {bad} "
                "non-finite value(s): check the values it was made with and what set_load "
                "writes into them"
            )
    return (
        "the residual is not finite at the start of the increment although the displacement and "
        "the prescribed values are: check the loads, constants and material parameters of the "
        "residual form"
    )


def _prescribed_values(bc: object) -> np.ndarray:
    """The values a Dirichlet condition prescribes (its Function's or Constant's)."""
    values = compat.boundary_values(bc)
    if hasattr(values, "x"):
        return np.asarray(values.x.array)
    return np.asarray(getattr(values, "value", values), dtype=float)


def non_finite_residual(
    norm: float, updates: int, problem: ContactProblem
) -> ContactSolverError | ContactDivergenceError:
    """The error of a residual that is not finite: the input's fault before any update."""
    if updates == 0:
        return ContactSolverError(non_finite_input(problem))
    return ContactDivergenceError(
        f"residual is not finite (norm {norm}) after {updates} Newton updates"
    )


def no_support_hint(problem: ContactProblem) -> str:
    """Why a body may float: contact pairs but no springs."""
    if problem.total_springs == 0 and problem.states:
        return (
            "; there are no contact springs, so a body held only by contact has no support "
            "(close the initial gap, or start with a prescribed displacement)"
        )
    return ""


def _unheld_bodies(problem: ContactProblem) -> tuple[int, np.ndarray, np.ndarray]:
    """The bodies, and those with no Dirichlet condition and no contact spring. Collective.

    Returns the number of bodies, the body of each local node of ``u``'s space and the unheld
    bodies' numbers (the same on every process).
    """
    V = problem.u.function_space
    num_bodies, body = nullspace.body_numbers(V)
    held = np.zeros(num_bodies, dtype=np.int64)
    for bc in problem.bcs:
        dofs = np.asarray(bc.dof_indices()[0])
        held[body[dofs // V.dofmap.index_map_bs]] = 1
    for state in problem.states:
        nodes = state.element_nodes.ravel()
        held[body[nodes[nodes < body.size]]] = 1
    V.mesh.comm.Allreduce(MPI.IN_PLACE, held, op=MPI.MAX)
    return num_bodies, body, np.flatnonzero(held == 0)


def unsupported_bodies(problem: ContactProblem) -> list[str]:
    """The bodies that nothing holds: no Dirichlet condition, no contact spring. Collective.

    A body is a connected component of the mesh. With linear constraints (which may hold a body
    through another) none is named. Returns one description per body (its node count and
    centroid), the same on every process.
    """
    if problem.constraints:
        return []
    num_bodies, body, unheld = _unheld_bodies(problem)
    return _describe_bodies(problem, num_bodies, body, unheld)


def _describe_bodies(
    problem: ContactProblem, num_bodies: int, body: np.ndarray, which: np.ndarray
) -> list[str]:
    """``body B of N (n nodes, centroid (x, y, z))`` for each body in ``which``. Collective."""
    V = problem.u.function_space
    owned = V.dofmap.index_map.size_local
    points = V.tabulate_dof_coordinates()[:owned]
    sums = np.zeros((num_bodies, 4))
    for k in range(3):
        sums[:, k] = np.bincount(body[:owned], weights=points[:, k], minlength=num_bodies)
    sums[:, 3] = np.bincount(body[:owned], minlength=num_bodies)
    sums = V.mesh.comm.allreduce(sums, op=MPI.SUM)
    described = []
    for b in which:
        centre = sums[b, :3] / max(sums[b, 3], 1.0)
        described.append(
            f"body {b + 1} of {num_bodies} ({int(sums[b, 3])} nodes, centroid "
            f"({centre[0]:.4g}, {centre[1]:.4g}, {centre[2]:.4g}))"
        )
    return described


#: A rigid-body mode ``z`` of a body is free when ``|A z| <= FREE_MOTION |A|_inf |z|``: round-off
#: of a singular Jacobian (a regular one leaves at least its smallest stiffness).
FREE_MOTION = 1e-10


def free_rigid_motion(problem: ContactProblem, A: PETSc.Mat) -> str | None:
    """Why ``A`` is singular, if a body that nothing holds moves rigidly at no force. Collective.

    The candidates are the bodies with no Dirichlet condition and no contact spring; a candidate
    is free when one of its rigid-body modes (translations, rotations about its centroid) is a
    null vector of ``A``. Other terms of the residual form (an elastic foundation, inertia) hold a
    body too: then no mode is null and nothing is reported. This finds a singular system that
    a zero right-hand side hides from the solve's residual. Returns the message, or None
    (:func:`linear_solve_failure` adds the bodies' names).
    """
    if problem.constraints:
        return None
    num_bodies, body, unheld = _unheld_bodies(problem)
    if unheld.size == 0:
        return None
    V = problem.u.function_space
    comm = V.mesh.comm
    owned = V.dofmap.index_map.size_local
    points = V.tabulate_dof_coordinates()[:owned]
    modes = nullspace.rigid_body_modes(points, body[:owned], num_bodies, comm)
    modes = modes.reshape(modes.shape[0], num_bodies, -1)[:, unheld].reshape(modes.shape[0], -1)
    scale = A.norm(PETSc.NormType.NORM_INFINITY)
    z, Az = A.createVecs()
    forces = []
    for mode in modes.T:
        z.array[:] = mode
        A.mult(z, Az)
        forces.append(Az.norm() / z.norm())
    z.destroy()
    Az.destroy()
    if min(forces) > FREE_MOTION * scale:
        return None
    return (
        "the Jacobian is singular (a body can move as a rigid body at no force; with a zero "
        "load the solve would return u = 0, one of infinitely many solutions)"
    )


def singular_hint(problem: ContactProblem) -> str:
    """Which bodies make a Jacobian singular, or the usual causes. Collective."""
    bodies = unsupported_bodies(problem)
    if bodies:
        return (
            f"; {', '.join(bodies)} has no Dirichlet condition and no contact spring: give it a "
            "Dirichlet condition, or close its gap to a held body so that springs hold it"
        )
    return no_support_hint(problem) or (
        "; a body may be held in too few directions (rigid-body motion left free by the Dirichlet "
        "conditions and the contact springs)"
    )


def linear_solve_failure(
    what: str, at_start: bool, updates: int, prefix: str, problem: ContactProblem
) -> ContactSolverError | ContactDivergenceError:
    """The error of a failed linear solve (or Newton iteration) after ``updates`` updates.

    Non-retryable (:class:`ContactSolverError`) ``at_start``, the very first Newton iteration of
    a solver, whose cause is the setup (options under ``prefix``, the residual form); a
    divergence later. A singular Jacobian's message names the bodies nothing holds.
    Collective.
    """
    if "singular" in what:
        hint = singular_hint(problem)
        if at_start:
            return ContactSolverError(f"{what} at the first Newton iteration{hint}")
        return ContactDivergenceError(f"{what} at Newton iteration {updates + 1}{hint}")
    if at_start:
        hint = (
            f"check the PETSc options under the prefix '{prefix}' (petsc_options) and that "
            "the residual form is built on the unknown Function u"
        )
        return ContactSolverError(
            f"{what} at the first Newton iteration: {hint}{no_support_hint(problem)}"
        )
    return ContactDivergenceError(
        f"{what} at Newton iteration {updates + 1}{no_support_hint(problem)}"
    )
