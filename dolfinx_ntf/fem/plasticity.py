"""J2 plasticity at quadrature points: the dolfinx glue of :mod:`dolfinx_ntf.kernels.plasticity`.

docs/method.md §21. :class:`J2Plasticity` evaluates the strain of the displacement at the
quadrature points (a ``dolfinx.fem.Expression``), runs the radial return map on all of them at
once and stores the stress and the algorithmic tangent in quadrature-space Functions (Mandel
6-vectors and 6x6 matrices, :func:`~dolfinx_ntf.compat.quadrature_space`). The residual
``inner(sigma, eps(v)) dx`` and the Jacobian ``inner(C_alg eps(du), eps(v)) dx`` are then UFL forms
like any bulk form of a :class:`~dolfinx_ntf.ContactProblem`, which calls the object's
:meth:`J2Plasticity.evaluate` before every residual and commits its history (plastic strain,
equivalent plastic strain) only when an increment converges (the
:class:`~dolfinx_ntf.contact.problem.MaterialHistory` role). 3D and plane strain (a 2D ``u``: the
out-of-plane strains are zero, the out-of-plane stress is kept in :attr:`J2Plasticity.stress`).
"""

from __future__ import annotations

import numbers
import typing

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat, validation
from dolfinx_ntf.kernels.plasticity import (
    IsotropicHardening,
    elastic_matrix,
    return_map,
    tensor_from_mandel,
)

__all__ = ["J2Plasticity", "mandel_strain", "material_cells"]

_SQRT2 = float(np.sqrt(2.0))

#: A yield stress no trial stress reaches: the return map's elastic branch everywhere.
_NEVER_YIELDS = IsotropicHardening(yield_stress=[1e300], plastic_strain=[0.0])


def mandel_strain(u: ufl.core.expr.Expr) -> ufl.core.expr.Expr:
    """The small strain of ``u`` as a Mandel 6-vector ``[xx, yy, zz, √2 xy, √2 xz, √2 yz]``.

    A 2D ``u`` is plane strain (zero out-of-plane components).

    Args:
        u: A 2D or 3D displacement (or a test or trial function of its space).
    """
    e = ufl.sym(ufl.grad(u))
    if ufl.shape(u) == (3,):
        return ufl.as_vector(
            [e[0, 0], e[1, 1], e[2, 2], _SQRT2 * e[0, 1], _SQRT2 * e[0, 2], _SQRT2 * e[1, 2]]
        )
    if ufl.shape(u) == (2,):
        return ufl.as_vector([e[0, 0], e[1, 1], 0.0, _SQRT2 * e[0, 1], 0.0, 0.0])
    raise ValueError(f"mandel_strain: a 2D or 3D displacement is needed, got shape {ufl.shape(u)}")


def material_cells(
    mesh: dolfinx.mesh.Mesh,
    degree: int,
    cell_tags: compat.MeshTags | None,
    tag: int,
    owner: str,
) -> tuple[np.ndarray, ufl.Measure]:
    """The local cells (ghosts included) of a material and its measure with the default rule.

    Every cell without ``cell_tags``, else the cells tagged ``tag`` and ``dx(tag)`` over those
    tags (so that other materials' forms can use the same ``subdomain_data``).

    Args:
        mesh: The mesh.
        degree: The quadrature degree of the measure.
        cell_tags: Cell tags of ``mesh``, or None.
        tag: The material's value in ``cell_tags``.
        owner: Name for error messages.
    """
    tdim = mesh.topology.dim
    metadata = {"quadrature_degree": degree, "quadrature_scheme": "default"}
    if cell_tags is None:
        cell_map = mesh.topology.index_map(tdim)
        cells = np.arange(cell_map.size_local + cell_map.num_ghosts, dtype=np.int32)
        return cells, ufl.dx(domain=mesh, metadata=metadata)
    if cell_tags.dim != tdim or not compat.tags_on_mesh(cell_tags, mesh):
        raise ValueError(f"{owner}: cell_tags must be cell tags of u's mesh")
    cells = np.asarray(cell_tags.indices[cell_tags.values == tag], dtype=np.int32)
    measure = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags, metadata=metadata)
    return cells, measure(int(tag))


def _cell_rows(
    law_cells: np.ndarray, values: np.ndarray, cells: np.ndarray, owner: str
) -> np.ndarray:
    """The rows ``(n, q, ...)`` of ``cells`` in per-point ``values``.

    ``values`` hold q points per cell of ``law_cells``, in that order.
    """
    cells = np.asarray(cells, dtype=np.int64).reshape(-1)
    q = values.shape[0] // max(law_cells.size, 1)
    pos = np.searchsorted(law_cells, cells)
    inside = pos < law_cells.size
    inside[inside] = law_cells[pos[inside]] == cells[inside]
    if not np.all(inside):
        raise ValueError(f"{owner}: cell {int(cells[~inside][0])} is not one of the law's cells")
    per_cell = values.reshape(law_cells.size, q, *values.shape[1:])
    return per_cell[pos]


class QuadratureLaw:
    """What the plasticity laws share: their arguments, cells and measure, and the trial state.

    A subclass sets ``self._trial`` (a return map's result with a ``plastic`` mask) in
    ``evaluate()``; the history it commits is its own.
    """

    _cells: np.ndarray
    _trial: typing.Any

    def _set_up(
        self,
        owner: str,
        u: dolfinx.fem.Function,
        youngs_modulus: float,
        poisson_ratio: float,
        hardening: IsotropicHardening,
        quadrature_degree: int | None,
        cell_tags: compat.MeshTags | None,
        tag: int,
    ) -> None:
        """Check the arguments, store them and pick the law's cells and measure."""
        validation.check_type(u, dolfinx.fem.Function, f"{owner}: u")
        validation.check_type(hardening, IsotropicHardening, f"{owner}: hardening")
        elastic_matrix(youngs_modulus, poisson_ratio)  # checks E and nu
        degree = 2 * compat.space_degree(u.function_space)
        if quadrature_degree is not None:
            if (
                isinstance(quadrature_degree, bool)
                or not isinstance(quadrature_degree, numbers.Integral)
                or quadrature_degree < 0
            ):
                raise ValueError(
                    f"{owner}: quadrature_degree must be an integer >= 0, got {quadrature_degree!r}"
                )
            degree = int(quadrature_degree)
        self.u = u
        self.youngs_modulus = float(youngs_modulus)
        self.poisson_ratio = float(poisson_ratio)
        self.hardening = hardening
        self.quadrature_degree = degree
        self._cells, self.dx = material_cells(u.function_space.mesh, degree, cell_tags, tag, owner)

    def evaluate(self) -> None:
        """Return-map the current ``u`` from the committed history (the subclass's)."""
        raise NotImplementedError

    def evaluate_elastic(self) -> None:
        """Evaluate the current ``u`` elastically from the committed history (no return map).

        The elastic trial stress and the elastic tangent: CalculiX's first iteration of a step
        whose prescribed displacements change (docs/method.md §31).
        """
        hardening = self.hardening
        self.hardening = _NEVER_YIELDS
        try:
            self.evaluate()
        finally:
            self.hardening = hardening

    def increment_rejected(self) -> None:
        """Drop the trial history: the stress goes back to the committed state at ``u``."""
        self.evaluate()

    @property
    def yielding(self) -> np.ndarray:
        """Whether each local quadrature point yielded at the last evaluation, (n,) bool."""
        return self._trial.plastic.copy()

    @property
    def cells(self) -> np.ndarray:
        """The law's local cells (owned and ghost), ascending."""
        return self._cells.copy()


class J2Plasticity(QuadratureLaw):
    """Small-strain J2 plasticity with isotropic hardening at the quadrature points of ``u``'s mesh.

    Args:
        u: The displacement (3D, or 2D for plane strain) the strain is taken of.
        youngs_modulus: E > 0.
        poisson_ratio: -1 < nu < 0.5.
        hardening: The yield stress table (CalculiX's ``*PLASTIC``), e.g.
            ``IsotropicHardening.linear(250.0, 1000.0)``.
        quadrature_degree: Degree of the quadrature rule the stresses live at; default
            ``2 * degree(u)`` (2x2x2 Gauss points on hexahedra of degree 1, as CalculiX's C3D8).
        cell_tags: Cell tags of the mesh (local cells, ghosts included) and ``tag``: the
            law covers the cells tagged ``tag`` and its forms integrate over them only; default
            every cell. Forms of other materials on the other cells use the same tags (UFL
            needs one ``subdomain_data`` per form), as a deck's sections do.
        tag: The value of this material's cells in ``cell_tags``.

    Attributes:
        stress: The stress at the last evaluation, Mandel 6-vectors (a quadrature Function).
        tangent: The algorithmic tangent at the last evaluation, 6x6 (a quadrature Function).
        dx: The cell measure of that quadrature rule (use it in every form with :attr:`stress`).
    """

    def __init__(
        self,
        u: dolfinx.fem.Function,
        youngs_modulus: float,
        poisson_ratio: float,
        hardening: IsotropicHardening,
        *,
        quadrature_degree: int | None = None,
        cell_tags: compat.MeshTags | None = None,
        tag: int = 1,
    ) -> None:
        owner = "J2Plasticity"
        if ufl.shape(u) not in ((2,), (3,)):
            raise ValueError(f"{owner}: u must be a 2D or 3D displacement, got {ufl.shape(u)}")
        self._set_up(
            owner, u, youngs_modulus, poisson_ratio, hardening, quadrature_degree, cell_tags, tag
        )
        degree = self.quadrature_degree
        mesh = u.function_space.mesh
        self.stress = dolfinx.fem.Function(compat.quadrature_space(mesh, degree, (6,)))
        self.tangent = dolfinx.fem.Function(compat.quadrature_space(mesh, degree, (6, 6)))
        self.stress.name = "stress"
        points = compat.quadrature_points(mesh, degree)
        self._strain = dolfinx.fem.Expression(mandel_strain(u), points)
        #: Quadrature points of the material's local cells (owned and ghost), in block dofs.
        self._dofs = compat.cell_dofs(self.stress.function_space)[self._cells].reshape(-1)
        n = self._dofs.size
        #: Committed plastic strain, Mandel (n, 6), one row per local quadrature point.
        self.plastic_strain = np.zeros((n, 6))
        #: Committed equivalent plastic strain (CalculiX's PEEQ), (n,).
        self.equivalent_plastic_strain = np.zeros(n)
        self._trial = None
        self.evaluate()

    # -- the forms -----------------------------------------------------------------------------

    def residual(self, v: ufl.Argument) -> ufl.Form:
        """The internal virtual work ``inner(sigma, eps(v)) dx`` at the quadrature points.

        Args:
            v: The test function of ``u``'s space.
        """
        return ufl.inner(self.stress, mandel_strain(v)) * self.dx

    def jacobian(self, du: ufl.Argument, v: ufl.Argument) -> ufl.Form:
        """The consistent Jacobian ``inner(C_alg eps(du), eps(v)) dx`` of :meth:`residual`.

        Pass it as ``J`` to the problem (``ufl.derivative`` cannot see through the stress).

        Args:
            du: The trial function of ``u``'s space.
            v: The test function.
        """
        return ufl.inner(ufl.dot(self.tangent, mandel_strain(du)), mandel_strain(v)) * self.dx

    def stress_tensor(self) -> ufl.core.expr.Expr:
        """The stress as a UFL 3x3 tensor (in-plane 2x2 for a 2D ``u``), e.g. for outputs."""
        s = self.stress
        r = 1.0 / _SQRT2
        if ufl.shape(self.u) == (2,):
            return ufl.as_matrix([[s[0], r * s[3]], [r * s[3], s[1]]])
        return ufl.as_matrix(
            [[s[0], r * s[3], r * s[4]], [r * s[3], s[1], r * s[5]], [r * s[4], r * s[5], s[2]]]
        )

    # -- the history (the MaterialHistory role) -------------------------------------------------

    def strain(self) -> np.ndarray:
        """The total strain of ``u`` at every local quadrature point, Mandel (n, 6)."""
        if self._cells.size == 0:  # a process without cells
            return np.zeros((0, 6))
        values = compat.evaluate_expression(self._strain, self.u.function_space.mesh, self._cells)
        return np.asarray(values).reshape(-1, 6)

    def evaluate(self) -> None:
        """Return-map the current ``u`` from the committed history into the stress and tangent.

        Called at every Newton iterate; the trial history is kept until committed.
        """
        result = return_map(
            self.strain(),
            self.plastic_strain,
            self.equivalent_plastic_strain,
            self.youngs_modulus,
            self.poisson_ratio,
            self.hardening,
        )
        self.stress.x.array.reshape(-1, 6)[self._dofs] = result.stress
        self.tangent.x.array.reshape(-1, 36)[self._dofs] = result.tangent.reshape(-1, 36)
        self._trial = result

    def increment_converged(self) -> None:
        """Commit the history of the last evaluation (the converged increment's)."""
        self.evaluate()  # at the converged u, whatever was evaluated last
        self.plastic_strain = self._trial.plastic_strain.copy()
        self.equivalent_plastic_strain = self._trial.equivalent_plastic_strain.copy()

    def cell_stresses(self, cells: np.ndarray) -> np.ndarray:
        """Stresses ``(n, q, 3, 3)`` of the last evaluation at the rule's points of ``cells``.

        Args:
            cells: Local cells of the law (``ValueError`` for others).
        """
        return _cell_rows(
            self._cells, tensor_from_mandel(self._trial.stress), cells, "J2Plasticity"
        )
