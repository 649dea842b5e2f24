"""A contact pair as the user declares it, and the state the pairing keeps for it.

:class:`ContactPair` is CalculiX's ``*CONTACT PAIR, TYPE=NODE TO SURFACE``; :class:`PairState` is
what :class:`~dolfinx_ntf.contact.pairing.Pairing` knows about it at the current pairing (slave
nodes, master faces, springs, friction history), in the numbering of the problem's nodes.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from dolfinx_ntf import validation
from dolfinx_ntf.fem.surfaces import (
    FaceNodesSurface,
    FacetSurface,
    NodeSurface,
    SlaveSurface,
    SurfaceFaces,
)
from dolfinx_ntf.kernels.friction_state import FrictionState
from dolfinx_ntf.kernels.laws import PressureOverclosureLaw, SurfaceInteraction
from dolfinx_ntf.kernels.master import ContactMaster
from dolfinx_ntf.kernels.rigid import RigidSurface
from dolfinx_ntf.kernels.springs import SpringEvaluation

__all__ = ["FALLBACK_AREAS", "ContactPair", "PairState", "fallback_scale"]

#: ccx's sector of an expanded axisymmetric element (2 degrees, its manual).
_CCX_SECTOR = np.pi / 90.0

#: The fallback areas of faceless slave nodes on a 2D mesh (:class:`ContactPair`).
FALLBACK_AREAS = ("edge", "ccx_plane", "ccx_ring")


def fallback_scale(pair: ContactPair) -> tuple[float, bool]:
    """``(factor, ring)`` of a 2D pair's fallback area: ``factor |q_ξ|`` (times ``2 pi r``).

    ccx's ``4|m|`` of the expanded master face: ``|q_η|`` is half the layer's thickness, or
    ``r sin(theta/2)`` across the sector of angle ``theta`` (its mid-plane at ``η = 0``), whose
    forces are ``theta/(2 pi)`` of the ring's.
    """
    if pair.fallback_area == "ccx_plane":
        return 2.0 * pair.thickness, False
    if pair.fallback_area == "ccx_ring":
        half = 0.5 * _CCX_SECTOR
        return 2.0 * np.sin(half) / half, True
    return 1.0, False


@dataclass
class ContactPair:
    """One node-to-face contact pair (CalculiX ``*CONTACT PAIR, TYPE=NODE TO SURFACE``).

    Args:
        slave: Face-based (:class:`FacetSurface`, or :class:`FaceNodesSurface` on meshes
            without facet numbering) or node-based (:class:`NodeSurface`) slave surface.
        master: Face-based master surface (:class:`FacetSurface` or
            :class:`FaceNodesSurface`), or a rigid analytical surface (one-node springs,
            docs/method.md §15.1).
        interaction: Pressure-overclosure law and optional friction; may be replaced between
            steps (new mu and lambda act from then on, the friction state is kept).
        small_sliding: Pair only at increment starts. Per pair by default; with
            ``ContactProblem(small_sliding_rule="last_pair")`` the flag of the *last* pair decides
            for all, as in CalculiX.
        name: Label used in messages and output.
        active: Inactive pairs generate no springs (``*MODEL CHANGE``); a pair that becomes
            active again starts with a fresh friction state.
        adjust: CalculiX's ADJUST at the first pairing of the analysis (docs/method.md §11.5): a
            distance ``a >= 0`` (slave nodes with clearance ``g <= a`` are moved onto the
            master) or a :class:`NodeSurface` of the nodes to move; None moves nothing.
        thickness: On a 2D mesh, the out-of-plane thickness the tributary edge lengths are
            multiplied by to give the spring areas (1: plane strain per unit thickness, like a
            residual form per unit thickness); it must be 1 on a 3D mesh.
        axisymmetric: On a 2D mesh of the meridian half-plane (``x[0] = r >= 0``, ``x[1] = z``),
            the spring areas are the ring areas ``2 pi ∫ r φ_p ds`` of the slave edges at the
            current radius (docs/method.md §17.2), for the full 360 degrees like a residual
            form with :func:`~dolfinx_ntf.fem.axisymmetric.axisymmetric_weight`; the thickness
            must then stay 1. False on a 3D mesh.
        area_weights: On a 2D mesh, how an edge's area (length times thickness, or ring area)
            is shared among its nodes: ``"consistent"`` (default: 1/2, 1/2 on a line2 edge,
            Simpson's 1/6, 1/6, 2/3 on a line3 one; rings weighted by each node's radius) or
            ``"ccx"``, CalculiX 2.20's fixed shares of the faces it expands 2D edges into (1/2, 1/2;
            26/100, 26/100, 48/100; rings shared by the edge's mean radius), to reproduce ccx
            (docs/method.md §23.3); the areas are then held between pairings (no
            ``linearize_area``).
        fallback_area: On a 2D mesh, the area of a spring whose slave node takes no share of the
            faces' area (a ``NodeSurface`` with ``faceless=True`` or its midside nodes):
            ``"edge"`` (default: ``|q_ξ|`` of the master edge at the projection point),
            ``"ccx_plane"`` (CalculiX's ``4|m|`` of the master face it expands a plane edge
            into, in the current configuration: ``2 |q_ξ|`` times the thickness) or
            ``"ccx_ring"`` (the same of an axisymmetric master's 2-degree sector, scaled to the
            ring: ``2 |q_ξ| 2 pi r sin(1 deg)/(1 deg)`` at the projection point; docs/method.md
            §26.3).
        hold_fallback_area: The fallback area of a spring whose slave node has no share of a
            slave face (``4|m|`` or ``|m|/2`` of its master face, docs/method.md §2.2) is taken
            at the first evaluation after each pairing and held until the next pairing, as ccx
            2.20 does (docs/method.md §38.5); False (default): taken at every evaluation, at the
            current projection point.
    """

    slave: FacetSurface | NodeSurface | FaceNodesSurface
    master: FacetSurface | FaceNodesSurface | RigidSurface
    interaction: SurfaceInteraction
    small_sliding: bool = False
    name: str = ""
    active: bool = True
    adjust: float | NodeSurface | None = None
    thickness: float = 1.0
    axisymmetric: bool = False
    area_weights: str = "consistent"
    fallback_area: str = "edge"
    hold_fallback_area: bool = False

    def __post_init__(self) -> None:
        """Check the kinds of the arguments (``TypeError``/``ValueError`` naming them)."""
        owner = (
            f"ContactPair {self.name!r}"
            if isinstance(self.name, str) and self.name
            else ("ContactPair")
        )
        validation.check_type(
            self.slave, (FacetSurface, NodeSurface, FaceNodesSurface), f"{owner}: slave"
        )
        if isinstance(self.master, NodeSurface):
            raise ValueError(
                f"{owner}: the master surface must be a FacetSurface (face-based), got a "
                "NodeSurface; only the slave surface may be node-based"
            )
        validation.check_type(
            self.master, (FacetSurface, FaceNodesSurface, RigidSurface), f"{owner}: master"
        )
        validation.check_type(
            self.interaction,
            SurfaceInteraction,
            f"{owner}: interaction",
            "wrap the law: SurfaceInteraction(law)"
            if isinstance(self.interaction, PressureOverclosureLaw)
            else "",
        )
        validation.check_type(self.name, str, f"{owner}: name")
        validation.check_positive(self.thickness, f"{owner}: thickness")
        validation.check_type(self.axisymmetric, bool, f"{owner}: axisymmetric")
        validation.check_type(self.hold_fallback_area, bool, f"{owner}: hold_fallback_area")
        if self.area_weights not in ("consistent", "ccx"):
            raise ValueError(
                f"{owner}: area_weights must be 'consistent' or 'ccx', got {self.area_weights!r}"
            )
        if self.fallback_area not in FALLBACK_AREAS:
            raise ValueError(
                f"{owner}: fallback_area must be one of {sorted(FALLBACK_AREAS)}, got "
                f"{self.fallback_area!r}"
            )
        if self.axisymmetric and self.thickness != 1.0:
            raise ValueError(
                f"{owner}: an axisymmetric pair has no thickness (its spring areas are rings, "
                f"2 pi r times a length), got thickness = {self.thickness:g}"
            )
        if self.adjust is not None and not isinstance(self.adjust, NodeSurface):
            if isinstance(self.adjust, bool) or not isinstance(self.adjust, (int, float)):
                raise TypeError(
                    f"{owner}: adjust must be a distance >= 0, a NodeSurface or None, got "
                    f"{validation.describe(self.adjust)}"
                )
            if not (np.isfinite(self.adjust) and self.adjust >= 0):
                raise ValueError(
                    f"{owner}: adjust must be a finite distance >= 0, got {self.adjust}"
                )


@dataclass
class PairState:
    """Numbering-level data of a pair and its springs at the current pairing."""

    pair: ContactPair
    slave: SlaveSurface
    master_faces: SurfaceFaces
    master: ContactMaster  # meshed, rigid or exchanged (a patch of it)
    overlap: np.ndarray  # (S,) initial overlap g0 per slave node (docs/method.md §3.5)
    spring_slave: np.ndarray = field(
        default_factory=lambda: np.empty(0, dtype=np.int64)
    )  # index into slave.nodes
    spring_face: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    spring_area: np.ndarray = field(default_factory=lambda: np.empty(0))
    xi: np.ndarray | None = None
    evaluation: SpringEvaluation | None = None
    found_face: np.ndarray | None = None  # face of every slave node at the last pairing, -1: none
    face_changes: int = 0  # slave nodes paired before and after the last pairing, on another face
    friction: FrictionState | None = None  # friction history per slave node (docs/method.md §11.3)
    adjust_nodes: np.ndarray | None = None  # ADJUST node set as slave dofs
    was_active: bool = True  # the pair was active at the previous pairing
    # springs whose fallback area is held (``pair.hold_fallback_area``), and their held areas:
    # None until the first evaluation after the pairing (docs/method.md §38.5)
    held_springs: np.ndarray = field(default_factory=lambda: np.empty(0, dtype=np.int64))
    held_areas: np.ndarray | None = None

    @property
    def num_springs(self) -> int:
        """Number of contact spring elements of this pair."""
        return int(self.spring_slave.size)

    @property
    def element_nodes(self) -> np.ndarray:
        """Spring nodes (N, n+1), the master face's nodes then the slave node."""
        faces = self.master_faces.faces[self.spring_face]
        return np.hstack([faces, self.slave.nodes[self.spring_slave][:, None]])
