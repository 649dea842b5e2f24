"""The role a master surface plays in the pairing: :class:`ContactMaster`.

Three kinds play it: the meshed :class:`~dolfinx_ntf.kernels.search.MasterSurface`, the rigid
:class:`~dolfinx_ntf.kernels.rigid.RigidMaster` (docs/method.md §15.1) and, in parallel, the
exchanged :class:`~dolfinx_ntf.parallel.master_exchange.MasterPatch` (docs/method.md §14.8). The
pairing (``contact/pairing.py``) calls them only through this interface. A new kind of master
surface implements it.
"""

from __future__ import annotations

import typing

import numpy as np

from dolfinx_ntf.kernels.laws import PressureOverclosureLaw
from dolfinx_ntf.kernels.springs import SpringEvaluation
from dolfinx_ntf.kernels.tie_frame import TieFrame

__all__ = ["ContactMaster"]


class ContactMaster(typing.Protocol):
    """A master surface as the pairing uses it: updated, searched, and the springs' evaluator.

    Attributes:
        name: Surface name for messages.
        collective: Whether :meth:`update` and :meth:`surface_moments` are collective calls and
            a search may need the surface enlarged (an exchanged master patch): the pairing then
            synchronizes the processes first (docs/method.md §14.4).
    """

    name: str
    collective: bool

    def update(self, coords: np.ndarray) -> None:
        """Follow the nodes to ``coords`` (N, 3) before a search."""

    def locate(
        self,
        points: np.ndarray,
        tolerances: np.ndarray | float,
        *,
        max_depth: float | None = None,
        start_faces: np.ndarray | None = None,
        tie_frame: TieFrame | None = None,
        ccx_ties: bool = False,
    ) -> np.ndarray:
        """Face holding each point (-1: none), docs/method.md §3.2."""

    def face_patches(self, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``(which, patch)``: the faces around each of ``faces``, reserved in a new matrix."""

    def surface_moments(self) -> tuple[np.ndarray, np.ndarray] | None:
        """``(origin, moments)`` of the surface for the search's tie frame; None: no ties."""

    def evaluate_springs(
        self,
        face_type: object,
        master_coords: np.ndarray,
        slave_coords: np.ndarray,
        areas: np.ndarray,
        law: PressureOverclosureLaw,
        *,
        gap_shift: float | np.ndarray = 0.0,
        xi0: np.ndarray | None = None,
        tangent: bool = True,
        symmetric: bool = False,
        friction: object | None = None,
        interior_projection: bool = False,
        damping: object | None = None,
    ) -> SpringEvaluation:
        """Forces (and tangent) of springs between slave nodes and this surface (§5, §6).

        ``interior_projection``: CalculiX's tangent at projections clamped to a face boundary
        (meshed masters; a rigid master has no face boundary). ``damping``: contact damping
        (``kernels.contact_damping.DampingInput``, docs/method.md §29; 3D meshed masters only).
        """
