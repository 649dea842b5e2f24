"""The deck's ``*TIE`` cards as linear constraints on ccx node numbers (docs/method.md §19).

Surface ties (tied contact, §19.1): each slave node within the position tolerance of the master
faces follows its projection point, ``u_s = Σ_i N_i(ξ) u_i``; with ADJUST (ccx's default) it is
first moved there. Slave nodes out of tolerance are left free with a warning, as ccx does (ccx 2.20
lists them in ``jobname_WarnNodeMissTiedContact.nam``).

Cyclic symmetry (``*TIE, CYCLIC SYMMETRY`` with ``*CYCLIC SYMMETRY MODEL``, static, nodal
diameter 0, §19.2): each dependent node is matched with the independent node at the same radius
and axial position, ``u_s = R^T u_m``.

Both are :class:`~dolfinx_ntf.fem.constraints.LinearConstraintBlock` objects on ccx node numbers
(the model builder maps them to the space), with ``drop_prescribed``: a row whose dofs all carry
a ``*BOUNDARY`` (e.g. a tied node on a fixed plane) is dropped.
"""

from __future__ import annotations

import dataclasses
import logging

import numpy as np
from scipy.spatial import cKDTree

from dolfinx_ntf.fem.constraints import LinearConstraintBlock
from dolfinx_ntf.kernels.cyclic_symmetry import ANGLE_CHECK, CyclicMatch, cyclic_rows
from dolfinx_ntf.kernels.faces import face_type_from_num_nodes
from dolfinx_ntf.kernels.search import MasterSurface
from dolfinx_ntf.kernels.surface_tie import default_tolerance, project_on_master, tie_rows

from ..deck import CyclicSymmetry, Deck, Tie, face_nodes, surface_nodes

__all__ = ["tie_constraints"]

logger = logging.getLogger(__name__)

CYCLIC_TOLERANCE_FRACTION = 1e-10
"""ccx's default cyclic tolerance: this fraction of the mean distance between master nodes."""


def tie_constraints(
    deck: Deck, meshed: np.ndarray, *, warn: bool = True
) -> tuple[Deck, list[LinearConstraintBlock]]:
    """The deck with ADJUST's node moves, and its ``*TIE`` constraints on ccx node numbers.

    Args:
        deck: The parsed deck.
        meshed: ``(N,)`` whether each deck node belongs to an element.
        warn: Log the slave nodes left untied (one process of several: rank 0).

    Raises:
        ValueError: a tie on nodes in no element, a nodal master surface of a surface tie,
            cyclic faces that do not match (naming the nodes) or a sector angle other than 2π/N.
        NotImplementedError: cyclic faces whose nodes do not match one to one, nodes on the axis.
    """
    if not deck.ties:
        return deck, []
    coords = np.array(deck.node_coords, dtype=float)
    symmetry = {s.tie: s for s in deck.cyclic_symmetries}
    blocks = []
    for tie in deck.ties:
        if tie.cyclic and tie.name not in symmetry:
            raise ValueError(
                f"{tie.location}: *TIE {tie.name}, CYCLIC SYMMETRY has no *CYCLIC SYMMETRY MODEL"
            )
        slaves = surface_nodes(deck, tie.slave)
        rows = deck.node_index(slaves)
        if not np.all(meshed[rows]):
            node = int(slaves[~meshed[rows]][0])
            raise ValueError(f"{tie.location}: *TIE {tie.name}: node {node} is in no element")
        if tie.cyclic:
            blocks.append(_cyclic(deck, tie, symmetry[tie.name], coords, slaves))
        else:
            blocks.append(_surface_tie(deck, tie, coords, slaves, warn))
    blocks = [b for b in blocks if len(b)]
    return dataclasses.replace(deck, node_coords=coords), blocks


def _surface_tie(
    deck: Deck, tie: Tie, coords: np.ndarray, slaves: np.ndarray, warn: bool
) -> LinearConstraintBlock:
    """Rows of a surface tie; moves the tied slave nodes in ``coords`` with ADJUST."""
    label = f"{tie.location}: *TIE {tie.name}"
    if deck.surfaces[tie.master].type != "ELEMENT":
        raise ValueError(f"{label}: the master surface {tie.master} must consist of element faces")
    faces = deck.node_index(face_nodes(deck, tie.master))
    face_type = face_type_from_num_nodes(faces.shape[1])
    master = MasterSurface(face_type, faces, name=tie.master, coords=coords)
    tolerance = tie.position_tolerance
    if tolerance is None or tolerance < 1e-10:
        tolerance = default_tolerance(face_type, faces, coords)
    rows = deck.node_index(slaves)
    projection = project_on_master(master, coords, coords[rows], tolerance)
    tied = projection.tied
    if warn and not np.all(tied):
        missed = slaves[~tied]
        logger.warning(
            "%s: %d slave node(s) have no master face within the position tolerance %.6g and are "
            "not tied (as ccx): %s%s",
            label,
            missed.size,
            tolerance,
            " ".join(str(n) for n in missed[:20]),
            " ..." if missed.size > 20 else "",
        )
    face_rows = faces[projection.face[tied]]
    # a slave node of its own master face (a shared node) is tied already
    own = np.any(face_rows == rows[tied][:, None], axis=1)
    if tie.adjust:
        coords[rows[tied]] = projection.points[tied]
    nodes, components, coefficients = tie_rows(
        slaves[tied][~own], deck.node_ids[face_rows[~own]], projection.weights[tied][~own]
    )
    return LinearConstraintBlock(
        nodes, components, coefficients, name=f"*TIE {tie.name}", drop_prescribed=True
    )


def _cyclic(
    deck: Deck, tie: Tie, symmetry: CyclicSymmetry, coords: np.ndarray, slaves: np.ndarray
) -> LinearConstraintBlock:
    """Rows of a cyclic symmetry tie (matching nodes only)."""
    label = f"{tie.location}: *TIE {tie.name}, CYCLIC SYMMETRY"
    masters = surface_nodes(deck, tie.master)
    shared = np.intersect1d(slaves, masters)
    if shared.size:
        raise NotImplementedError(
            f"{label}: node {int(shared[0])} is on both cyclic faces (a node on the axis): "
            "not supported yet"
        )
    master_x = coords[deck.node_index(masters)]
    tolerance = tie.position_tolerance
    if tolerance is None or tolerance < 1e-30:
        if masters.size > 1:
            distance, _ = cKDTree(master_x).query(master_x, k=2)
            tolerance = CYCLIC_TOLERANCE_FRACTION * float(distance[:, 1].mean())
        else:
            tolerance = 1e-10
    match = CyclicMatch(
        coords[deck.node_index(slaves)],
        master_x,
        symmetry.point_a,
        symmetry.point_b,
        symmetry.num_sectors,
        tolerance,
    )
    if np.any(match.on_axis):
        node = int(slaves[match.on_axis][0])
        raise NotImplementedError(f"{label}: slave node {node} lies on the axis: not supported yet")
    missing = slaves[match.master < 0]
    if missing.size:
        raise NotImplementedError(
            f"{label}: {missing.size} slave node(s) match no master node within the position "
            f"tolerance {tolerance:.6g} in the radial plane (e.g. node {int(missing[0])}): "
            "cyclic constraints to master faces (non-matching meshes) are not supported yet"
        )
    if symmetry.check and match.angle_error > ANGLE_CHECK:
        raise ValueError(
            f"{symmetry.location}: *CYCLIC SYMMETRY MODEL: the sector angle of the geometry, "
            f"{np.degrees(abs(match.angle)):.6g} degrees, differs from 360/N = "
            f"{np.degrees(match.sector):.6g} degrees (CHECK=NO to accept it)"
        )
    nodes, components, coefficients = cyclic_rows(slaves, masters[match.master], match.rotation)
    return LinearConstraintBlock(
        nodes,
        components,
        coefficients,
        name=f"*TIE {tie.name} (cyclic symmetry)",
        drop_prescribed=True,
    )
