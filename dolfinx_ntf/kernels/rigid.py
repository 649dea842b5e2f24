"""Rigid analytical master surfaces and their one-node springs (docs/method.md §15.1).

A rigid master is a surface given by a signed distance ``phi(x)`` (positive on the side of the
slave body, i.e. outside the rigid body), its unit normal ``n = grad phi`` and the Hessian
``H = grad grad phi``, optionally translated by a prescribed motion ``c(t)``: the surface at step
time ``t`` is ``{x : phi(x - c(t)) = 0}``. Each slave node p with spring area ``A_p`` gets a spring
of one node (the master has no nodes):

- clearance ``g = phi(x_p - c)``, overclosure ``d = -(g - gap_shift)``,
  ``F_N = law.spring_force(d, A)``;
- internal force on the slave node ``f_p = -F_N n``;
- tangent ``df_p/dx_p = F_N'(d) n (x) n - F_N H`` (symmetric), with the area held constant.

Everything here is pure numpy. :class:`RigidMaster` adapts a surface to the interface
:class:`~dolfinx_ntf.ContactProblem` uses for meshed masters (``locate``, ``update``,
``face_patches`` and a spring evaluator), so that the same pairing schedule, laws, spring areas and
outputs apply unchanged.
"""

from __future__ import annotations

import abc
import dataclasses
import typing

import numpy as np
import numpy.typing as npt

from dolfinx_ntf.kernels.laws import PressureOverclosureLaw
from dolfinx_ntf.kernels.springs import SpringEvaluation

__all__ = [
    "RigidCylinder",
    "RigidMaster",
    "RigidPlane",
    "RigidSphere",
    "RigidSurface",
    "SignedDistanceSurface",
    "check_in_plane",
    "evaluate_rigid_springs",
    "in_plane",
    "rigid_master",
]

Motion = typing.Callable[[float], npt.ArrayLike]


def _vector(value: npt.ArrayLike, what: str, *, unit: bool = False) -> np.ndarray:
    """A finite 3-vector (normalized if ``unit``) or a ValueError naming it."""
    v = np.asarray(value, dtype=float)
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{what} must be 3 finite numbers, got {value!r}")
    if unit:
        length = np.linalg.norm(v)
        if not length > 0.0:
            raise ValueError(f"{what} must not be zero")
        v = v / length
    return v


def _positive(value: float, what: str) -> float:
    value = float(value)
    if not (np.isfinite(value) and value > 0.0):
        raise ValueError(f"{what} must be a positive number, got {value!r}")
    return value


def _points(x: npt.ArrayLike) -> np.ndarray:
    points = np.asarray(x, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise ValueError(f"points must have shape (N, 3), got {points.shape}")
    return points


class RigidSurface(abc.ABC):
    """A rigid surface: signed distance, unit normal and Hessian, optionally moving.

    Args:
        motion: Translation ``c(t)`` of the surface at relative step time ``t`` (the time at the
            end of the current increment, 0..1); ``None`` keeps it fixed. Set a new motion between
            steps, or move :attr:`offset` from a load callback.
    """

    def __init__(self, motion: Motion | None = None) -> None:
        if motion is not None and not callable(motion):
            raise TypeError(f"motion must be a callable c(t) or None, got {motion!r}")
        self.motion = motion
        #: Constant translation added to the motion (e.g. set from a StaticStep load callback).
        self.offset = np.zeros(3)

    def translation(self, time: float = 0.0) -> np.ndarray:
        """The surface's translation at relative step time ``time``."""
        c = np.asarray(self.offset, dtype=float).copy()
        if self.motion is not None:
            c = c + _vector(self.motion(float(time)), f"{type(self).__name__}.motion({time})")
        return c

    def distance(self, x: npt.ArrayLike, time: float = 0.0) -> np.ndarray:
        """Signed distance of points ``x`` (N, 3) at step ``time``, positive outside the body."""
        return self._distance(_points(x) - self.translation(time))

    def normal(self, x: npt.ArrayLike, time: float = 0.0) -> np.ndarray:
        """Unit normal (N, 3) at points ``x`` at step ``time``: the signed distance's gradient."""
        return self._normal(_points(x) - self.translation(time))

    def hessian(self, x: npt.ArrayLike, time: float = 0.0) -> np.ndarray:
        """Derivative of the normal (N, 3, 3) at ``x`` and step ``time``: the distance's Hessian."""
        return self._hessian(_points(x) - self.translation(time))

    @abc.abstractmethod
    def _distance(self, y: np.ndarray) -> np.ndarray: ...

    @abc.abstractmethod
    def _normal(self, y: np.ndarray) -> np.ndarray: ...

    @abc.abstractmethod
    def _hessian(self, y: np.ndarray) -> np.ndarray: ...


class RigidPlane(RigidSurface):
    """The plane through ``point`` with unit ``normal`` pointing towards the slave body.

    ``motion``, if given, translates the plane by ``motion(t)`` at relative step time ``t``.
    """

    def __init__(
        self, point: npt.ArrayLike, normal: npt.ArrayLike, motion: Motion | None = None
    ) -> None:
        super().__init__(motion)
        self.point = _vector(point, "RigidPlane: point")
        self.unit_normal = _vector(normal, "RigidPlane: normal", unit=True)

    def _distance(self, y: np.ndarray) -> np.ndarray:
        return (y - self.point) @ self.unit_normal

    def _normal(self, y: np.ndarray) -> np.ndarray:
        return np.broadcast_to(self.unit_normal, y.shape).copy()

    def _hessian(self, y: np.ndarray) -> np.ndarray:
        return np.zeros((y.shape[0], 3, 3))


def _radial(y: np.ndarray, what: str) -> tuple[np.ndarray, np.ndarray]:
    """Lengths and unit directions of the vectors y (a ValueError at zero length)."""
    length = np.linalg.norm(y, axis=1)
    bad = np.flatnonzero(~(length > 0.0))
    if bad.size:
        raise ValueError(
            f"{what}: the normal is undefined at points {bad[:10].tolist()} (on the axis)"
        )
    return length, y / length[:, None]


class RigidSphere(RigidSurface):
    """A sphere of ``radius`` around ``center``.

    The slave body is outside the sphere (a rigid ball), or inside it with ``inside=True`` (a
    spherical cup). ``motion``, if given, translates the sphere by ``motion(t)`` at step time ``t``.
    """

    def __init__(
        self,
        center: npt.ArrayLike,
        radius: float,
        *,
        inside: bool = False,
        motion: Motion | None = None,
    ) -> None:
        super().__init__(motion)
        self.center = _vector(center, "RigidSphere: center")
        self.radius = _positive(radius, "RigidSphere: radius")
        self.sign = -1.0 if inside else 1.0

    def _distance(self, y: np.ndarray) -> np.ndarray:
        return self.sign * (np.linalg.norm(y - self.center, axis=1) - self.radius)

    def _normal(self, y: np.ndarray) -> np.ndarray:
        return self.sign * _radial(y - self.center, "RigidSphere")[1]

    def _hessian(self, y: np.ndarray) -> np.ndarray:
        length, e = _radial(y - self.center, "RigidSphere")
        projector = np.eye(3) - e[:, :, None] * e[:, None, :]
        return self.sign * projector / length[:, None, None]


class RigidCylinder(RigidSurface):
    """An infinite circular cylinder of ``radius`` around the line through ``point`` along ``axis``.

    The slave body is outside (a rigid roller) or, with ``inside=True``, inside it (a bore).
    ``motion``, if given, translates the cylinder by ``motion(t)`` at step time ``t``.
    """

    def __init__(
        self,
        point: npt.ArrayLike,
        axis: npt.ArrayLike,
        radius: float,
        *,
        inside: bool = False,
        motion: Motion | None = None,
    ) -> None:
        super().__init__(motion)
        self.point = _vector(point, "RigidCylinder: point")
        self.axis = _vector(axis, "RigidCylinder: axis", unit=True)
        self.radius = _positive(radius, "RigidCylinder: radius")
        self.sign = -1.0 if inside else 1.0

    def _radial_part(self, y: np.ndarray) -> np.ndarray:
        r = y - self.point
        return r - (r @ self.axis)[:, None] * self.axis

    def _distance(self, y: np.ndarray) -> np.ndarray:
        return self.sign * (np.linalg.norm(self._radial_part(y), axis=1) - self.radius)

    def _normal(self, y: np.ndarray) -> np.ndarray:
        return self.sign * _radial(self._radial_part(y), "RigidCylinder")[1]

    def _hessian(self, y: np.ndarray) -> np.ndarray:
        length, e = _radial(self._radial_part(y), "RigidCylinder")
        projector = np.eye(3) - np.outer(self.axis, self.axis) - e[:, :, None] * e[:, None, :]
        return self.sign * projector / length[:, None, None]


class SignedDistanceSurface(RigidSurface):
    """Any rigid surface given as numpy callables.

    Args:
        distance: ``phi(y)``: (N, 3) -> (N,) signed distance, positive on the slave side.
        normal: ``grad phi(y)``: (N, 3) -> (N, 3) unit normals.
        hessian: ``grad grad phi(y)``: (N, 3) -> (N, 3, 3); by default central differences of
            ``normal`` with step ``step`` (symmetrized).
        step: Finite-difference step for the Hessian (length units).
        motion: Translation ``c(t)``, see :class:`RigidSurface`.
        ufl_distance: Optional ``phi`` as a function of a UFL vector, for the continuum
            formulations (:mod:`dolfinx_ntf.fem.continuum`); numpy callables cannot enter a form.
    """

    def __init__(
        self,
        distance: typing.Callable[[np.ndarray], npt.ArrayLike],
        normal: typing.Callable[[np.ndarray], npt.ArrayLike],
        hessian: typing.Callable[[np.ndarray], npt.ArrayLike] | None = None,
        *,
        step: float = 1e-6,
        motion: Motion | None = None,
        ufl_distance: typing.Callable[[typing.Any], typing.Any] | None = None,
    ) -> None:
        super().__init__(motion)
        self.ufl_distance = ufl_distance
        for name, f in (("distance", distance), ("normal", normal)):
            if not callable(f):
                raise TypeError(f"SignedDistanceSurface: {name} must be callable, got {f!r}")
        if hessian is not None and not callable(hessian):
            raise TypeError(f"SignedDistanceSurface: hessian must be callable, got {hessian!r}")
        self._phi, self._grad, self._hess = distance, normal, hessian
        self.step = _positive(step, "SignedDistanceSurface: step")

    def _call(self, f: typing.Callable, y: np.ndarray, shape: tuple, what: str) -> np.ndarray:
        value = np.asarray(f(y), dtype=float)
        if value.shape != shape:
            raise ValueError(
                f"SignedDistanceSurface: {what} returned shape {value.shape}, expected {shape}"
            )
        bad = np.flatnonzero(~np.all(np.isfinite(value.reshape(shape[0], -1)), axis=1))
        if bad.size:
            raise ValueError(
                f"SignedDistanceSurface: {what} is not finite at points {bad[:10].tolist()}"
            )
        return value

    def _distance(self, y: np.ndarray) -> np.ndarray:
        return self._call(self._phi, y, (y.shape[0],), "distance")

    def _normal(self, y: np.ndarray) -> np.ndarray:
        return self._call(self._grad, y, y.shape, "normal")

    def _hessian(self, y: np.ndarray) -> np.ndarray:
        shape = (y.shape[0], 3, 3)
        if self._hess is not None:
            return self._call(self._hess, y, shape, "hessian")
        h = np.empty(shape)
        for j in range(3):
            e = np.zeros(3)
            e[j] = self.step
            h[:, :, j] = (self._normal(y + e) - self._normal(y - e)) / (2.0 * self.step)
        return 0.5 * (h + h.transpose(0, 2, 1))


def evaluate_rigid_springs(
    surface: RigidSurface,
    slave_coords: npt.ArrayLike,
    areas: npt.ArrayLike,
    law: PressureOverclosureLaw,
    *,
    gap_shift: float | np.ndarray = 0.0,
    time: float = 0.0,
    tangent: bool = True,
    symmetric: bool = False,
) -> SpringEvaluation:
    """Forces and tangent of N one-node springs against a rigid surface (docs/method.md §15.1).

    The result has the layout of :func:`~dolfinx_ntf.kernels.springs.evaluate_springs` with no
    master nodes: ``forces`` (N, 1, 3), ``stiffness`` (N, 3, 3), ``xi`` zeros (N, 2), ``phi``
    (N, 0).

    Raises:
        ValueError: Wrong shapes, non-finite values, or a zero spring area (a slave node without
            slave faces: rigid masters have no face area to fall back on).
    """
    x = _points(slave_coords)
    num = x.shape[0]
    area = np.asarray(areas, dtype=float)
    if area.shape != (num,):
        raise ValueError(f"areas must have shape ({num},), got {area.shape}")
    zero = np.flatnonzero(~(area > 0.0))
    if zero.size:
        raise ValueError(
            f"rigid master: springs {zero[:10].tolist()} have no spring area (slave nodes without "
            "slave faces); use a face-based slave surface against a rigid master"
        )
    shift = np.broadcast_to(np.asarray(gap_shift, dtype=float), (num,))
    gap = surface.distance(x, time)
    normal = surface.normal(x, time)
    overclosure = -(gap - shift)
    force, dforce = law.spring_force(overclosure, area)
    force = np.asarray(force, dtype=float) * np.ones(num)
    dforce = np.asarray(dforce, dtype=float) * np.ones(num)
    slave_force = -force[:, None] * normal
    stiffness = None
    if tangent:
        stiffness = dforce[:, None, None] * normal[:, :, None] * normal[:, None, :]
        stiffness -= force[:, None, None] * surface.hessian(x, time)
        if symmetric:
            stiffness = 0.5 * (stiffness + stiffness.transpose(0, 2, 1))
    return SpringEvaluation(
        xi=np.zeros((num, 2)),
        phi=np.zeros((num, 0)),
        normal=normal,
        gap=gap,
        overclosure=overclosure,
        normal_force=force,
        area=area,
        forces=slave_force[:, None, :],
        force_per_area=(slave_force / area[:, None])[:, None, :],
        stiffness=stiffness,
    )


class _RigidFaceType:
    """Stands in for a FaceType: a rigid master has one 'face' without nodes."""

    name = "rigid"
    num_nodes = 0
    num_corners = 0
    is_triangle = False
    center = np.zeros(2)


class _RigidFaces:
    """Stands in for SurfaceFaces: one face (index 0) without nodes or facets."""

    face_type = _RigidFaceType()
    faces = np.zeros((1, 0), dtype=np.int64)
    facets = np.zeros(0, dtype=np.int32)
    nodes = np.zeros(0, dtype=np.int64)


def check_in_plane(surface: RigidSurface, what: str) -> None:
    """A rigid surface for a 2D mesh must not depend on z (a line or a circle in the xy-plane).

    Planes, cylinders and spheres are checked by their data; a :class:`SignedDistanceSurface`
    and moving surfaces only by their normal where they are evaluated (:func:`in_plane`).

    Args:
        surface: The rigid surface.
        what: Who uses it, for the message (e.g. ``"pair 1 master"``).

    Raises:
        ValueError: A plane's normal, a cylinder's axis or a sphere's centre leaves the plane.
    """
    tilt = None
    if isinstance(surface, RigidPlane) and surface.unit_normal[2] != 0.0:
        tilt = f"the plane's normal {tuple(surface.unit_normal)} is not in the xy-plane"
    elif isinstance(surface, RigidCylinder) and abs(abs(surface.axis[2]) - 1.0) > 1e-12:
        tilt = f"the cylinder's axis {tuple(surface.axis)} is not along z"
    elif isinstance(surface, RigidSphere) and surface.center[2] != 0.0:
        tilt = f"the sphere's centre {tuple(surface.center)} is not in the plane z = 0"
    if tilt is not None:
        raise ValueError(
            f"{what}: on a 2D mesh a rigid surface must be a line or a circle of the xy-plane: "
            f"{tilt}"
        )


def in_plane(evaluation: SpringEvaluation, points: np.ndarray, name: str) -> SpringEvaluation:
    """The in-plane (x, y) part of rigid springs evaluated at points of a 2D mesh (z = 0).

    The surface must not depend on z there: its normal has no z component (a plane whose normal
    lies in the xy-plane, a cylinder along z, a sphere centred in z = 0, which is a circle in that
    plane); then the forces and the tangent of the 2D springs are the first two rows and columns.

    Raises:
        ValueError: The normal has a z component at some point (the first one named).
    """
    tilt = np.abs(evaluation.normal[:, 2]) if evaluation.normal.size else np.zeros(0)
    bad = np.flatnonzero(tilt > 1e-12)
    if bad.size:
        i = int(bad[np.argmax(tilt[bad])])
        raise ValueError(
            f"{name}: on a 2D mesh a rigid surface must not depend on z, but its normal at the "
            f"slave node ({points[i, 0]:.6g}, {points[i, 1]:.6g}) has the z component "
            f"{evaluation.normal[i, 2]:.3g} (use a RigidPlane with its normal in the xy-plane, a "
            "RigidCylinder along z, or a RigidSphere centred in z = 0)"
        )
    stiffness = evaluation.stiffness
    return dataclasses.replace(
        evaluation,
        xi=evaluation.xi[:, :1],
        normal=evaluation.normal[:, :2].copy(),
        forces=evaluation.forces[..., :2].copy(),
        force_per_area=evaluation.force_per_area[..., :2].copy(),
        stiffness=None if stiffness is None else stiffness[:, :2, :2].copy(),
    )


class RigidMaster:
    """A rigid surface behind the master-surface interface of :class:`~dolfinx_ntf.ContactProblem`.

    Every slave node "finds" the one face 0 unless it lies deeper than ``max_depth``; the spring
    evaluator ignores the (empty) master coordinates and evaluates :func:`evaluate_rigid_springs`
    at the time ``clock()`` (the problem's relative step time). With ``dim=2`` (a 2D mesh) the
    springs keep their in-plane part (:func:`in_plane`).
    """

    def __init__(
        self,
        surface: RigidSurface,
        clock: typing.Callable[[], float],
        name: str = "",
        *,
        dim: int = 3,
    ) -> None:
        if dim not in (2, 3):
            raise ValueError(f"{name}: dim must be 2 or 3, got {dim!r}")
        self.surface = surface
        self.clock = clock
        self.name = name
        self.dim = dim

    #: Searches involve this process only (the :class:`~dolfinx_ntf.kernels.master.ContactMaster`
    #: role).
    collective = False

    def update(self, coords: np.ndarray) -> None:
        """Nothing to update: the surface does not follow the mesh."""

    def locate(
        self,
        points: np.ndarray,
        tolerances: np.ndarray,
        *,
        max_depth: float | None = None,
        start_faces: np.ndarray | None = None,
        ccx_ties: bool = False,
        tie_frame: object | None = None,
    ) -> np.ndarray:
        """Face 0 for every point, -1 where it lies deeper than ``max_depth`` below the surface.

        One face: no ties, so ``ccx_ties`` (docs/method.md §3.6) changes nothing.
        """
        face = np.zeros(points.shape[0], dtype=np.int64)
        if max_depth is not None and points.shape[0]:
            face[self.surface.distance(points, self.clock()) < -max_depth] = -1
        return face

    def surface_moments(self) -> None:
        """One face: no search ties, hence no tie frame."""
        return None

    def face_patches(self, faces: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """No master nodes: nothing to reserve in the matrix."""
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty

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
        """:func:`evaluate_rigid_springs` with the signature of ``evaluate_springs``.

        ``interior_projection`` has no effect: the surface has no face boundary. Contact
        ``damping`` is refused (not supported against a rigid master yet).
        """
        if damping is not None:
            raise NotImplementedError(
                f"{self.name}: contact damping against a rigid analytical master is not supported "
                "yet; use a meshed master (docs/method.md §29)"
            )
        if friction is not None:
            raise NotImplementedError(
                f"{self.name}: friction against a rigid analytical master is not supported yet; "
                "use a meshed master (docs/method.md §15.1)"
            )
        evaluation = evaluate_rigid_springs(
            self.surface,
            slave_coords,
            areas,
            law,
            gap_shift=gap_shift,
            time=self.clock(),
            tangent=tangent,
            symmetric=symmetric,
        )
        if self.dim == 2:
            return in_plane(evaluation, np.asarray(slave_coords), self.name)
        return evaluation


def rigid_master(
    surface: RigidSurface, clock: typing.Callable[[], float], name: str = "", *, dim: int = 3
) -> tuple[_RigidFaces, RigidMaster]:
    """The (faces, master) pair a ContactProblem keeps for a rigid master surface.

    ``dim``: 2 on a 2D mesh (in-plane springs, :func:`in_plane`).
    """
    return _RigidFaces(), RigidMaster(surface, clock, name, dim=dim)
