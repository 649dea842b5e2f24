"""Measures of a contact solution, the same for every formulation (docs/method.md §15.4).

Every measure here reads only what all formulations have: the displacement, the bulk residual form,
and the recovered contact pressure ``p_h`` on the contact boundary
(:class:`~dolfinx_ntf.fem.pressure_recovery.BoundaryPressure`):

- reaction on a set of facets: the assembled bulk residual summed over their dofs;
- contact area: ``∫ [p_h > 0] ds``;
- contact radius three ways: a least-squares fit of Hertz's profile to the nodal ``p_h``, the radius
  of a disc of the contact area, and the pair of nodes that brackets the edge (last with
  ``p_h > 0``, first beyond it without);
- peak pressure two ways: the fit's ``p0`` and the largest nodal ``p_h``;
- largest penetration of the contact nodes into a rigid surface;
- Newton iterations per increment and the time split (recorded by the drivers).
"""

from __future__ import annotations

import math

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np
import scipy.optimize

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.kernels.rigid import RigidSurface

__all__ = [
    "bracketing_radius",
    "contact_area",
    "facet_reaction",
    "fit_hertz_profile",
    "largest_penetration",
    "radius_from_area",
]


def facet_reaction(
    residual: ufl.Form, u: dolfinx.fem.Function, facet_tags: compat.MeshTags, tag: int
) -> np.ndarray:
    """``(d,)`` sum of the assembled residual (no Dirichlet conditions) over the dofs of facets.

    At prescribed dofs this is the force the support exerts on the body. Collective.

    Args:
        residual: The residual form whose assembled vector holds the nodal forces (e.g. the bulk
            residual, or bulk plus contact where the facets carry contact too).
        u: The displacement (its space locates the facets' dofs).
        facet_tags: Facet tags.
        tag: The tag of the facets.

    Returns:
        The summed force components (``d`` = 3, or 2 on a 2D mesh), the same on every process.
    """
    V = u.function_space
    form = dolfinx.fem.form(residual)
    b = dolfinx.fem.petsc.assemble_vector(form)
    b.ghostUpdate(addv=PETSc.InsertMode.ADD, mode=PETSc.ScatterMode.REVERSE)
    fdim = V.mesh.topology.dim - 1
    nodes = dolfinx.fem.locate_dofs_topological(V, fdim, facet_tags.find(tag))
    nodes = nodes[nodes < V.dofmap.index_map.size_local]
    local = b.array.reshape(-1, V.dofmap.index_map_bs)[nodes].sum(axis=0)
    b.destroy()
    return V.mesh.comm.allreduce(local, op=MPI.SUM)


def contact_area(pressure: dolfinx.fem.Function, ds: ufl.Measure, degree: int = 8) -> float:
    """``∫ [p_h > 0] ds``: the area where the recovered pressure is positive. Collective.

    Args:
        pressure: The recovered pressure ``p_h`` (``pressure`` of a
            :class:`~dolfinx_ntf.BoundaryPressure`).
        ds: Measure of the contact boundary.
        degree: Quadrature degree of the indicator (discontinuous inside the facets at the edge).
    """
    mesh = pressure.function_space.mesh
    indicator = ufl.conditional(ufl.gt(pressure, 0.0), 1.0, 0.0)
    measure = ds(metadata={"quadrature_degree": degree})
    value = dolfinx.fem.assemble_scalar(dolfinx.fem.form(indicator * measure))
    return float(mesh.comm.allreduce(value, op=MPI.SUM))


def fit_hertz_profile(r: np.ndarray, p: np.ndarray, a0: float, p0: float) -> tuple[float, float]:
    """Least-squares fit of ``p0 sqrt(1 - r^2/a^2)`` to nodal pressures within ``1.5 a0``.

    Hertz's profile: ``r`` is the radius of a point contact or the distance ``|x|`` from the
    centre line of a line contact (same form).

    Args:
        r: ``(N,)`` distance of each slave node from the contact centre (reference positions).
        p: ``(N,)`` contact pressure at the nodes, 0 where a node has no spring.
        a0: Starting guess of the contact radius (half-width), e.g. Hertz's; only nodes with
            ``r < 1.5 a0`` take part.
        p0: Starting guess of the peak pressure.

    Returns:
        ``(a, p0)``: the fitted contact radius and peak pressure.
    """
    near = r < 1.5 * a0
    r, p = r[near], p[near]

    def residual(params: np.ndarray) -> np.ndarray:
        a, peak = params
        return peak * np.sqrt(np.clip(1 - (r / a) ** 2, 0, None)) - p

    fit = scipy.optimize.least_squares(residual, x0=[a0, p0], x_scale=[a0, p0])
    return float(fit.x[0]), float(fit.x[1])


def radius_from_area(area: float, fraction: float = 1.0) -> float:
    """Radius of a disc whose ``fraction`` (1/4 for a quarter model) has the area ``area``.

    Args:
        area: The contact area of the model.
        fraction: The part of the disc the model holds (1/4 for a quarter model).
    """
    return math.sqrt(area / (fraction * math.pi))


def bracketing_radius(r: np.ndarray, p: np.ndarray, threshold: float = 0.0) -> tuple[float, float]:
    """``(last r with p > threshold, first larger r with p <= threshold)`` (nan if none).

    The contact edge lies between the two: a bracket that needs no fit.

    Args:
        r: ``(N,)`` distance of each node from the contact centre.
        p: ``(N,)`` pressure at the nodes.
        threshold: Pressures above it count as closed.
    """
    closed = p > threshold
    if not closed.any():
        return math.nan, math.nan
    last = float(r[closed].max())
    beyond = ~closed & (r > last)
    return last, float(r[beyond].min()) if beyond.any() else math.nan


def largest_penetration(surface: RigidSurface, positions: np.ndarray, time: float = 0.0) -> float:
    """Largest depth of the points below the rigid surface (0 if none penetrates).

    Args:
        surface: The rigid surface.
        positions: ``(N, 3)`` current positions of the points (e.g. contact nodes, ``X + u``).
        time: Relative step time of the surface's position.
    """
    if positions.shape[0] == 0:
        return 0.0
    return float(max(0.0, -surface.distance(positions, time).min()))
