"""The values a deck's output requests ask for, in ccx numbering and with their accuracy.

Nodal forces (``RF``), stresses, strains and equivalent plastic strains at ccx's integration points
and extrapolated to the nodes (``S``, ``E``, ``PEEQ``), displacements with the reference nodes of
``*EQUATION`` at their value, and the contact rows of every pair (``CDIS``, ``CSTR``, ``CELS``, the
``.cel`` elements). Each is gathered over the processes in ccx order (``gather.py``), so that it is
the serial run's on any number of processes; the accuracy of each value (``roundoff.py``,
docs/method.md §14.5) decides which digits are printed.
"""

from __future__ import annotations

from dataclasses import dataclass

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.contact.pair import PairState
from dolfinx_ntf.contact.problem import ContactProblem
from dolfinx_ntf.fem.collapsed_wedges import wedge_cells
from dolfinx_ntf.kernels.friction import output_tangents
from dolfinx_ntf.kernels.wedge_rule import NUM_CLASSES, wedge_rule
from dolfinx_ntf.outputs.results import ContactResults, contact_results

from .deck import Deck
from .elements import AXISYMMETRIC_SECTOR, C3D6_EXTRAPOLATION
from .gather import CcxNumbering
from .model import CalculixModel
from .roundoff import (
    FieldAccuracy,
    clean,
    element_sizes,
    force_floor,
    largest_modulus,
    law_accuracy,
)

__all__ = ["ContactRows", "OutputValues", "sector_stresses"]


@dataclass(frozen=True, eq=False)
class ContactRows:
    """Contact elements of one pair at one increment, slave nodes ascending (the ``.dat`` rows).

    Attributes:
        pair: ``SLAVE-MASTER`` surface names.
        nodes: ``(k,)`` ccx slave node numbers.
        clearance: ``(k,)`` CDIS normal value (negative = penetration).
        pressure: ``(k,)`` CSTR contact pressure.
        energy: ``(k,)`` CELS spring energy (with ccx 2.20's friction energy, docs/method.md
            §11.4).
        master_faces: ``(k, n)`` ccx node numbers of each element's master face, ccx face order.
        slip: ``(k, 2)`` CDIS tangential columns: accumulated tangential relative displacement
            along ccx's output directions t1, t2 (zero without friction).
        shear: ``(k, 2)`` CSTR tangential columns: shear traction along t1, t2.
        accuracy: ``(length, pressure (k,), energy (k,))``: what each value is known to
            (``roundoff.clean_contact``, docs/method.md §14.5).
    """

    pair: str
    nodes: np.ndarray
    clearance: np.ndarray
    pressure: np.ndarray
    energy: np.ndarray
    master_faces: np.ndarray
    slip: np.ndarray | None = None
    shear: np.ndarray | None = None
    accuracy: tuple | None = None


def _vectors3(values: np.ndarray) -> np.ndarray:
    """``(n, 3)`` vectors: those of a 2D model with z = 0 (docs/method.md §23)."""
    values = np.asarray(values, dtype=float)
    if values.shape[1] == 3:
        return values
    return np.column_stack([values, np.zeros((values.shape[0], 3 - values.shape[1]))])


class OutputValues:
    """The output values of a deck's model at its current displacement (all collective).

    Args:
        deck: The deck.
        model: Its dolfinx model.
        problem: The contact problem solved for ``model.u``.
        numbering: The model's nodes, cells and springs in ccx numbering.
        comm: The job's communicator.
    """

    def __init__(
        self,
        deck: Deck,
        model: CalculixModel,
        problem: ContactProblem,
        numbering: CcxNumbering,
        comm: MPI.Comm,
    ) -> None:
        self.deck, self.model, self.problem, self.numbering = deck, model, problem, numbering
        self.comm = comm
        self._stress: tuple[dolfinx.fem.Expression, int] | None = None
        self._heat_flux: tuple[dolfinx.fem.Expression, int] | None = None
        self._strain: tuple[dolfinx.fem.Expression, int] | None = None
        self._field_scales: tuple[float, float, tuple[float, float]] | None = None
        self._wedge_classes: np.ndarray | None = None
        self._strain_tensor: ufl.core.expr.Expr | None = None
        self._energy: tuple[dolfinx.fem.Expression, ufl.core.expr.Expr] | None = None
        self._wedge_expressions: dict[tuple[str, int], dolfinx.fem.Expression] = {}
        #: The velocity of the job's dynamic steps (``*NODE PRINT V``), None before the first.
        self.velocity: dolfinx.fem.Function | None = None

    # -- forces ------------------------------------------------------------------------------------

    def internal_forces(self) -> np.ndarray:
        """``(N, 3)`` internal force of bulk elements plus contact springs at every deck node.

        Summed in ccx order, the same on any number of processes; C3D20's face- and cell-centre
        forces moved to its 20 nodes (docs/method.md §13.5). Collective.
        """
        return self.numbering.nodal_forces(self.problem) * self.model.printed_scale

    def printed_forces(self, largest_residual: float) -> tuple[np.ndarray, float]:
        """:meth:`internal_forces` with those within their accuracy as 0, and that accuracy.

        The accuracy is the converged iterate's ``largest_residual`` force plus round-off, plus
        the round-off of the displacement they come from (docs/method.md §14.5). Collective.
        """
        forces = self.internal_forces()
        floor = force_floor(forces, largest_residual)
        floor += self.field_accuracy().force
        return clean(forces, floor), floor

    def field_accuracy(self) -> FieldAccuracy:
        """Accuracy of the stresses and contact values of the current displacement.

        From the largest coordinate and displacement, the largest modulus and the smallest
        element (docs/method.md §14.5). Collective.
        """
        if self._field_scales is None:
            deck = self.deck
            block = deck.elements[self.model.element_type.name]
            coords = np.asarray(deck.node_coords, dtype=np.float64)
            self._field_scales = (
                float(np.abs(coords).max(initial=0.0)),
                largest_modulus(m.elastic for m in deck.materials.values() if m.elastic),
                element_sizes(coords, deck.node_index(block.connectivity)),
            )
        coordinates, modulus, sizes = self._field_scales
        local = float(np.abs(self.model.u.x.array).max(initial=0.0))
        return FieldAccuracy.of(coordinates, self.comm.allreduce(local, MPI.MAX), modulus, sizes)

    # -- displacements -----------------------------------------------------------------------------

    def displacements(self) -> np.ndarray:
        """``(N, 3)`` displacement of every deck node (rows of ``deck.node_ids``). Collective.

        Shell nodes: ccx's combination of their expanded nodes (docs/method.md §24); 2D elements:
        ``u_z = 0`` (§23).
        """
        values = self.model.u.x.array.reshape(-1, self.model.gdim)
        if values.shape[1] == 2:  # ccx's 2D elements
            values = np.column_stack([values, np.zeros(values.shape[0])])
        values = self.numbering.nodal(values)
        if self.deck.shells is not None:
            values = self.deck.shells.printed(self.deck.node_ids, values)
        return values

    def velocities(self) -> np.ndarray:
        """``(N, 3)`` velocity of every deck node (after a dynamic step began). Collective.

        Nodes without dofs (reference nodes of ``*EQUATION``) print 0.
        """
        if self.velocity is None:
            raise ValueError("no velocity: *NODE PRINT V needs a *DYNAMIC step")
        return self.numbering.nodal(self.velocity.x.array.reshape(-1, 3))

    def temperatures(self) -> np.ndarray:
        """``(N, 1)`` temperature of every deck node (coupled steps only). Collective."""
        thermal = self.model.thermal
        if thermal is None:
            raise ValueError("the model has no temperature field (no *COUPLED step)")
        return self.numbering.nodal(thermal.T.x.array[:, None])

    def with_reference(
        self, ids: np.ndarray, values: np.ndarray, load_time: tuple[int, float]
    ) -> np.ndarray:
        """``values (n, 3)`` of nodes ``ids``, reference nodes at their prescribed displacement.

        ``load_time`` is ``(step index, step time)`` of the loads applied. Collective when the
        model has free reference nodes.
        """
        gathered = None  # free reference nodes: from the displacement of all processes
        if self.model.free_references:
            gathered = self.displacements()
        keys, known = self.model.reference_displacements(*load_time, gathered)
        if keys.size == 0:
            return values
        wanted = 3 * self.deck.node_index(ids)[:, None] + np.arange(3)
        pos = np.minimum(np.searchsorted(keys, wanted), keys.size - 1)
        hit = keys[pos] == wanted
        values = values.copy()
        values[hit] = known[pos[hit]]
        return values

    # -- stresses ----------------------------------------------------------------------------------

    def stresses(self, element_ids: np.ndarray) -> np.ndarray:
        """Cauchy stresses ``(E, q, 6)`` (xx, yy, zz, xy, xz, yz) at ccx's integration points.

        Collective: each element is evaluated by the process owning it.
        """
        if self.model.incompatible_modes is not None:
            return self._incompatible_mode_stresses(element_ids)
        if self._stress is None:
            points = self.model.element_type.integration_points
            self._stress = (dolfinx.fem.Expression(self.model.cauchy, points), points.shape[0])
        expression, q = self._stress
        index = ([0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2])

        order = self._plastic_point_order()

        def evaluate(cells: np.ndarray) -> np.ndarray:
            values = compat.evaluate_expression(
                expression, self.model.mesh, cells.astype(np.int32)
            ).reshape(cells.size, q, 3, 3)
            plastic = np.zeros(cells.size, dtype=bool)
            for law in self.model.plasticity:  # their stresses at ccx's points (§21.6)
                mine = np.isin(cells, law.cells)
                if mine.any():
                    _put_law_values(values, mine, law.cell_stresses(cells[mine]), order)
                    plastic |= mine
            self._at_wedge_points("S", cells, values, skip=plastic)
            return values[:, :, index[0], index[1]]

        self._compile_wedge_expressions("S", self.model.cauchy)
        values = self.numbering.element_values(element_ids, evaluate, (q, 6))
        rows = self.model.element_type.print_rows
        if rows is None:
            return values
        values = values[:, rows]  # ccx's expanded 2D elements
        axisymmetric = self.model.axisymmetric_elements
        etype = self.model.element_type
        quadratic = etype.num_nodes > etype.num_corners  # CAX8R; not CAX4's straight wedge
        if axisymmetric is not None and quadratic and rows.size == 2 * np.unique(rows).size:
            turned = np.isin(np.asarray(element_ids), axisymmetric)
            values[turned] = sector_stresses(values[turned])
        return values

    def point_counts(self, element_ids: np.ndarray, rows: int) -> np.ndarray:
        """``(E,)`` number of integration points ccx prints of each element: 2 on a C3D6 wedge.

        The element arrays of :meth:`stresses` and :meth:`strains` hold a wedge's two points in
        their first two rows (docs/method.md §30.6); every other element prints all ``rows``
        (ccx's points: 8 for a 2D element, which ccx expands into a C3D8).
        """
        element_ids = np.asarray(element_ids)
        counts = np.full(element_ids.size, rows, dtype=np.int64)
        counts[np.isin(element_ids, self.deck.wedges)] = 2
        return counts

    def _wedge_classes_of_cells(self) -> np.ndarray:
        """The collapse class of every local cell (-1: no wedge)."""
        if self._wedge_classes is None:
            self._wedge_classes = wedge_cells(self.model.mesh)
        return self._wedge_classes

    def _compile_wedge_expressions(self, key: str, tensor: ufl.core.expr.Expr) -> None:
        """``tensor`` at the two points of each collapse class present on any process.

        Collective: dolfinx compiles an Expression on every process of the mesh, so all
        processes compile the same classes in the same order, whether or not they evaluate
        them (the wedge punch hung on 2 processes when only one held a class).
        """
        if self.deck.wedges.size == 0:
            return
        classes = self._wedge_classes_of_cells()
        mask = sum(1 << c for c in np.unique(classes[classes >= 0]).tolist())
        mask = self.comm.allreduce(mask, op=MPI.BOR)
        for c in (c for c in range(NUM_CLASSES) if mask >> c & 1):
            if (key, c) not in self._wedge_expressions:
                points = wedge_rule(c)[0]
                self._wedge_expressions[key, c] = dolfinx.fem.Expression(tensor, points)

    def _at_wedge_points(
        self,
        key: str,
        cells: np.ndarray,
        values: np.ndarray,
        skip: np.ndarray | None = None,
    ) -> None:
        """Put the ``key`` tensor at ccx's two C3D6 points into rows 0, 1 of wedge cells' values.

        ``values`` is ``(cells, q, 3, 3)``; rows past the second of a wedge become 0. The points
        are those of the cell's collapse class (``kernels/wedge_rule.py``, ccx's order). Cells
        where ``skip`` is set (plastic wedges: their laws' values) are left alone.
        """
        if self.deck.wedges.size == 0 or cells.size == 0:
            return
        classes = self._wedge_classes_of_cells()[cells].copy()
        if skip is not None:
            classes[skip] = -1
        for c in np.unique(classes[classes >= 0]).tolist():
            hit = np.flatnonzero(classes == c)  # compiled by _compile_wedge_expressions
            at = compat.evaluate_expression(
                self._wedge_expressions[key, c], self.model.mesh, cells[hit].astype(np.int32)
            ).reshape(hit.size, 2, 3, 3)
            values[hit] = 0.0
            values[hit, :2] = at

    def _plastic_point_order(self) -> np.ndarray | None:
        """The plastic laws' point of each of ccx's integration points (same rule, other order)."""
        if not self.model.plasticity:
            return None
        ccx = self.model.element_type.integration_points
        law = self.model.plasticity[0]
        points = compat.quadrature_points(self.model.mesh, law.quadrature_degree)
        distance = np.linalg.norm(ccx[:, None, :] - points[None, :, :], axis=2)
        order = np.argmin(distance, axis=1)
        if points.shape != ccx.shape or np.any(distance[np.arange(order.size), order] > 1e-10):
            raise ValueError(
                f"the plastic laws' quadrature points are not ccx's {self.model.element_type.name} "
                "integration points"
            )
        return order

    def strains(self, element_ids: np.ndarray) -> np.ndarray:
        """Total strains ``(E, q, 6)`` (xx, yy, zz, xy, xz, yz; tensor shears) at ccx's points.

        ccx 2.20's ``*EL PRINT E``: the small strain, under NLGEOM the Green-Lagrange strain
        (measured, docs/method.md §21.6). 3D continuum elements; ``check_requests`` refuses the
        others. Collective.
        """
        if self._strain is None:
            model = self.model
            kinematics = model.nlgeom
            if kinematics is None:
                kinematics = float(any(step.nlgeom for step in self.deck.steps))
            H = ufl.grad(model.u)
            strain = ufl.sym(H) + 0.5 * kinematics * H.T * H
            points = model.element_type.integration_points
            self._strain = (dolfinx.fem.Expression(strain, points), points.shape[0])
            self._strain_tensor = strain
        expression, q = self._strain
        index = ([0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2])

        strain = self._strain_tensor

        def evaluate(cells: np.ndarray) -> np.ndarray:
            values = compat.evaluate_expression(expression, self.model.mesh, cells.astype(np.int32))
            values = values.reshape(cells.size, q, 3, 3)
            self._at_wedge_points("E", cells, values)
            return values[:, :, index[0], index[1]]

        self._compile_wedge_expressions("E", strain)
        return self.numbering.element_values(element_ids, evaluate, (q, 6))

    def _kinematics(self) -> float | dolfinx.fem.Constant:
        """0 (small strain) or 1 (NLGEOM), or the model's switch when its steps mix them."""
        if self.model.nlgeom is not None:
            return self.model.nlgeom
        return float(any(step.nlgeom for step in self.deck.steps))

    def _mechanical_strain(self) -> ufl.core.expr.Expr:
        """The strain of ``grad u`` less the thermal strain ``x I`` (that of the stresses).

        Small strain ``sym(H - x I)``, under NLGEOM the Green-Lagrange strain of ``H - x I``
        (``bulk.stresses``, docs/method.md §20.8); the total strain without temperatures.
        """
        kinematics = self._kinematics()
        H = ufl.grad(self.model.u)
        if self.model.thermal is not None:
            H = H - self.model.thermal.thermal_strain()
        return ufl.sym(H) + 0.5 * kinematics * H.T * H

    def mechanical_strains(self, element_ids: np.ndarray) -> np.ndarray:
        """Mechanical strains ``(E, q, 6)`` (ccx's ``ME``) at ccx's integration points.

        The total strain less the thermal strain, as the stresses see it: without temperatures
        :meth:`strains` (measured equal in ccx 2.20, small strain and NLGEOM; in coupled steps
        the strain of ``grad u - x I``, docs/method.md §36). Collective.
        """
        if self.model.thermal is None:
            return self.strains(element_ids)
        model = self.model
        points = model.element_type.integration_points
        q = points.shape[0]
        tensor = self._mechanical_strain()
        expression = dolfinx.fem.Expression(tensor, points)
        index = ([0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2])

        def evaluate(cells: np.ndarray) -> np.ndarray:
            values = compat.evaluate_expression(expression, model.mesh, cells.astype(np.int32))
            values = values.reshape(cells.size, q, 3, 3)
            self._at_wedge_points("ME", cells, values)
            return values[:, :, index[0], index[1]]

        self._compile_wedge_expressions("ME", tensor)
        return self.numbering.element_values(element_ids, evaluate, (q, 6))

    def energy_densities(self, element_ids: np.ndarray) -> np.ndarray:
        """Strain energy densities ``(E, q, 1)`` (ccx's ``ENER``) at ccx's integration points.

        Elastic sections ``S : E / 2`` (the Cauchy stress and small strain, under NLGEOM the
        second Piola-Kirchhoff stress and Green-Lagrange strain: per unit reference volume; the
        mechanical strain in coupled steps);
        plastic sections their laws' energy accumulated over the increments by ccx's
        trapezoidal rule (``kernels/strain_energy.py``). Measured, docs/method.md §36.
        Collective.
        """
        model = self.model
        points = model.element_type.integration_points
        q = points.shape[0]
        if self._energy is None:
            kinematics = self._kinematics()
            H = ufl.grad(model.u)
            strain = self._mechanical_strain()
            if isinstance(kinematics, float) and kinematics == 0.0:
                second_piola = model.first_piola
            else:
                second_piola = ufl.inv(ufl.Identity(3) + kinematics * H) * model.first_piola
            # a tensor (energy times I) so that the wedges' points take the strains' path
            tensor = 0.5 * ufl.inner(second_piola, strain) * ufl.Identity(3)
            self._energy = (dolfinx.fem.Expression(tensor, points), tensor)
        expression, tensor = self._energy
        order = self._plastic_point_order()

        def evaluate(cells: np.ndarray) -> np.ndarray:
            values = compat.evaluate_expression(expression, model.mesh, cells.astype(np.int32))
            values = values.reshape(cells.size, q, 3, 3)
            plastic = np.zeros(cells.size, dtype=bool)
            for law in model.plasticity:
                plastic |= np.isin(cells, law.cells)
            self._at_wedge_points("ENER", cells, values, skip=plastic)
            energy = values[:, :, :1, 0].copy()
            for law in model.plasticity:
                mine = np.isin(cells, law.cells)
                if mine.any():
                    held = law.cell_strain_energy_densities(cells[mine])
                    _put_law_values(energy[..., 0], mine, held, order)
            return energy

        self._compile_wedge_expressions("ENER", tensor)
        return self.numbering.element_values(element_ids, evaluate, (q, 1))

    def state_variables(self, element_ids: np.ndarray) -> np.ndarray:
        """Internal state variables ``(E, q, k)`` (ccx's ``SDV``) at ccx's integration points.

        With plastic sections ``k = 13``, ccx 2.20's layout of its isotropic ``*PLASTIC`` law:
        the equivalent plastic strain, the plastic strain tensor (xx, yy, zz, xy, xz, yz; under
        NLGEOM ``(I - Cp^-1)/2``) and six zeros (the back stress of kinematic hardening);
        elements of elastic sections 0. Without them ``k = 0``. Measured, docs/method.md §36.
        Collective.
        """
        q = self.model.element_type.integration_points.shape[0]
        if not self.model.plasticity:  # ccx prints the rows' labels only
            return np.zeros((np.asarray(element_ids).size, q, 0))
        width = 13
        order = self._plastic_point_order()

        def evaluate(cells: np.ndarray) -> np.ndarray:
            values = np.zeros((cells.size, q, width))
            for law in self.model.plasticity:
                mine = np.isin(cells, law.cells)
                if mine.any():
                    held = law.cell_state_variables(cells[mine])  # (n, p, 7)
                    _put_law_values(values[..., :7], mine, held, order)
            return values

        return self.numbering.element_values(element_ids, evaluate, (q, width))

    def nodal_strains(self) -> tuple[np.ndarray, np.ndarray]:
        """Strains at the nodes like ccx's ``.frd`` block ``TOSTRAIN`` (frd order, as stresses).

        Collective.
        """
        block = self.deck.elements[self.model.element_type.name]
        nodes, values = self._at_nodes(self.strains(block.ids))
        return nodes, values[:, [0, 1, 2, 3, 5, 4]]

    def equivalent_plastic_strains(self, element_ids: np.ndarray) -> np.ndarray:
        """Equivalent plastic strains ``(E, q, 1)`` (PEEQ) at ccx's integration points.

        The plastic laws' committed values (the last converged increment's), 0 in elastic
        sections, as ccx 2.20 prints them (docs/method.md §21.6). Collective.
        """
        q = self.model.element_type.integration_points.shape[0]
        order = self._plastic_point_order()

        def evaluate(cells: np.ndarray) -> np.ndarray:
            values = np.zeros((cells.size, q, 1))
            for law in self.model.plasticity:
                mine = np.isin(cells, law.cells)
                if mine.any():
                    held = law.cell_equivalent_plastic_strains(cells[mine])
                    _put_law_values(values[..., 0], mine, held, order)
            return values

        values = self.numbering.element_values(element_ids, evaluate, (q, 1))
        rows = self.model.element_type.print_rows
        return values if rows is None else values[:, rows]

    def heat_fluxes(self, element_ids: np.ndarray) -> np.ndarray:
        """Heat fluxes ``-k grad T`` ``(E, q, 3)`` at ccx's integration points (coupled steps).

        In the reference configuration, as ccx 2.20 prints them under NLGEOM (docs/method.md
        §20.8). Collective.
        """
        thermal = self.model.thermal
        if thermal is None:
            raise ValueError("the model has no temperature field (no *COUPLED step)")
        if self._heat_flux is None:
            points = self.model.element_type.integration_points
            flux = -thermal.conductivity * ufl.grad(thermal.T)
            self._heat_flux = (dolfinx.fem.Expression(flux, points), points.shape[0])
        expression, q = self._heat_flux

        def evaluate(cells: np.ndarray) -> np.ndarray:
            values = compat.evaluate_expression(expression, self.model.mesh, cells.astype(np.int32))
            return values.reshape(cells.size, q, 3)

        return self.numbering.element_values(element_ids, evaluate, (q, 3))

    def _incompatible_mode_stresses(self, element_ids: np.ndarray) -> np.ndarray:
        """C3D8I's stresses ``(E, 8, 6)``: small-strain, the condensed modes' strains included."""
        modes = self.model.incompatible_modes
        self.model.u.x.scatter_forward()
        strain = modes.strains(compat.petsc_vector(self.model.u))  # (C, 8, 3, 3), owned cells
        position = np.full(self.numbering.num_owned_cells, -1)
        position[modes.cells] = np.arange(modes.cells.size)
        mu = self.model.mu.x.array[compat.cell_dofs(self.model.mu.function_space)[modes.cells, 0]]
        lmbda = self.model.lmbda.x.array[
            compat.cell_dofs(self.model.lmbda.function_space)[modes.cells, 0]
        ]
        trace = np.trace(strain, axis1=2, axis2=3)
        stress = 2 * mu[:, None, None, None] * strain
        stress += (lmbda[:, None] * trace)[:, :, None, None] * np.eye(3)
        index = ([0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2])

        def evaluate(cells: np.ndarray) -> np.ndarray:
            return stress[position[cells]][:, :, index[0], index[1]]

        return self.numbering.element_values(element_ids, evaluate, (8, 6))

    def nodal_stresses(self) -> tuple[np.ndarray, np.ndarray]:
        """Cauchy stresses at the nodes like ccx's ``.frd`` (frd order xx, yy, zz, xy, yz, zx).

        Integration-point values extrapolated to each element's nodes, averaged over the elements
        around a node (docs/method.md §13.2). Collective.
        """
        block = self.deck.elements[self.model.element_type.name]
        nodes, values = self._at_nodes(self.stresses(block.ids))
        return nodes, values[:, [0, 1, 2, 3, 5, 4]]

    def nodal_equivalent_plastic_strains(self) -> tuple[np.ndarray, np.ndarray]:
        """PEEQ at the nodes like ccx's ``.frd`` block ``PE``: ``(nodes, (n, 1))``.

        Extrapolated and averaged as the stresses, elastic elements counting 0 (measured on a
        plastic C3D8 beside an elastic one, docs/method.md §21.6). Collective.
        """
        block = self.deck.elements[self.model.element_type.name]
        return self._at_nodes(self.equivalent_plastic_strains(block.ids))

    def nodal_element_values(self, key: str) -> tuple[np.ndarray, np.ndarray]:
        """``ME``, ``ENER`` or ``SDV`` at the nodes like ccx's ``.frd`` blocks.

        ``MESTRAIN``, ``ENER`` and ``SDV``: extrapolated and averaged as the stresses (frd order
        of tensors). Collective.

        Args:
            key: ``ME``, ``ENER`` or ``SDV``.
        """
        ids = self.deck.elements[self.model.element_type.name].ids
        if key == "ME":
            nodes, values = self._at_nodes(self.mechanical_strains(ids))
            return nodes, values[:, [0, 1, 2, 3, 5, 4]]
        if key == "ENER":
            return self._at_nodes(self.energy_densities(ids))
        if key == "SDV":
            return self._at_nodes(self.state_variables(ids))
        raise ValueError(f"no nodal values of element output {key!r}")

    def _at_nodes(self, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Point values ``(E, q, k)`` of every element extrapolated and averaged at the nodes.

        A C3D6 wedge's two points (its first two rows) go to its six nodes by ccx's C3D6
        extrapolation and count once at each (docs/method.md §35).
        """
        block = self.deck.elements[self.model.element_type.name]
        extrapolate = self.model.element_type.extrapolation
        wedge = np.isin(block.ids, self.deck.wedges)
        components = values.shape[2]  # 0 for SDV without plastic sections
        at_nodes = np.einsum("nq,eqk->enk", extrapolate, values[~wedge])
        index = self.deck.node_index(block.connectivity[~wedge])
        at_nodes, index = at_nodes.reshape(index.size, components), index.ravel()
        if wedge.any():
            nodes = self.deck.wedge_nodes[np.searchsorted(self.deck.wedges, block.ids[wedge])]
            at_wedge = np.einsum("nq,eqk->enk", C3D6_EXTRAPOLATION, values[wedge, :2])
            at_nodes = np.vstack([at_nodes, at_wedge.reshape(nodes.size, components)])
            index = np.concatenate([index, self.deck.node_index(nodes).ravel()])
        total = np.zeros((self.deck.node_ids.size, components))
        count = np.zeros(self.deck.node_ids.size)
        np.add.at(total, index, at_nodes)
        np.add.at(count, index, 1.0)
        used = count > 0
        return self.deck.node_ids[used], total[used] / count[used, None]

    # -- contact -----------------------------------------------------------------------------------

    def contact_rows(self, ccx: str = "2.20") -> list[ContactRows]:
        """Contact rows of every pair at the current springs, slave nodes ascending.

        ``ccx`` is the version whose CELS is printed: 2.20 adds twice the tangential spring
        energy, 2.23 the energy itself (docs/method.md §13.6). Collective: the springs of all
        processes.
        """
        rows = []
        numbering = self.numbering
        length = self.field_accuracy().length
        groups = _pair_groups(self.problem.states, contact_results(self.problem))
        for group, pair in zip(groups, self.deck.contact_pairs):
            parts = [self._contact_values(state, results, ccx, length) for state, results in group]
            if len(parts) > 1:  # a master of several face types (docs/method.md §38.8)
                width = max(part[4].shape[1] for part in parts)
                for part in parts:
                    part[4] = np.pad(
                        part[4], ((0, 0), (0, width - part[4].shape[1])), constant_values=-1
                    )
            values = [np.concatenate(arrays) for arrays in zip(*parts)]
            nodes, clearance, pressure, energy, faces, slip, shear, dp, de = numbering.allgather(
                *values
            )
            faces = numbering.master_faces(pair.master, faces)
            order = np.argsort(nodes, kind="stable")
            rows.append(
                ContactRows(
                    group[0][1].pair,
                    nodes[order],
                    clearance[order],
                    pressure[order],
                    energy[order],
                    faces[order],
                    slip[order],
                    shear[order],
                    (length, dp[order], de[order]),
                )
            )
        return rows

    def _contact_values(
        self, state: PairState, results: ContactResults, ccx: str, length: float
    ) -> list[np.ndarray]:
        """This process's contact rows of one pair state, unsorted, in ccx numbering."""
        numbering = self.numbering
        faces = numbering.ccx_nodes(self.problem, state.master_faces.faces[state.spring_face])
        normal, slip, shear = (_vectors3(v) for v in (results.normal, results.slip, results.shear))
        t1, t2 = output_tangents(normal)
        slip = np.column_stack([np.einsum("ni,ni->n", slip, t) for t in (t1, t2)])
        shear = np.column_stack([np.einsum("ni,ni->n", shear, t) for t in (t1, t2)])
        # ccx 2.20 prints twice the tangential spring energy (docs/method.md §11.4), 2.23 not
        energy = results.energy + (2.0 if ccx == "2.20" else 1.0) * results.friction_energy
        energy = energy * self.model.printed_scale  # CAX: ccx's sector (§23)
        dp, de = law_accuracy(state.pair.interaction.law, -results.clearance, results.area, length)
        return [
            numbering.ccx_nodes(self.problem, results.node),
            results.clearance,
            results.pressure,
            energy,
            faces,
            slip.reshape(-1, 2),
            shear.reshape(-1, 2),
            dp,
            de,
        ]

    def contact_elements(self, problem: ContactProblem) -> list[tuple[np.ndarray, np.ndarray]]:
        """Master faces ``(k, n)`` and slave nodes ``(k,)`` of each pair's springs (``.cel``).

        In ccx numbering, slave nodes ascending, pairs in deck order. Collective.
        """
        numbering = self.numbering
        elements = []
        groups = _pair_groups(problem.states, problem.states)
        for group, pair in zip(groups, self.deck.contact_pairs):
            if len(group) > 1:  # refused by the model (docs/method.md §38.8)
                raise NotImplementedError(
                    f"{pair.location}: the CONTACT ELEMENTS file of a master of several face types"
                )
            state = group[0][0]
            slaves, faces = numbering.allgather(
                numbering.ccx_nodes(problem, state.slave.nodes[state.spring_slave]),
                numbering.ccx_nodes(problem, state.master_faces.faces[state.spring_face]),
            )
            faces = numbering.master_faces(pair.master, faces)
            order = np.argsort(slaves, kind="stable")
            elements.append((faces[order], slaves[order]))
        return elements


def _pair_groups(states: list[PairState], values: list) -> list[list[tuple[PairState, object]]]:
    """``(state, value)`` of each pair's states, pairs in order.

    One state per pair, or one per face type of a master of several types (consecutive states
    of one pair, docs/method.md §38.8).
    """
    groups: list[list[tuple[PairState, object]]] = []
    for state, value in zip(states, values, strict=True):
        if groups and groups[-1][0][0].pair is state.pair:
            groups[-1].append((state, value))
        else:
            groups.append([(state, value)])
    return groups


def _put_law_values(
    values: np.ndarray, mine: np.ndarray, held: np.ndarray, order: np.ndarray | None
) -> None:
    """Put a plastic law's point values ``held (n, p, ...)`` into rows ``mine`` of ``values``.

    A law of C3D8's points gives them in ccx's ``order``; a wedge's law (``p = 2``, ccx's C3D6
    rule in ccx's order, docs/method.md §30.5) fills the first two rows, the others 0.
    """
    if held.shape[1] == 2 and values.shape[1] != 2:
        values[mine] = 0.0
        values[mine, :2] = held
    else:
        values[mine] = held[:, order]


def sector_stresses(values: np.ndarray) -> np.ndarray:
    """ccx's printed stresses of a CAX8R element: two layers of its 2-degree quadratic sector.

    ccx's integration points of the two layers lie at ``phi = -+ theta/(2 sqrt 3)`` about the
    axis (rows of the first layer first), where it prints the Cartesian components of the ring's
    stress ``(s_rr, s_zz, s_tt, s_rz)`` turned by ``phi``: ``s_xx = s_rr c^2 + s_tt s^2``,
    ``s_zz = s_rr s^2 + s_tt c^2``, ``s_xz = (s_rr - s_tt) s c``, ``s_xy = s_rz c``,
    ``s_yz = s_rz s`` (measured on the bolt deck, docs/method.md §26.4).

    Args:
        values: ``(E, q, 6)`` the 2D model's stresses (xx, yy, zz, xy, xz, yz) of ccx's rows.
    """
    q = values.shape[1]
    phi = np.where(np.arange(q) < q // 2, -1.0, 1.0) * AXISYMMETRIC_SECTOR / (2 * np.sqrt(3.0))
    s, c = np.sin(phi), np.cos(phi)
    rr, zz, tt, rz = values[..., 0], values[..., 1], values[..., 2], values[..., 3]
    out = np.empty_like(values)
    out[..., 0] = rr * c**2 + tt * s**2
    out[..., 1] = zz
    out[..., 2] = rr * s**2 + tt * c**2
    out[..., 3] = rz * c
    out[..., 4] = (rr - tt) * s * c
    out[..., 5] = rz * s
    return out
