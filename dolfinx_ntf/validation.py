"""Checks of what users pass to dolfinx_ntf, run where their call enters the library.

Each check names the argument, the value and what is expected, so that a wrong use fails at once
with a message that says what to do instead, not later inside a Newton iteration with an
``AttributeError``, an ``IndexError`` or a PETSc error code. The constructors and entry methods
(:class:`~dolfinx_ntf.FacetSurface`, :class:`~dolfinx_ntf.NodeSurface`,
:class:`~dolfinx_ntf.ContactPair`, :class:`~dolfinx_ntf.ContactProblem`,
:class:`~dolfinx_ntf.ContactNewtonSolver`, the steps, :class:`~dolfinx_ntf.ContactWriter`, the
helpers of ``postprocess.py``) check their own arguments with these generic helpers, once; nothing
here runs on every Newton evaluation.

Shared rules:
    - ``TypeError`` for an argument of the wrong kind, ``ValueError`` for a wrong value,
      ``OSError`` (``FileNotFoundError``, ``PermissionError``) for an output path that cannot be
      written, ``UserWarning`` where CalculiX's rule replaces a value.
    - Checks that depend on data distributed over MPI processes are collective: every process
      raises (the same type and message) or none does, so that no process continues alone into the
      next collective call and hangs.
"""

from __future__ import annotations

import numbers
import os
import typing
import warnings
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx.fem
import ufl

from dolfinx_ntf import compat

__all__ = [
    "check_bcs",
    "check_displacement",
    "check_linear_solver",
    "check_petsc_options",
    "check_positive",
    "check_residual",
    "check_sequence",
    "check_type",
    "check_writable",
    "describe",
    "describe_petsc_error",
    "raise_collectively",
    "vertex_indices",
    "warn",
]

#: Continuous Lagrange family names as dolfinx 0.5.2 (tetrahedra: Lagrange, hexahedra: Q) and 0.9
#: (Lagrange) report them.
_LAGRANGE_FAMILIES = ("Lagrange", "P", "Q", "CG")

#: PETSc error codes that users meet through wrong options or a singular system, in words.
_PETSC_ERRORS = {
    56: "no support for this operation (often: a linear solver that cannot factor this matrix)",
    71: "zero pivot in the factorization: the matrix is singular (are all rigid-body motions "
    "constrained, and does the residual depend on u?)",
    73: "object in the wrong state",
    76: "error in an external library (e.g. MUMPS could not factor the matrix: singular system?)",
    86: "unknown type: a solver or preconditioner name that this PETSc does not have",
    92: "no factorization package of that name: check pc_factor_mat_solver_type",
}


def describe(value: object) -> str:
    """Short description of a value for messages: its type and a shortened repr."""
    text = repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{type(value).__name__} {text}"


def check_type(value: object, expected: type | tuple[type, ...], what: str, hint: str = "") -> None:
    """Raise ``TypeError`` naming ``what`` unless ``value`` is an instance of ``expected``.

    Args:
        value: The argument.
        expected: Accepted type(s).
        what: Owner and argument name, e.g. ``"ContactProblem: u"``.
        hint: What to do instead, appended to the message.
    """
    if isinstance(value, expected):
        return
    names = (
        " or ".join(t.__name__ for t in expected)
        if isinstance(expected, tuple)
        else expected.__name__
    )
    raise TypeError(
        f"{what} must be a {names}, got {describe(value)}" + (f"; {hint}" if hint else "")
    )


def check_sequence(values: object, item_type: type, what: str, *, single_hint: str = "") -> list:
    """Return ``values`` as a list after checking it is a sequence of ``item_type``.

    A single ``item_type`` instance where a sequence is expected is a ``TypeError`` that says how
    to wrap it (``single_hint``); so is any item of another type (the message names its index).
    """
    if isinstance(values, item_type):
        raise TypeError(
            f"{what} must be a list of {item_type.__name__}, got a single {item_type.__name__}"
            + (f"; {single_hint}" if single_hint else "")
        )
    if isinstance(values, (str, bytes, dict)) or not isinstance(values, typing.Iterable):
        raise TypeError(f"{what} must be a list of {item_type.__name__}, got {describe(values)}")
    items = list(values)
    for i, item in enumerate(items):
        if not isinstance(item, item_type):
            raise TypeError(f"{what}[{i}] must be a {item_type.__name__}, got {describe(item)}")
    return items


def raise_collectively(comm: MPI.Comm, error: Exception | None) -> None:
    """Raise on every process of ``comm`` if ``error`` is set on any of them. Collective.

    A process re-raises its own exception; the others raise the first reported one (same type and
    message, or a ``RuntimeError`` if that type cannot be rebuilt from its message).
    """
    reports = comm.allgather(None if error is None else (type(error), str(error)))
    first = next((r for r in reports if r is not None), None)
    if first is None:
        return
    if error is not None:
        raise error
    kind, message = first
    try:
        rebuilt = kind(message)
    except Exception:
        rebuilt = RuntimeError(f"{kind.__name__} on another process: {message}")
    raise rebuilt


# -- the displacement, the residual, the boundary conditions ---------------------------------------


def check_displacement(u: object, owner: str) -> None:
    """``u``: a Function on a vector continuous Lagrange space (P1, P2) of a 2D or 3D mesh."""
    expected = "a dolfinx.fem.Function on a vector Lagrange space (P1 or P2) of a 2D or 3D mesh"
    if not isinstance(u, dolfinx.fem.Function):
        raise TypeError(f"{owner}: u must be {expected}, got {describe(u)}")
    V = u.function_space
    mesh = V.mesh
    tdim = mesh.topology.dim
    if tdim not in (2, 3) or mesh.geometry.dim != tdim:
        raise ValueError(
            f"{owner}: u must be {expected}; its mesh is {tdim}D in "
            f"{mesh.geometry.dim}D space (contact needs a 3D mesh, or a 2D mesh in the plane)"
        )
    family, degree = compat.space_family(V), compat.space_degree(V)
    bs = V.dofmap.index_map_bs
    space = f"{family} degree {degree}, block size {bs}"
    if bs != tdim:
        raise ValueError(
            f"{owner}: u must be {expected} (a {tdim}D vector displacement space, block size "
            f"{tdim}), got {space}"
        )
    if family not in _LAGRANGE_FAMILIES:
        raise ValueError(
            f"{owner}: u must be {expected}, got {space}: contact springs sit on nodes shared by "
            "the faces of neighbouring cells, which a discontinuous or non-Lagrange space lacks"
        )
    if degree not in (1, 2):
        raise ValueError(f"{owner}: u must be {expected}, got {space}")


def check_residual(
    F: object, u: dolfinx.fem.Function, owner: str, J: object = None, *, through: bool = False
) -> None:
    """``F`` must be a UFL residual form (one test function) that depends on ``u``.

    With ``through`` it may depend on ``u`` only through coefficients updated from it (a
    material history's stresses); ``J`` is then needed.
    """
    if not isinstance(F, ufl.Form):
        raise TypeError(
            f"{owner}: F must be a UFL form (the residual, e.g. inner(sigma(u), grad(v)) * dx), "
            f"got {describe(F)}"
        )
    arguments = F.arguments()
    if len(arguments) != 1:
        raise ValueError(
            f"{owner}: F must be a residual form, linear in one test function, got a form with "
            f"{len(arguments)} arguments"
        )
    if through and J is None:
        raise ValueError(
            f"{owner}: with a material history (e.g. J2Plasticity) pass J, the consistent "
            "Jacobian (e.g. plasticity.jacobian(du, v)): ufl.derivative cannot see through the "
            "stresses"
        )
    if u not in F.coefficients() and not through:
        raise ValueError(
            f"{owner}: F does not depend on u (its coefficients are "
            f"{[getattr(c, 'name', str(c)) for c in F.coefficients()]}): the Jacobian would be "
            "zero; build F with the Function u that is passed here"
        )
    if J is not None and not isinstance(J, ufl.Form):
        raise TypeError(f"{owner}: J must be a UFL form or None, got {describe(J)}")


def check_bcs(bcs: object, owner: str) -> list:
    """``bcs`` must be a sequence of Dirichlet conditions; returns it as a list."""
    return check_sequence(
        bcs, compat.DirichletBC, f"{owner}: bcs", single_hint="pass [bc] instead of bc"
    )


def check_positive(value: object, what: str, *, allow_none: bool = False) -> None:
    """``value`` must be a finite real number > 0 (or None if allowed)."""
    if value is None and allow_none:
        return
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{what} must be a positive number, got {describe(value)}")
    if not (np.isfinite(value) and value > 0):
        raise ValueError(f"{what} must be a finite number > 0, got {float(value):g}")


# -- surfaces --------------------------------------------------------------------------------------


def vertex_indices(vertices: object, owner: str) -> np.ndarray:
    """Vertex indices as an int32 array; non-integer, negative or missing entries are errors.

    Args:
        vertices: 1-D integer indices (integer-valued floats are accepted).
        owner: Name of the caller for messages.
    """
    array = np.asarray(vertices)
    if array.dtype == bool:
        raise TypeError(
            f"{owner}: vertices must be vertex indices, got a boolean mask; use "
            "np.flatnonzero(mask)"
        )
    if array.ndim != 1:
        raise ValueError(
            f"{owner}: vertices must be a 1-D array of indices, got shape {array.shape}"
        )
    if array.size == 0:  # a process may hold none of a surface's vertices
        return np.empty(0, dtype=np.int32)
    if not np.issubdtype(array.dtype, np.integer):
        try:
            values = array.astype(float)
        except (TypeError, ValueError) as error:
            raise TypeError(
                f"{owner}: vertices must be integer vertex indices, got {describe(vertices)}"
            ) from error
        fractional = np.flatnonzero(~np.isfinite(values) | (values != np.round(values)))
        if fractional.size:
            i = int(fractional[0])
            raise ValueError(
                f"{owner}: vertices must be integer vertex indices, but entry {i} is {values[i]:g} "
                f"({fractional.size} non-integer entries)"
            )
        array = values.astype(np.int64)
    negative = np.flatnonzero(array < 0)
    if negative.size:
        i = int(negative[0])
        raise ValueError(f"{owner}: vertex indices must be >= 0, but entry {i} is {int(array[i])}")
    if array.max() > np.iinfo(np.int32).max:
        i = int(np.argmax(array))
        raise ValueError(f"{owner}: vertex index {int(array[i])} (entry {i}) is too large")
    return array.astype(np.int32)


# -- PETSc -----------------------------------------------------------------------------------------


def check_petsc_options(options: object, owner: str) -> dict[str, typing.Any]:
    """PETSc options as a dict of option names (no leading ``-``) to values."""
    if not isinstance(options, dict):
        raise TypeError(
            f"{owner}: petsc_options must be a dict such as {{'ksp_type': 'preonly', "
            f"'pc_type': 'lu'}}, got {describe(options)}"
        )
    checked = {}
    for key, value in options.items():
        if not isinstance(key, str) or not key.strip("-"):
            raise TypeError(f"{owner}: petsc_options keys must be option names, got {key!r}")
        if value is not None and not isinstance(value, (str, bool, numbers.Real)):
            raise TypeError(
                f"{owner}: petsc_options[{key!r}] must be a string, number, bool or None, got "
                f"{describe(value)}"
            )
        checked[key.lstrip("-")] = value
    return checked


def describe_petsc_error(error: PETSc.Error) -> str:
    """A PETSc error with its code in words."""
    code = getattr(error, "ierr", None)
    meaning = _PETSC_ERRORS.get(code)
    return f"PETSc error {code}" + (f" ({meaning})" if meaning else "")


def _named_type_error(options: dict[str, typing.Any]) -> str | None:
    """The option whose solver name this PETSc does not know, as a message, or None."""
    known = {
        "ksp_type": PETSc.KSP.Type,
        "pc_type": PETSc.PC.Type,
        "pc_factor_mat_solver_type": PETSc.Mat.SolverType,
    }
    for key, names in known.items():
        if key not in options:
            continue
        values = sorted(
            {str(v) for k, v in vars(names).items() if not k.startswith("_") and isinstance(v, str)}
        )
        if str(options[key]) not in values:
            return (
                f"{key} = {options[key]!r} is not a name PETSc knows (known: {', '.join(values)})"
            )
    return None


def check_linear_solver(comm: MPI.Comm, options: dict[str, typing.Any], owner: str) -> None:
    """Configure a throw-away KSP from ``options`` and factor a tiny matrix with it. Collective.

    Unknown solver, preconditioner or factorization package names then fail here with a
    ``ValueError`` naming the option, instead of PETSc error 86 or 92 at the first Newton solve.
    The options are set under a prefix of their own and removed again.
    """
    prefix = "dolfinx_ntf_check_"
    database = PETSc.Options()
    for key, value in options.items():
        database[f"{prefix}{key}"] = value
    ksp = PETSc.KSP().create(comm)
    matrix = None
    try:
        ksp.setOptionsPrefix(prefix)
        ksp.setFromOptions()
        if ksp.getPC().getType() in ("lu", "cholesky", "ilu", "icc"):
            matrix = PETSc.Mat().createAIJ(((1, None), (1, None)), nnz=1, comm=comm)
            row = matrix.getOwnershipRange()[0]
            matrix.setValue(row, row, 1.0)
            matrix.assemble()
            ksp.setOperators(matrix)
            ksp.setUp()
    except PETSc.Error as error:
        named = _named_type_error(options)
        raise ValueError(
            f"{owner}: PETSc cannot set up the linear solver of petsc_options {options}: "
            + (named if named else describe_petsc_error(error))
        ) from None
    finally:
        ksp.destroy()
        if matrix is not None:
            matrix.destroy()
        for key in options:
            database.delValue(f"{prefix}{key}")


# -- files -----------------------------------------------------------------------------------------


def check_writable(path: str | os.PathLike, comm: MPI.Comm, owner: str) -> Path:
    """The output file ``path`` must be creatable (its folder exists and is writable). Collective.

    Returns:
        ``path`` as a Path.
    """
    if not isinstance(path, (str, os.PathLike)):
        raise TypeError(f"{owner}: path must be a str or pathlib.Path, got {describe(path)}")
    path = Path(path)
    error: OSError | None = None
    if comm.rank == 0:
        folder = path.parent
        if not folder.is_dir():
            error = FileNotFoundError(
                f"{owner}: cannot write {str(path)!r}: the folder {str(folder)!r} does not exist"
            )
        else:
            # Try it (permissions, read-only file systems): open for appending, remove if new.
            for target in (path, path.with_suffix(".h5")):
                existed = target.exists()
                try:
                    with open(target, "a"):
                        pass
                    if not existed:
                        target.unlink()
                except OSError as failure:
                    error = type(failure)(
                        f"{owner}: cannot write {str(target)!r}: {failure.strerror or failure}"
                    )
                    break
    raise_collectively(comm, error)
    return path


def warn(message: str) -> None:
    """A ``UserWarning`` pointing at the user's call."""
    warnings.warn(message, UserWarning, stacklevel=3)
