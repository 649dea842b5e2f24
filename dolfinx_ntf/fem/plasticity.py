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
from dolfinx_ntf.kernels.strain_energy import trapezoidal_energy

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
    metadata: dict | None = None,
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
        metadata: The measure's metadata instead of the default rule of ``degree`` (e.g. a
            custom rule).
    """
    tdim = mesh.topology.dim
    if metadata is None:
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
    #: Committed equivalent plastic strain (CalculiX's PEEQ), one per local point, (n,).
    equivalent_plastic_strain: np.ndarray
    #: Committed strain energy density (CalculiX's ENER) of every local point, shape (n,), the
    #: stress power integrated over the converged increments by the trapezoidal rule
    #: (docs/method.md §36), from 0 at the law's creation.
    strain_energy_density: np.ndarray
    _committed_pair: tuple[np.ndarray, np.ndarray]

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
        quadrature_rule: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> None:
        """Check the arguments, store them and pick the law's cells, measure and points."""
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
        mesh = u.function_space.mesh
        metadata = None
        if quadrature_rule is None:
            self._points = compat.quadrature_points(mesh, degree)
        else:
            points, weights = (np.asarray(a, dtype=float) for a in quadrature_rule)
            tdim = mesh.topology.dim
            if points.ndim != 2 or points.shape[1] != tdim or weights.shape != points.shape[:1]:
                raise ValueError(
                    f"{owner}: quadrature_rule must be (points (q, {tdim}), weights (q,)), got "
                    f"shapes {points.shape} and {weights.shape}"
                )
            if compat.geometry_dofs(mesh).shape[1] != 2**tdim or points.shape[0] > 2**tdim:
                raise ValueError(
                    f"{owner}: a custom quadrature_rule needs a mesh of linear quadrilaterals or "
                    f"hexahedra and at most {2**tdim} points"
                )
            self._points = points
            metadata = {
                "quadrature_rule": "custom",
                "quadrature_degree": degree,
                "quadrature_points": tuple(map(tuple, points.tolist())),
                "quadrature_weights": tuple(weights.tolist()),
            }
        self._custom = quadrature_rule is not None
        self._cells, self.dx = material_cells(mesh, degree, cell_tags, tag, owner, metadata)
        #: Points per cell and in all (the rows of the history arrays).
        self._points_per_cell = self._points.shape[0]
        self._num_points = self._cells.size * self._points_per_cell
        self._carrier: np.ndarray | None = None

    def _space(self, shape: tuple[int, ...]) -> dolfinx.fem.FunctionSpace:
        """The space of per-point values of ``shape``.

        The quadrature space of the default rule, or with a custom rule a DG1 space that
        reproduces the values at its points.
        """
        mesh = self.u.function_space.mesh
        if self._custom:
            return compat.discontinuous_space(mesh, 1, shape)
        return compat.quadrature_space(mesh, self.quadrature_degree, shape)

    def _store(self, function: dolfinx.fem.Function, values: np.ndarray) -> None:
        """Write per-point ``values`` (one row per point of the law's cells) into ``function``.

        With a custom rule the DG1 coefficients of each cell are the least-norm ones whose
        values at the rule's points are ``values`` (exact: fewer points than coefficients).
        """
        size = int(np.prod(function.ufl_shape)) if function.ufl_shape else 1
        values = np.asarray(values).reshape(self._num_points, size)
        dofs = compat.cell_dofs(function.function_space)[self._cells]
        if not self._custom:
            function.x.array.reshape(-1, size)[dofs.reshape(-1)] = values
            return
        if self._carrier is None:
            self._carrier = np.linalg.pinv(self._tabulate_carrier())  # (8, q)
        per_cell = values.reshape(self._cells.size, self._points_per_cell, size)
        coefficients = np.einsum("bq,cqk->cbk", self._carrier, per_cell)
        function.x.array.reshape(-1, size)[dofs.reshape(-1)] = coefficients.reshape(-1, size)

    def _tabulate_carrier(self) -> np.ndarray:
        """``(q, 8)`` values of the scalar DG1 basis (in dof order) at the rule's points."""
        mesh = self.u.function_space.mesh
        scalar = dolfinx.fem.Function(compat.discontinuous_space(mesh, 1))
        expression = dolfinx.fem.Expression(scalar, self._points)
        if self._cells.size == 0:
            return np.zeros((self._points_per_cell, 2**mesh.topology.dim))
        cell = self._cells[:1]
        dofs = compat.cell_dofs(scalar.function_space)[cell[0]]
        table = np.empty((self._points_per_cell, dofs.size))
        for k, dof in enumerate(dofs):
            scalar.x.array[:] = 0.0
            scalar.x.array[dof] = 1.0
            table[:, k] = np.asarray(compat.evaluate_expression(expression, mesh, cell)).ravel()
        return table

    def evaluate(self) -> None:
        """Return-map the current ``u`` from the committed history (the subclass's)."""
        raise NotImplementedError

    def _work_pair(self) -> tuple[np.ndarray, np.ndarray]:
        """Work-conjugate stress and strain ``(n, 3, 3)`` of the last evaluation (subclass's)."""
        raise NotImplementedError

    def _start_energy(self) -> None:
        """Energy 0 at the state of the first evaluation (the law's creation)."""
        self.strain_energy_density = np.zeros(self._num_points)
        self._committed_pair = self._work_pair()

    def _commit_energy(self) -> None:
        """Add the converged increment's work (trapezoidal rule) to the energy density."""
        pair = self._work_pair()
        self.strain_energy_density = trapezoidal_energy(
            self.strain_energy_density, self._committed_pair[0], pair[0], self._committed_pair[1],
            pair[1],
        )  # fmt: skip
        self._committed_pair = pair

    def evaluate_elastic(self) -> None:
        """Evaluate the current ``u`` elastically from the committed history (no return map).

        The elastic trial stress and the elastic tangent: CalculiX's first iteration of a step
        whose prescribed displacements change (docs/method.md §33).
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

    def cell_equivalent_plastic_strains(self, cells: np.ndarray) -> np.ndarray:
        """Committed equivalent plastic strains ``(n, q)`` (CalculiX's PEEQ) of ``cells``.

        The values of the last converged increment at the rule's points, as ccx prints them.

        Args:
            cells: Local cells of the law (``ValueError`` for others).
        """
        owner = type(self).__name__
        return _cell_rows(self._cells, self.equivalent_plastic_strain, cells, owner)

    def cell_strain_energy_densities(self, cells: np.ndarray) -> np.ndarray:
        """Committed strain energy densities ``(n, q)`` (CalculiX's ENER) of ``cells``.

        Args:
            cells: Local cells of the law (``ValueError`` for others).
        """
        owner = type(self).__name__
        return _cell_rows(self._cells, self.strain_energy_density, cells, owner)

    def state_variables(self) -> np.ndarray:
        """Committed internal variables of every local point, ``(n, 7)`` (the subclass's)."""
        raise NotImplementedError

    def cell_state_variables(self, cells: np.ndarray) -> np.ndarray:
        """Committed internal variables ``(n, q, 7)`` of ``cells`` (:meth:`state_variables`).

        Args:
            cells: Local cells of the law (``ValueError`` for others).
        """
        owner = type(self).__name__
        return _cell_rows(self._cells, self.state_variables(), cells, owner)


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
        quadrature_rule: Custom ``(points (q, d), weights (q,))`` on the reference cell of a
            mesh of linear quadrilaterals or hexahedra (e.g. CalculiX's two-point C3D6 rule on
            collapsed hexahedra, docs/method.md §30.5), instead of the default rule of
            ``quadrature_degree``; the stress and tangent are then DG1 Functions whose values
            at those points are the points' (FFCx 0.5 has no quadrature element with custom
            points).

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
        quadrature_rule: tuple[np.ndarray, np.ndarray] | None = None,
    ) -> None:
        owner = "J2Plasticity"
        if ufl.shape(u) not in ((2,), (3,)):
            raise ValueError(f"{owner}: u must be a 2D or 3D displacement, got {ufl.shape(u)}")
        self._set_up(
            owner,
            u,
            youngs_modulus,
            poisson_ratio,
            hardening,
            quadrature_degree,
            cell_tags,
            tag,
            quadrature_rule,
        )
        self.stress = dolfinx.fem.Function(self._space((6,)))
        self.tangent = dolfinx.fem.Function(self._space((6, 6)))
        self.stress.name = "stress"
        self._strain = dolfinx.fem.Expression(mandel_strain(u), self._points)
        n = self._num_points
        #: Committed plastic strain, Mandel (n, 6), one row per local quadrature point.
        self.plastic_strain = np.zeros((n, 6))
        #: Committed equivalent plastic strain (CalculiX's PEEQ), (n,).
        self.equivalent_plastic_strain = np.zeros(n)
        self._trial = None
        self._trial_strain = np.zeros((n, 6))
        self.evaluate()
        self._start_energy()

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
        self._trial_strain = self.strain()
        result = return_map(
            self._trial_strain,
            self.plastic_strain,
            self.equivalent_plastic_strain,
            self.youngs_modulus,
            self.poisson_ratio,
            self.hardening,
        )
        self._store(self.stress, result.stress)
        self._store(self.tangent, result.tangent.reshape(-1, 36))
        self._trial = result

    def increment_converged(self) -> None:
        """Commit the history of the last evaluation (the converged increment's)."""
        self.evaluate()  # at the converged u, whatever was evaluated last
        self.plastic_strain = self._trial.plastic_strain.copy()
        self.equivalent_plastic_strain = self._trial.equivalent_plastic_strain.copy()
        self._commit_energy()

    def _work_pair(self) -> tuple[np.ndarray, np.ndarray]:
        """The stress and the small strain of the last evaluation, ``(n, 3, 3)`` each."""
        return tensor_from_mandel(self._trial.stress), tensor_from_mandel(self._trial_strain)

    def state_variables(self) -> np.ndarray:
        """Committed ``[alpha, eps_p xx, yy, zz, xy, xz, yz]`` of every local point, ``(n, 7)``.

        The equivalent plastic strain and the plastic strain tensor (tensor shears): CalculiX's
        first seven internal state variables (``SDV``) of its isotropic ``*PLASTIC`` law
        (measured, docs/method.md §36).
        """
        tensor = tensor_from_mandel(self.plastic_strain)
        rows, cols = (0, 1, 2, 0, 0, 1), (0, 1, 2, 1, 2, 2)
        return np.column_stack([self.equivalent_plastic_strain, tensor[:, rows, cols]])

    def cell_stresses(self, cells: np.ndarray) -> np.ndarray:
        """Stresses ``(n, q, 3, 3)`` of the last evaluation at the rule's points of ``cells``.

        Args:
            cells: Local cells of the law (``ValueError`` for others).
        """
        return _cell_rows(
            self._cells, tensor_from_mandel(self._trial.stress), cells, "J2Plasticity"
        )
