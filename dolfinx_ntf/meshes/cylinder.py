"""Plane-strain Hertz contact: a cylinder touching a block along a line, as a 2D gmsh model.

The section of the cylinder of radius R centred at ``(0, R)`` touches the block top ``y = 0`` at
the origin. The half model keeps ``x >= 0``: the cylinder's part is the quarter disc below its
centre, closed by its flat top ``y = R`` (where the load goes), the block is
``[0, W] x [-W, 0]`` (``W = block * R``), and the line ``x = 0`` is a symmetry line of both
bodies. The bodies share no nodes.

The triangles have the size ``size_fine`` within ``refine_distance`` of the contact point and grow
to ``size_coarse`` at ``coarse_distance`` (gmsh Distance + Threshold fields); ``order=2`` gives
6-node triangles with curved edges on the arc.

:func:`build_two_cylinders` meshes the same upper cylinder on a second one (radius
``lower_radius``, centred at ``(0, -lower_radius)``) instead of the block: its quarter disc above
its centre takes the block's tags (its arc is ``BLOCK_TOP``, its flat bottom
``y = -lower_radius`` is ``BLOCK_BOTTOM``).

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
    "build_two_cylinders",
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
# A size field's band edge off y = 0 (in radii): at the contact point both fine sizes apply.
_BAND_EDGE = 1e-9
_FAR = 1e30


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
    _mesh_graded([(points, size_fine, None)], size_coarse, refine_distance, coarse_distance, order)


def build_two_cylinders(
    *,
    radius: float = 1.0,
    lower_radius: float = 2.0,
    size_fine: float = 0.005,
    size_coarse: float | None = None,
    refine_distance: float | None = None,
    coarse_distance: float | None = None,
    order: int = 1,
    lower_size_fine: float | None = None,
) -> None:
    """Mesh the half model (x >= 0) of a cylinder section on a second cylinder's in a new model.

    The upper cylinder is :func:`build_cylinder_on_block`'s; the lower one, of radius
    ``lower_radius`` and centred at ``(0, -lower_radius)``, is the quarter disc above its centre:
    its arc (``BLOCK_TOP``) touches the upper arc at the origin and its flat bottom
    (``BLOCK_BOTTOM``) is held. Hertz's line contact of the two has ``1/R = 1/R1 + 1/R2``.

    Args:
        radius: The upper cylinder's radius R1.
        lower_radius: The lower cylinder's radius R2.
        size_fine: Element size at the contact point.
        size_coarse: Element size far from it (default ``0.3 R1``).
        refine_distance: Distance from the contact point within which the size is ``size_fine``
            (default ``0.125 R1``).
        coarse_distance: Distance from which the size is ``size_coarse`` (default ``1.5 R1``).
        order: 1 (3-node triangles) or 2 (6-node triangles).
        lower_size_fine: The lower cylinder's element size at the contact point (default
            ``size_fine``). With equal sizes the two arcs' nodes face each other, so every slave
            node lies over a vertex of the master polygon, where its normal jumps (see
            docs/guide/two_d.md).

    Raises:
        ValueError: A radius or a size is not positive, or ``order`` is not 1 or 2.
    """
    lower_size_fine = size_fine if lower_size_fine is None else lower_size_fine
    for value, what in (
        (radius, "radius"),
        (lower_radius, "lower_radius"),
        (size_fine, "size_fine"),
        (lower_size_fine, "lower_size_fine"),
    ):
        if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
            raise ValueError(f"build_two_cylinders: {what} must be positive, got {value!r}")
    if order not in (1, 2):
        raise ValueError(f"build_two_cylinders: order must be 1 or 2, got {order!r}")
    r1, r2 = float(radius), float(lower_radius)
    gmsh.model.add("two_cylinders")
    g = gmsh.model.geo
    model = gmsh.model
    discs, arcs, flats, axes, contact_points = [], [], [], [], []
    for centre_y, r in ((r1, r1), (-r2, r2)):  # upper, then lower: arc from the contact point
        touch, rim, centre = (
            g.addPoint(0, 0, 0),
            g.addPoint(r, centre_y, 0),
            g.addPoint(0, centre_y, 0),
        )
        arc, flat, axis = (
            g.addCircleArc(touch, centre, rim),
            g.addLine(rim, centre),
            g.addLine(centre, touch),
        )
        discs.append(g.addPlaneSurface([g.addCurveLoop([arc, flat, axis])]))
        arcs.append(arc)
        flats.append(flat)
        axes.append(axis)
        contact_points.append(touch)
    g.synchronize()
    model.addPhysicalGroup(2, [discs[0]], CYLINDER)
    model.addPhysicalGroup(1, [arcs[0]], CYLINDER_CONTACT)
    model.addPhysicalGroup(1, [flats[0]], CYLINDER_TOP)
    model.addPhysicalGroup(2, [discs[1]], BLOCK)
    model.addPhysicalGroup(1, [arcs[1]], BLOCK_TOP)
    model.addPhysicalGroup(1, [flats[1]], BLOCK_BOTTOM)
    model.addPhysicalGroup(1, axes, SYMMETRY)
    _mesh_graded(
        [
            ([contact_points[0]], size_fine, (_BAND_EDGE * r1, math.inf)),
            ([contact_points[1]], lower_size_fine, (-math.inf, -_BAND_EDGE * r1)),
        ],
        0.3 * r1 if size_coarse is None else size_coarse,
        0.125 * r1 if refine_distance is None else refine_distance,
        1.5 * r1 if coarse_distance is None else coarse_distance,
        order,
    )


def _mesh_graded(
    refinements: list[tuple[list[int], float, tuple[float, float] | None]],
    size_coarse: float,
    refine_distance: float,
    coarse_distance: float,
    order: int,
) -> None:
    """Mesh the model with triangles graded from fine sizes near points to ``size_coarse``.

    ``refinements``: ``(points, size_fine, band)``: the size near the points, only where
    ``band[0] < y < band[1]`` (``None``: everywhere); the finest size applies where several do.
    """
    model = gmsh.model
    field = model.mesh.field
    sizes = []
    for points, size_fine, band in refinements:
        distance = field.add("Distance")
        field.setNumbers(distance, "PointsList", points)
        threshold = field.add("Threshold")
        field.setNumber(threshold, "InField", distance)
        field.setNumber(threshold, "SizeMin", size_fine)
        field.setNumber(threshold, "SizeMax", size_coarse)
        field.setNumber(threshold, "DistMin", refine_distance)
        field.setNumber(threshold, "DistMax", coarse_distance)
        if band is not None:  # size_coarse outside the band (a Box field, as gmsh 4.8 has it)
            outside = field.add("Box")
            for key, value in (
                ("VIn", 0.0),
                ("VOut", size_coarse),
                ("XMin", -_FAR),
                ("XMax", _FAR),
                ("YMin", band[0]),
                ("YMax", band[1]),
                ("ZMin", -_FAR),
                ("ZMax", _FAR),
            ):
                field.setNumber(outside, key, value)
            banded = field.add("Max")
            field.setNumbers(banded, "FieldsList", [threshold, outside])
            threshold = banded
        sizes.append(threshold)
    if len(sizes) > 1:
        finest = field.add("Min")
        field.setNumbers(finest, "FieldsList", sizes)
        sizes = [finest]
    field.setAsBackgroundMesh(sizes[0])
    for option in ("MeshSizeExtendFromBoundary", "MeshSizeFromPoints", "MeshSizeFromCurvature"):
        gmsh.option.setNumber(f"Mesh.{option}", 0)
    model.mesh.generate(2)
    model.mesh.setOrder(order)
