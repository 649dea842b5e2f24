"""A pair's springs evaluated at the current displacement, as blocks to assemble (§5, §6, §11).

:func:`evaluate_pair` evaluates the springs of one :class:`~dolfinx_ntf.contact.pair.PairState`
(forces, tangent, friction) through its master surface and stores the results in the state (the
projection points and the friction trial state carry over to the next evaluation);
:func:`area_block` is the tangent of the spring areas when they follow the deformation.
"""

from __future__ import annotations

import numpy as np

from dolfinx_ntf.contact.assembly import SpringBlocks
from dolfinx_ntf.contact.pair import PairState
from dolfinx_ntf.contact.pairing import slave_areas
from dolfinx_ntf.kernels.contact_damping import DampingInput
from dolfinx_ntf.kernels.edges import EdgeType, edge_spring_area_gradients
from dolfinx_ntf.kernels.friction import FrictionInput
from dolfinx_ntf.kernels.laws import PressureOverclosureLaw
from dolfinx_ntf.kernels.spring_areas import spring_area_gradients

__all__ = ["area_block", "evaluate_pair"]


def evaluate_pair(
    state: PairState,
    coords: np.ndarray,
    law: PressureOverclosureLaw,
    *,
    reference: np.ndarray,
    gap_shift: np.ndarray | float,
    tangent: bool,
    symmetric: bool,
    linearize_area: bool,
    friction_in_tension: bool,
    friction_tangent: str,
    projection_tangent: str = "exact",
    velocities: np.ndarray | None = None,
    velocity_rate: float = 0.0,
    force_stick: bool = False,
) -> list[SpringBlocks]:
    """Evaluate the springs of one pair at ``coords``; returns the blocks to assemble.

    Args:
        state: The pair's state at the current pairing (updated: evaluation, projection points,
            friction trial state, and the areas with ``linearize_area``).
        coords: (N, 3) current node coordinates.
        law: The law whose slope the tangent takes.
        reference: (N, 3) reference node coordinates (friction works on displacements).
        gap_shift: The springs' ramped initial overlap (docs/method.md §3.5).
        tangent: Also the tangent (else forces only).
        symmetric: Symmetrize the spring matrices.
        linearize_area: Areas follow the deformation, with their derivative in the tangent.
        friction_in_tension: Friction also where the law gives tension.
        friction_tangent: ``"consistent"`` or ``"ccx"`` (docs/method.md §11.2).
        projection_tangent: ``"exact"`` or ``"ccx"`` (the interior-projection formula also at
            projections clamped to the face boundary, docs/method.md §6.1).
        velocities: (N, 3) node velocities (a dynamic step's): the pair's contact damping acts
            (docs/method.md §29); None: no damping (static steps).
        velocity_rate: ``dv/du`` of ``velocities`` (the damping's tangent).
        force_stick: The friction force and state stick whatever the trial force (the tangent:
            :class:`~dolfinx_ntf.kernels.friction.FrictionInput`; docs/method.md §33.4).
    """
    nodes = state.element_nodes
    friction = _friction_input(
        state, coords, nodes, reference, friction_in_tension, friction_tangent, force_stick
    )
    if linearize_area:  # areas follow the deformation between pairings too
        areas = slave_areas(state.slave, coords)
        state.spring_area = areas[state.spring_slave]
    areas = state.spring_area
    held = state.held_springs
    if held.size and state.held_areas is not None:  # ccx's fallback areas, held (§38.5)
        areas = areas.copy()
        areas[held] = state.held_areas
    ev = state.master.evaluate_springs(
        state.master_faces.face_type,
        coords[nodes[:, :-1]],
        coords[nodes[:, -1]],
        areas,
        law,
        gap_shift=gap_shift,
        xi0=state.xi,
        tangent=tangent,
        symmetric=symmetric,
        friction=friction,
        **({"interior_projection": True} if projection_tangent == "ccx" else {}),
        **_damping_input(state, nodes, velocities, velocity_rate),
    )
    state.evaluation = ev
    state.xi = ev.xi
    if held.size and state.held_areas is None:  # the first evaluation after the pairing
        state.held_areas = np.array(ev.area[held], dtype=float)
    if ev.tangential is not None:
        tf = ev.tangential
        state.friction.store(state.spring_slave, tf.a, tf.t, tf.slip)
    blocks = [
        SpringBlocks(
            nodes,
            nodes,
            ev.stiffness,
            ev.forces.reshape(nodes.shape[0], ev.forces.shape[-1] * nodes.shape[1]),
        )
    ]
    if tangent and linearize_area:
        blocks.append(area_block(state, coords))
    return blocks


def _damping_input(
    state: PairState, nodes: np.ndarray, velocities: np.ndarray | None, rate: float
) -> dict[str, DampingInput]:
    """``{"damping": ...}`` for a damped pair with velocities, else ``{}``."""
    damping = state.pair.interaction.damping
    if damping is None or velocities is None:
        return {}
    return {
        "damping": DampingInput(
            velocities[nodes], rate, damping.coefficient, damping.tangent_fraction
        )
    }


def _friction_input(
    state: PairState,
    coords: np.ndarray,
    nodes: np.ndarray,
    reference: np.ndarray,
    in_tension: bool,
    tangent_mode: str,
    force_stick: bool = False,
) -> FrictionInput | None:
    """Friction state and parameters of the pair's springs, None without friction."""
    friction = state.pair.interaction.friction
    if friction is None:
        return None
    displacements = (coords - reference)[nodes]
    return FrictionInput(
        displacements,
        *state.friction.start_values(state.spring_slave),
        mu=friction.mu,
        stick_slope=friction.stick_slope,
        in_tension=in_tension,
        tangent_mode=tangent_mode,
        force_stick=force_stick,
    )


def area_block(state: PairState, coords: np.ndarray, *, values: bool = True) -> SpringBlocks:
    """Tangent of F_N = A_p p(d) with respect to the slave-face nodes around p (dA_p/du).

    With ``values=False`` only the couplings (for the matrix pattern).
    """
    faces, slave = state.slave.faces, state.slave
    if isinstance(faces.face_type, EdgeType):  # 2D: lengths or rings (§17.2)
        slave_index, node, gradient = edge_spring_area_gradients(
            faces.face_type, faces.faces, coords, slave.nodes,
            thickness=slave.thickness, axisymmetric=slave.axisymmetric,
        )  # fmt: skip
    else:  # every face type's (a C3D15 surface of triangles and quadrilaterals, §38)
        parts = [
            spring_area_gradients(group.face_type, group.faces, coords, slave.nodes)
            for group in slave.face_groups
        ]
        slave_index, node, gradient = (np.concatenate(arrays) for arrays in zip(*parts))
    spring_of_slave = np.full(state.slave.nodes.size, -1, dtype=np.int64)
    spring_of_slave[state.spring_slave] = np.arange(state.num_springs)
    spring = spring_of_slave[slave_index]
    keep = spring >= 0
    if state.slave.faceless is not None:  # no face area: the fallback, not dA/du
        keep &= ~state.slave.faceless[slave_index]
    spring, node, gradient = spring[keep], node[keep], gradient[keep]
    block_values = None
    if values:
        per_area = state.evaluation.force_per_area.reshape(
            state.num_springs, gradient.shape[1] * state.element_nodes.shape[1]
        )[spring]
        block_values = per_area[:, :, None] * gradient[:, None, :]
    return SpringBlocks(state.element_nodes[spring], node[:, None].astype(np.int64), block_values)
