"""Hertz contact: a hemisphere touching a block at one point, as a gmsh model.

The indenter is the lower half of the sphere of radius R centred at ``(0, 0, R)``; its lowest point
touches the block top ``z = 0`` at the origin. Its flat top ``z = R`` takes the load or prescribed
displacement. The quarter model (default) keeps ``x >= 0, y >= 0`` with the symmetry planes
``x = 0`` and ``y = 0`` tagged on both bodies; the block is then ``[0, Lx] x [0, Ly] x [-Lz, 0]``
(full model: ``[-Lx, Lx] x [-Ly, Ly] x [-Lz, 0]``). Sphere and block share no nodes.

The mesh size is ``size_fine`` within ``refine_radius`` of the contact point and grows linearly to
``size_coarse`` at ``coarse_radius`` (gmsh MathEval distance + Threshold fields). Tetrahedra come
from the unstructured mesher; hexahedra from splitting each tetrahedron into four (gmsh
subdivision), with the tetrahedral sizes doubled so that hexahedral edges keep the requested sizes.

:func:`build_hertz_axisymmetric` meshes the meridian section of the same model in 2D
(``x = r``, ``y = z``): a quarter disc on a rectangle, for axisymmetric contact
(``ContactPair(..., axisymmetric=True)``), with the same tags (``SYMMETRY_X`` is the axis).

Builders talk to gmsh only: call them on one MPI rank with gmsh initialized. Run as a script to
write ``hertz.msh``::

    python -m dolfinx_ntf.meshes.hertz           # ~27k P1 dofs (tetrahedra)
    python -m dolfinx_ntf.meshes.hertz --coarse  # ~3.4k P1 dofs (tetrahedra), for tests
"""

from __future__ import annotations

import argparse
import math
import typing
from collections.abc import Sequence
from pathlib import Path

import gmsh

from dolfinx_ntf.meshes.gmsh_io import gmsh_session, write_msh

__all__ = [
    "BLOCK",
    "BLOCK_BOTTOM",
    "BLOCK_TOP",
    "COARSE",
    "PHYSICAL_NAMES",
    "SPHERE",
    "SPHERE_CONTACT",
    "SPHERE_TOP",
    "SYMMETRY_X",
    "SYMMETRY_Y",
    "build_hertz",
    "build_hertz_axisymmetric",
    "build_hertz_sphere",
    "main",
]

# Physical groups (cell tags).
BLOCK = 1
SPHERE = 2
# Physical groups (facet tags).
BLOCK_BOTTOM = 11  # clamped
BLOCK_TOP = 12  # contact master
SPHERE_CONTACT = 13  # contact slave: the curved lower half-sphere surface
SPHERE_TOP = 14  # flat face z = R: load or prescribed displacement
SYMMETRY_X = 21  # plane x = 0, both bodies (quarter model only): u_x = 0
SYMMETRY_Y = 22  # plane y = 0, both bodies (quarter model only): u_y = 0

PHYSICAL_NAMES: dict[int, str] = {
    BLOCK: "block",
    SPHERE: "sphere",
    BLOCK_BOTTOM: "block_bottom",
    BLOCK_TOP: "block_top",
    SPHERE_CONTACT: "sphere_contact",
    SPHERE_TOP: "sphere_top",
    SYMMETRY_X: "symmetry_x",
    SYMMETRY_Y: "symmetry_y",
}

# Keyword arguments of `build_hertz` for a small mesh (tests), relative to radius 1: ~3k P1 dofs.
COARSE: dict[str, float] = {"size_fine": 0.04, "size_coarse": 0.3, "refine_radius": 0.2}

_CELL_TYPES = ("tetrahedron", "hexahedron")
_TOL = 1e-5  # OCC pads bounding boxes by 1e-7


def build_hertz(
    *,
    radius: float = 1.0,
    block_size: Sequence[float] | None = None,
    quarter: bool = True,
    size_fine: float | None = None,
    size_coarse: float | None = None,
    refine_radius: float | None = None,
    coarse_radius: float | None = None,
    cell_type: str = "tetrahedron",
    order: int = 1,
    name: str = "hertz",
) -> None:
    """Mesh a hemisphere on a block, touching at the origin, in a new current gmsh model.

    Sizes default to multiples of ``radius``: block ``(2R, 2R, 1.5R)``, fine size ``0.014R`` within
    ``0.25R`` of the contact point, coarse size ``R/4`` beyond ``1.2R``: about 27k P1 dofs for the
    quarter tetrahedral model. Hexahedral defaults are 1.5 times larger (about 32k P1 dofs; at
    equal sizes hexahedra give 3-4 times more nodes). The full model has about 3.4 times more.
    For Hertz theory the contact radius should stay well inside ``refine_radius`` and small
    against R and the block.

    Args:
        radius: Sphere radius R.
        block_size: ``(Lx, Ly, Lz)``; the block is ``[0, Lx] x [0, Ly] x [-Lz, 0]`` for the quarter
            model and ``[-Lx, Lx] x [-Ly, Ly] x [-Lz, 0]`` for the full one.
        quarter: Quarter model with symmetry planes x = 0 and y = 0.
        size_fine: Edge length near the contact point.
        size_coarse: Largest edge length.
        refine_radius: Distance from the contact point within which the size is ``size_fine``.
        coarse_radius: Distance from which the size is ``size_coarse`` (default ``1.2 R``).
        cell_type: ``"tetrahedron"`` or ``"hexahedron"`` (subdivided tetrahedra).
        order: Geometric order 1 or 2 (10-node tetrahedra, 27-node hexahedra; curved faces).
        name: Name of the gmsh model to create.

    Raises:
        ValueError: Bad sizes, cell type or order.
    """
    r = _positive(radius, "radius")
    lx, ly, lz = (2.0 * r, 2.0 * r, 1.5 * r) if block_size is None else _triple(block_size)
    # Hexahedra are denser at equal edge length: coarser defaults keep ~30k P1 dofs.
    stretch = 1.5 if cell_type == "hexahedron" else 1.0
    h_fine = _positive(0.014 * stretch * r if size_fine is None else size_fine, "size_fine")
    h_coarse = _positive(0.25 * stretch * r if size_coarse is None else size_coarse, "size_coarse")
    d_fine = _positive(0.25 * r if refine_radius is None else refine_radius, "refine_radius")
    d_coarse = _positive(1.2 * r if coarse_radius is None else coarse_radius, "coarse_radius")
    if h_coarse < h_fine:
        raise ValueError(f"size_coarse ({h_coarse}) must not be smaller than size_fine ({h_fine})")
    if d_coarse <= d_fine:
        raise ValueError(f"coarse_radius ({d_coarse}) must exceed refine_radius ({d_fine})")
    if cell_type not in _CELL_TYPES:
        raise ValueError(f"cell_type must be one of {_CELL_TYPES}, got {cell_type!r}")
    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")

    _new_model(name, hexahedra=cell_type == "hexahedron")
    occ = gmsh.model.occ
    sphere = occ.addSphere(
        0.0,
        0.0,
        r,
        r,
        angle1=-0.5 * math.pi,
        angle2=0.0,
        angle3=0.5 * math.pi if quarter else 2.0 * math.pi,
    )
    if quarter:
        block = occ.addBox(0.0, 0.0, -lz, lx, ly, lz)
    else:
        block = occ.addBox(-lx, -ly, -lz, 2.0 * lx, 2.0 * ly, lz)
    occ.synchronize()

    # The tetrahedral mesh is split 1 -> 4 hexahedra: hexahedron edges are half the tetrahedron's.
    scale = 2.0 if cell_type == "hexahedron" else 1.0
    _size_field(r, scale * h_fine, scale * h_coarse, d_fine, d_coarse)
    _tag_groups(block, sphere, r, lz, quarter)
    gmsh.model.mesh.generate(3)
    if order > 1:
        gmsh.model.mesh.setOrder(order)
    gmsh.model.mesh.renumberNodes()
    gmsh.model.mesh.renumberElements()


def build_hertz_sphere(**kwargs: typing.Any) -> None:
    """:func:`build_hertz`, then the block removed: the same sphere cells alone.

    For contact against a rigid plane ``z = 0`` (docs/method.md §15.1): the sphere mesh is the one
    the two-body model has, so that rigid and meshed masters compare on identical sphere cells.
    The sphere keeps its groups (``SPHERE``, ``SPHERE_CONTACT``, ``SPHERE_TOP`` and its parts of
    ``SYMMETRY_X``/``SYMMETRY_Y``). Takes the arguments of :func:`build_hertz`.
    """
    build_hertz(**kwargs)
    model = gmsh.model
    spheres = list(model.getEntitiesForPhysicalGroup(3, SPHERE))
    blocks = list(model.getEntitiesForPhysicalGroup(3, BLOCK))
    boundary = model.getBoundary([(3, v) for v in spheres], combined=False, oriented=False)
    sphere_faces = {abs(s) for _, s in boundary}
    groups = {
        (dim, tag): list(model.getEntitiesForPhysicalGroup(dim, tag))
        for dim, tag in model.getPhysicalGroups()
    }
    model.removePhysicalGroups()
    model.removeEntities([(3, b) for b in blocks], recursive=True)
    for (dim, tag), entities in groups.items():
        keep = spheres if (dim, tag) == (3, SPHERE) else []
        if dim == 2:
            keep = [e for e in entities if e in sphere_faces]
        if keep:
            model.addPhysicalGroup(dim, keep, tag)
            model.setPhysicalName(dim, tag, PHYSICAL_NAMES[tag])
    model.mesh.renumberNodes()
    model.mesh.renumberElements()


def build_hertz_axisymmetric(
    *,
    radius: float = 1.0,
    block_size: Sequence[float] | None = None,
    size_fine: float | None = None,
    size_coarse: float | None = None,
    refine_radius: float | None = None,
    coarse_radius: float | None = None,
    order: int = 1,
    name: str = "hertz_axisymmetric",
) -> None:
    """Mesh the meridian section of :func:`build_hertz`'s model in 2D (triangles).

    The sphere is the quarter disc of centre ``(0, R)`` between the axis ``x = 0`` and its top
    ``y = R``, touching the block ``[0, Lr] x [-Lz, 0]`` at the origin (separate nodes); the
    defaults and the size field are :func:`build_hertz`'s (block ``2R x 1.5R``, ``0.014 R``
    within ``0.25 R`` of the contact point, ``R/4`` beyond ``1.2 R``). Tags: ``BLOCK``,
    ``SPHERE``, ``BLOCK_BOTTOM``, ``BLOCK_TOP``, ``SPHERE_CONTACT`` (the arc), ``SPHERE_TOP``,
    and ``SYMMETRY_X`` for the axis segments of both bodies.

    Args:
        radius: Sphere radius R.
        block_size: ``(Lr, Lz)``: the block's radius and depth.
        size_fine: Edge length near the contact point.
        size_coarse: Largest edge length.
        refine_radius: Distance from the contact point within which the size is ``size_fine``.
        coarse_radius: Distance from which the size is ``size_coarse`` (default ``1.2 R``).
        order: Geometric order 1 or 2 (6-node triangles, curved arc edges).
        name: Name of the gmsh model to create.

    Raises:
        ValueError: Bad sizes or order.
    """
    r = _positive(radius, "radius")
    if block_size is None:
        lr, lz = 2.0 * r, 1.5 * r
    else:
        lr, lz = (_positive(v, "block_size") for v in block_size)
    h_fine = _positive(0.014 * r if size_fine is None else size_fine, "size_fine")
    h_coarse = _positive(0.25 * r if size_coarse is None else size_coarse, "size_coarse")
    d_fine = _positive(0.25 * r if refine_radius is None else refine_radius, "refine_radius")
    d_coarse = _positive(1.2 * r if coarse_radius is None else coarse_radius, "coarse_radius")
    if h_coarse < h_fine:
        raise ValueError(f"size_coarse ({h_coarse}) must not be smaller than size_fine ({h_fine})")
    if d_coarse <= d_fine:
        raise ValueError(f"coarse_radius ({d_coarse}) must exceed refine_radius ({d_fine})")
    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    _new_model(name, hexahedra=False)
    geo = gmsh.model.geo
    corners = [geo.addPoint(x, y, 0.0) for x, y in ((0, -lz), (lr, -lz), (lr, 0), (0, 0))]
    block_lines = [geo.addLine(corners[i], corners[(i + 1) % 4]) for i in range(4)]
    block = geo.addPlaneSurface([geo.addCurveLoop(block_lines)])
    pole, rim, centre = geo.addPoint(0, 0, 0), geo.addPoint(r, r, 0), geo.addPoint(0, r, 0)
    arc = geo.addCircleArc(pole, centre, rim)
    top, axis = geo.addLine(rim, centre), geo.addLine(centre, pole)
    sphere = geo.addPlaneSurface([geo.addCurveLoop([arc, top, axis])])
    geo.synchronize()
    _size_field(r, h_fine, h_coarse, d_fine, d_coarse)
    groups = {
        (2, BLOCK): [block],
        (2, SPHERE): [sphere],
        (1, BLOCK_BOTTOM): [block_lines[0]],
        (1, BLOCK_TOP): [block_lines[2]],
        (1, SPHERE_CONTACT): [arc],
        (1, SPHERE_TOP): [top],
        (1, SYMMETRY_X): [block_lines[3], axis],
    }
    for (dim, tag), entities in groups.items():
        gmsh.model.addPhysicalGroup(dim, entities, tag)
        gmsh.model.setPhysicalName(dim, tag, PHYSICAL_NAMES[tag])
    gmsh.model.mesh.generate(2)
    if order > 1:
        gmsh.model.mesh.setOrder(order)
    gmsh.model.mesh.renumberNodes()
    gmsh.model.mesh.renumberElements()


def _positive(value: float, what: str) -> float:
    """A positive finite float or a ValueError naming the parameter."""
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{what} must be a positive number, got {value!r}")
    return value


def _triple(values: Sequence[float]) -> tuple[float, float, float]:
    """Three positive finite floats (the block size)."""
    values = tuple(float(v) for v in values)
    if len(values) != 3 or not all(math.isfinite(v) and v > 0.0 for v in values):
        raise ValueError(f"block_size must be three positive numbers, got {values!r}")
    return values


def _new_model(name: str, *, hexahedra: bool) -> None:
    """Add a fresh gmsh model (current from now on) and set the mesh options used here."""
    gmsh.model.add(name)
    for option, value in (
        ("Mesh.RecombineAll", 0),
        ("Mesh.Recombine3DAll", 0),
        ("Mesh.SubdivisionAlgorithm", 2 if hexahedra else 0),
        ("Mesh.SecondOrderIncomplete", 0),
        ("Mesh.MeshSizeFromPoints", 0),
        ("Mesh.MeshSizeExtendFromBoundary", 0),
        ("Mesh.MeshSizeFromCurvature", 0),
        ("Mesh.MeshSizeMin", 0.0),
        ("Mesh.MeshSizeMax", 1e22),
        ("Mesh.MeshSizeFactor", 1.0),
    ):
        gmsh.option.setNumber(option, value)


def _size_field(r: float, h_fine: float, h_coarse: float, d_fine: float, d_coarse: float) -> None:
    """Background size: fine near the contact point (origin), linear growth, then coarse."""
    fields = gmsh.model.mesh.field
    distance = fields.add("MathEval")
    # Distance to the contact point; the sphere pole and the block top both touch it.
    fields.setString(distance, "F", "Sqrt(x*x + y*y + z*z)")
    threshold = fields.add("Threshold")
    fields.setNumber(threshold, "InField", distance)
    fields.setNumber(threshold, "SizeMin", h_fine)
    fields.setNumber(threshold, "SizeMax", h_coarse)
    fields.setNumber(threshold, "DistMin", d_fine)
    fields.setNumber(threshold, "DistMax", d_coarse)
    fields.setAsBackgroundMesh(threshold)


def _faces(volume: int, predicate) -> list[int]:
    """Boundary surfaces of a volume whose bounding box ``(x0, y0, z0, x1, y1, z1)`` passes."""
    surfaces = gmsh.model.getBoundary([(3, volume)], combined=False, oriented=False)
    return sorted(abs(s) for _, s in surfaces if predicate(gmsh.model.getBoundingBox(2, abs(s))))


def _tag_groups(block: int, sphere: int, r: float, lz: float, quarter: bool) -> None:
    """Create the physical groups; each boundary face of either body lands in at most one."""

    def flat(axis: int, value: float):
        return lambda box: abs(box[axis] - value) < _TOL and abs(box[axis + 3] - value) < _TOL

    def curved(box) -> bool:  # spanning 0 < z < R: the spherical face
        spans = box[2] < _TOL and box[5] > r - _TOL
        return spans and not flat(0, 0.0)(box) and not flat(1, 0.0)(box)

    groups = {
        (3, BLOCK): [block],
        (3, SPHERE): [sphere],
        (2, BLOCK_BOTTOM): _faces(block, flat(2, -lz)),
        (2, BLOCK_TOP): _faces(block, flat(2, 0.0)),
        (2, SPHERE_CONTACT): _faces(sphere, curved),
        (2, SPHERE_TOP): _faces(sphere, flat(2, r)),
    }
    if quarter:
        groups[(2, SYMMETRY_X)] = _faces(block, flat(0, 0.0)) + _faces(sphere, flat(0, 0.0))
        groups[(2, SYMMETRY_Y)] = _faces(block, flat(1, 0.0)) + _faces(sphere, flat(1, 0.0))
    expected = 2 if quarter else 1
    for (dim, tag), entities in groups.items():
        count = expected if tag in (SYMMETRY_X, SYMMETRY_Y) else 1
        if len(entities) != count:
            raise RuntimeError(f"physical group {PHYSICAL_NAMES[tag]}: found surfaces {entities}")
        gmsh.model.addPhysicalGroup(dim, entities, tag)
        gmsh.model.setPhysicalName(dim, tag, PHYSICAL_NAMES[tag])


def main(argv: Sequence[str] | None = None) -> None:
    """Write a Hertz contact mesh to a .msh file."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "-o", "--output", type=Path, default=Path("hertz.msh"), help="default: hertz.msh"
    )
    parser.add_argument("--cell-type", choices=_CELL_TYPES, default="tetrahedron")
    parser.add_argument("--order", type=int, choices=(1, 2), default=1)
    parser.add_argument("--radius", type=float, default=1.0)
    parser.add_argument("--full", action="store_true", help="full model instead of a quarter")
    parser.add_argument("--coarse", action="store_true", help="small mesh for tests")
    parser.add_argument("--size-fine", type=float, default=None)
    parser.add_argument("--size-coarse", type=float, default=None)
    parser.add_argument("--refine-radius", type=float, default=None)
    args = parser.parse_args(argv)

    sizes = {key: value * args.radius for key, value in COARSE.items()} if args.coarse else {}
    for key in ("size_fine", "size_coarse", "refine_radius"):
        if getattr(args, key) is not None:
            sizes[key] = getattr(args, key)
    with gmsh_session(terminal=True):
        build_hertz(
            radius=args.radius,
            quarter=not args.full,
            cell_type=args.cell_type,
            order=args.order,
            **sizes,
        )
        write_msh(args.output)


if __name__ == "__main__":
    main()
