"""Plane-strain Hertz contact: a cylinder touching a block along a line, as a 2D gmsh model.

The section of the cylinder of radius R centred at ``(0, R)`` touches the block top ``y = 0`` at
the origin. The half model keeps ``x >= 0``: the cylinder's part is the quarter disc below its
centre, closed by its flat top ``y = R`` (where the load goes), the block is
``[0, W] x [-W, 0]`` (``W = block * R``), and the line ``x = 0`` is a symmetry line of both
bodies. The bodies share no nodes.

The triangles have the size ``size_fine`` within ``refine_distance`` of the contact point and grow
to ``size_coarse`` at ``coarse_distance`` (gmsh Distance + Threshold fields); ``order=2`` gives
6-node triangles with curved edges on the arc.

Builders talk to gmsh only: call them on one MPI rank with gmsh initialized (or through
:func:`~dolfinx_ntf.meshes.gmsh_io.mesh_from_gmsh` with ``gdim=2``).
"""

from __future__ import annotations

import math

import gmsh

__all__ = [
    "BLOCK",
    "BLOCK_BOTTOM",
    "BLOCK_TOP",
    "CYLINDER",
    "CYLINDER_CONTACT",
    "CYLINDER_TOP",
    "SYMMETRY",
    "build_cylinder_on_block",
]

# Physical groups (cell tags).
BLOCK = 1
CYLINDER = 2
# Physical groups (facet tags: edges).
BLOCK_BOTTOM = 11  # held
BLOCK_TOP = 12  # contact master
CYLINDER_CONTACT = 13  # contact slave: the arc
CYLINDER_TOP = 14  # flat top y = R: the load
SYMMETRY = 21  # x = 0, both bodies: u_x = 0


def build_cylinder_on_block(
    *,
    radius: float = 1.0,
    block: float = 4.0,
    size_fine: float = 0.005,
    size_coarse: float | None = None,
    refine_distance: float | None = None,
    coarse_distance: float | None = None,
    order: int = 1,
    bodies: str = "both",
) -> None:
    """Mesh the half model (x >= 0) of a cylinder section on a block in a new gmsh model.

    Args:
        radius: The cylinder's radius R.
        block: The block's width and depth in radii.
        size_fine: Element size at the contact point.
        size_coarse: Element size far from it (default ``0.3 R``).
        refine_distance: Distance from the contact point within which the size is ``size_fine``
            (default ``0.125 R``).
        coarse_distance: Distance from which the size is ``size_coarse`` (default ``1.5 R``).
        order: 1 (3-node triangles) or 2 (6-node triangles).
        bodies: ``"both"``, or ``"cylinder"`` or ``"block"`` alone (against a rigid master:
            a rigid line under the cylinder, a rigid circle on the block); the groups of the
            missing body are left out.

    Raises:
        ValueError: A size, the radius or the block is not positive, ``order`` is not 1 or 2, or
            ``bodies`` is none of the three.
    """
    for value, what in ((radius, "radius"), (block, "block"), (size_fine, "size_fine")):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"build_cylinder_on_block: {what} must be positive, got {value!r}")
    if order not in (1, 2):
        raise ValueError(f"build_cylinder_on_block: order must be 1 or 2, got {order!r}")
    if bodies not in ("both", "cylinder", "block"):
        raise ValueError(
            f"build_cylinder_on_block: bodies must be 'both', 'cylinder' or 'block', got {bodies!r}"
        )
    with_block, with_cylinder = bodies != "cylinder", bodies != "block"
    r, w = float(radius), float(block) * radius
    size_coarse = 0.3 * r if size_coarse is None else size_coarse
    refine_distance = 0.125 * r if refine_distance is None else refine_distance
    coarse_distance = 1.5 * r if coarse_distance is None else coarse_distance
    gmsh.model.add("cylinder_on_block")
    g = gmsh.model.geo
    model = gmsh.model
    points, symmetry = [], []
    if with_block:
        p = [g.addPoint(x, y, 0) for x, y in ((0, -w), (w, -w), (w, 0), (0, 0))]
        edges = [g.addLine(p[i], p[(i + 1) % 4]) for i in range(4)]  # bottom, right, top, axis
        lower = g.addPlaneSurface([g.addCurveLoop(edges)])
        points.append(p[3])
        symmetry.append(edges[3])
    if with_cylinder:
        bottom, right, centre = g.addPoint(0, 0, 0), g.addPoint(r, r, 0), g.addPoint(0, r, 0)
        arc, top, axis = (
            g.addCircleArc(bottom, centre, right),
            g.addLine(right, centre),
            g.addLine(centre, bottom),
        )
        upper = g.addPlaneSurface([g.addCurveLoop([arc, top, axis])])
        points.append(bottom)
        symmetry.append(axis)
    g.synchronize()
    if with_block:
        model.addPhysicalGroup(2, [lower], BLOCK)
        model.addPhysicalGroup(1, [edges[0]], BLOCK_BOTTOM)
        model.addPhysicalGroup(1, [edges[2]], BLOCK_TOP)
    if with_cylinder:
        model.addPhysicalGroup(2, [upper], CYLINDER)
        model.addPhysicalGroup(1, [arc], CYLINDER_CONTACT)
        model.addPhysicalGroup(1, [top], CYLINDER_TOP)
    model.addPhysicalGroup(1, symmetry, SYMMETRY)
    field = model.mesh.field
    distance = field.add("Distance")
    field.setNumbers(distance, "PointsList", points)
    threshold = field.add("Threshold")
    field.setNumber(threshold, "InField", distance)
    field.setNumber(threshold, "SizeMin", size_fine)
    field.setNumber(threshold, "SizeMax", size_coarse)
    field.setNumber(threshold, "DistMin", refine_distance)
    field.setNumber(threshold, "DistMax", coarse_distance)
    field.setAsBackgroundMesh(threshold)
    for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{option}", 0)
    model.mesh.generate(2)
    model.mesh.setOrder(order)
