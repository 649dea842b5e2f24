"""ccx's 2D elements (CPE, CPS, CAX) run natively on a 2D mesh (docs/method.md §23).

ccx 2.20 expands them into one layer of 3D elements; here the deck's 2D elements become a 2D
dolfinx mesh (``x`` and ``y`` of the nodes, which must lie in ``z = 0``) with a 2-component
displacement. The bulk is plane strain, plane stress or axisymmetric small-strain elasticity
written with a 3x3 displacement gradient (zz entry 0, the plane-stress strain, or the hoop strain
``u_r / r``), so that the Cauchy stress has ccx's six components; the residual is weighted by the
``*SOLID SECTION`` thickness (plane) or by ``2 pi r`` (axisymmetric: every force is the whole
ring's, as ccx's input). What the 2D model does not support is refused here, naming the card.
"""

from __future__ import annotations

import math

import numpy as np

import dolfinx.fem
import dolfinx.mesh
import ufl

from dolfinx_ntf.fem.plane_sections import PlaneSections

from ..deck import Deck, ElementBlock, not_supported
from ..elements import AXISYMMETRIC_SECTOR

__all__ = [
    "check_two_d_deck",
    "plane_kinematics",
    "plane_sections",
    "printed_scale",
    "section_thickness",
    "volume_weight",
]


def section_thickness(
    deck: Deck, block: ElementBlock, models: np.ndarray | None = None
) -> np.ndarray:
    """The out-of-plane thickness of each element of ``block`` (ccx's default 1).

    Plane elements take their ``*SOLID SECTION``'s first value, one for all of them (a
    thickness that varies between sections is refused); CAX elements 1 (the value has no effect
    in ccx either). In a quasi-axisymmetric deck the plane-stress thickness is the
    whole circumference's width, as ccx's manual asks (docs/method.md §26).

    Args:
        deck: The deck.
        block: Its (merged) element block.
        models: The 2D model of each element of ``block`` (default: its type's).
    """
    if models is None:
        models = np.full(block.ids.size, block.type.model, dtype=object)
    thickness = np.ones(block.ids.size)
    order = np.argsort(block.ids)
    for section in deck.sections:
        t = section.thickness
        if t is not None and not (np.isfinite(t) and t > 0.0):
            raise ValueError(
                f"{section.location}: *SOLID SECTION thickness of {block.type.name} elements must "
                "be a positive number"
            )
        members = np.unique(deck.elsets[section.elset])
        members = members[np.isin(members, block.ids)]
        rows = order[np.searchsorted(block.ids, members, sorter=order)]
        thickness[rows] = 1.0 if t is None else t
    plane = models != "axisymmetric"
    if np.any(plane) and not np.all(plane):  # ccx gives it an effect there (measured, §26)
        rows_of = np.argsort(block.ids)
        for section in deck.sections:
            members = np.unique(deck.elsets[section.elset])
            members = members[np.isin(members, block.ids)]
            rows = rows_of[np.searchsorted(block.ids, members, sorter=rows_of)]
            if section.thickness is not None and np.any(~plane[rows]):
                raise not_supported(
                    "a *SOLID SECTION thickness on axisymmetric elements beside plane-stress "
                    "ones (ccx then changes the forces: measured 3 times the plane-stress "
                    "section's alone); give the CAX elements a section without a thickness",
                    section.location,
                )
    values = np.unique(thickness[plane])
    if values.size > 1:  # ccx allows it; its springs would need a thickness per slave node
        raise not_supported(
            f"*SOLID SECTION thicknesses {values.tolist()} that differ between sections of "
            f"{block.type.name} elements",
            deck.sections[0].location,
        )
    thickness[~plane] = 1.0
    return thickness


def check_two_d_deck(deck: Deck, block: ElementBlock, models: np.ndarray | None = None) -> None:
    """Refuse what the 2D deck runner does not do (``NotImplementedError``/``ValueError``).

    The nodes must lie in ``z = 0`` (ccx's rule for 2D elements), those of CAX elements at
    ``x >= 0``; no dynamic or frequency steps, NLGEOM in some steps only, ``*MODEL CHANGE``,
    ``*EQUATION``, ``*TIE``, spring elements, out-of-plane loads, ``.frd`` output, nodes shared by
    plane-stress and axisymmetric elements (ccx's hinge). ``*FRICTION`` and ``*CHANGE FRICTION``
    pass to the 2D pairs as in 3D; NLGEOM steps are St.Venant-Kirchhoff (docs/method.md §26).

    Args:
        deck: The deck.
        block: Its (merged) element block.
        models: The 2D model of each element of ``block`` (default: its type's).
    """
    name = block.type.name
    if models is None:
        models = np.full(block.ids.size, block.type.model, dtype=object)
    axi = models == "axisymmetric"
    if np.any(axi) and not np.all(axi):
        shared = np.intersect1d(block.connectivity[axi], block.connectivity[~axi])
        if shared.size:
            raise not_supported(
                f"node {int(shared[0])} shared by plane-stress and axisymmetric elements (ccx "
                "connects them by a hinge)",
                block.locations[0] if block.locations else deck.path,
            )
    coords = np.asarray(deck.node_coords, dtype=np.float64)
    used = deck.node_index(np.unique(block.connectivity))
    off = np.abs(coords[used, 2]) > 0.0
    if np.any(off):
        row = used[np.argmax(off)]
        raise ValueError(
            f"{deck.path}: node {int(deck.node_ids[row])} of a {name} element has z = "
            f"{coords[row, 2]}; structures of 2D elements must lie in the plane z = 0"
        )
    used_axi = deck.node_index(np.unique(block.connectivity[axi]))
    if np.any(coords[used_axi, 0] < 0.0):
        node = int(deck.node_ids[used_axi[np.argmax(coords[used_axi, 0] < 0.0)]])
        raise ValueError(
            f"{deck.path}: node {node} of a {name} element has a negative radius x "
            f"= {coords[deck.node_index([node])[0], 0]}"
        )
    features = [
        ("*EQUATION", deck.equations),
        ("*TIE", deck.ties),
        ("spring elements", deck.springs),
        ("*CYCLIC SYMMETRY MODEL", deck.cyclic_symmetries),
    ]
    for what, cards in features:
        if cards:
            raise not_supported(f"{what} with {name} elements", _where(cards[0], deck))
    if len({step.nlgeom for step in deck.steps}) > 1:
        step = next(s for s in deck.steps if s.nlgeom)
        raise not_supported(
            f"NLGEOM in some steps only with {name} elements (all steps or none)", step.location
        )
    for step in deck.steps:
        for change in step.model_changes:
            raise not_supported(f"*MODEL CHANGE with {name} elements", _where(change, deck))
        if step.dynamic is not None or step.frequency is not None or step.modal_dynamic:
            raise not_supported(
                f"*DYNAMIC, *FREQUENCY and *MODAL DYNAMIC steps with {name} elements",
                step.location,
            )
        for request in step.file_requests:
            raise not_supported(
                f"{request.keyword} (.frd and .cel files) with {name} elements", request.location
            )
        for card in step.cloads:
            if card.dof == 3 and card.value != 0.0:
                raise ValueError(
                    f"{card.location}: *CLOAD in direction 3 on a structure of {name} elements, "
                    "which lies in the xy-plane"
                )
    for card in [*deck.boundaries, *(b for s in deck.steps for b in s.boundaries)]:
        if card.first_dof <= 3 <= card.last_dof and card.value not in (None, 0.0):
            raise ValueError(
                f"{card.location}: *BOUNDARY prescribes a displacement in direction 3 on a "
                f"structure of {name} elements, which lies in the xy-plane"
            )


def plane_sections(
    mesh: dolfinx.mesh.Mesh, models: np.ndarray, thickness: np.ndarray, element_cell: np.ndarray
) -> PlaneSections:
    """The per-cell 2D models of a deck's mesh (local cells of its elements, docs/method.md §26).

    Args:
        mesh: The deck's 2D mesh.
        models: The 2D model of each element (rows of the block).
        thickness: The thickness of each element.
        element_cell: The local cell of each element, -1 on other processes.
    """
    here = element_cell >= 0
    cells, kinds = element_cell[here], models[here]
    index_map = mesh.topology.index_map(mesh.topology.dim)
    per_cell = np.ones(index_map.size_local + index_map.num_ghosts)
    per_cell[cells] = thickness[here]
    return PlaneSections.from_cells(
        mesh,
        axisymmetric=cells[kinds == "axisymmetric"],
        plane_stress=cells[kinds == "plane stress"],
        thickness=per_cell,
    )


def _where(card: object, deck: Deck) -> str:
    """The location of a deck card, or the deck's path."""
    return str(getattr(card, "location", deck.path))


def volume_weight(mesh: dolfinx.mesh.Mesh, model: str, thickness: float) -> ufl.core.expr.Expr:
    """The weight of the 2D residual: ``2 pi r`` (axisymmetric) or the thickness (plane)."""
    if model == "axisymmetric":
        return 2 * math.pi * ufl.SpatialCoordinate(mesh)[0]
    return dolfinx.fem.Constant(mesh, float(thickness))


def plane_kinematics(
    w: ufl.core.expr.Expr, model: str, nu_factor: ufl.core.expr.Expr | None = None
) -> ufl.core.expr.Expr:
    """The 3x3 gradient of a 2D field ``w`` in ``model``.

    zz entry: 0 (plane strain, and the test function of plane stress), ``w_r / r``
    (axisymmetric), or for plane stress with ``nu_factor = -lambda / (lambda + 2 mu)`` the strain
    ``nu_factor (e_xx + e_yy)`` that makes ``sigma_zz = 0``.
    """
    g = ufl.grad(w)
    if model == "axisymmetric":
        r = ufl.SpatialCoordinate(ufl.domain.extract_unique_domain(w))[0]
        zz = w[0] / r
    elif model == "plane stress" and nu_factor is not None:
        zz = nu_factor * (g[0, 0] + g[1, 1])
    else:
        zz = 0
    return ufl.as_tensor([[g[0, 0], g[0, 1], 0], [g[1, 0], g[1, 1], 0], [0, 0, zz]])


def printed_scale(model: str, quadratic: bool = False) -> float:
    """Factor from the 2D model's forces and energies to those ccx prints.

    ccx prints the forces and spring energies of its expanded CAX sector of angle ``theta`` =
    2 degrees. A linear element (CAX3, CAX4) becomes a wedge with straight chords, whose volume is
    ``sin(theta)/(2 pi)`` of the ring's (``r^2 sin(theta)/2`` against ``r^2 theta/2`` per unit
    area of the meridian section): its forces are the ring's times ``sin(theta)/(2 pi)`` (measured
    to 7 digits, docs/method.md §23). A quadratic element (CAX6, CAX8, CAX8R) becomes a C3D15 or
    C3D20 whose mid-plane nodes lie on the arc: its hoop sides are parabolas through the arc, and
    its forces are ``theta/(2 pi)`` = 1/180 of the ring's (measured: to 7.5e-8, where
    ``sin(theta)/(2 pi)`` is 2.0e-4 off).

    Args:
        model: ``axisymmetric``, ``plane strain`` or ``plane stress``; plane elements: 1 (the
            2D model has the thickness already).
        quadratic: The 2D element has midside nodes (its expansion has mid-plane nodes).
    """
    if model == "axisymmetric":
        if quadratic:
            return AXISYMMETRIC_SECTOR / (2 * math.pi)
        return math.sin(AXISYMMETRIC_SECTOR) / (2 * math.pi)
    return 1.0
