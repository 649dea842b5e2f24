"""Flat punch on a block: gmsh models for node-to-face contact.

The block fills ``[0, Lx] x [0, Ly] x [-Lz, 0]``; the punch is a separate body (no shared nodes)
centred over the block top with its bottom face at ``z = gap``. Both are meshed through the gmsh API
in a *new* gmsh model that becomes the current one, so that `gmsh_io.model_to_mesh` can
read it directly. Hexahedra come from transfinite volumes with recombined faces; tetrahedra from the
unstructured mesher (`build_punch`) or from split transfinite hexahedra (`build_patch_test`).

The builders only talk to gmsh: call them on one MPI rank, with gmsh initialized.

Run as a script to write ``punch.msh``::

    python -m dolfinx_ntf.meshes.punch --cell-type tetrahedron --block-size 0.1 --punch-size 0.05
    python -m dolfinx_ntf.meshes.punch --patch --divisions 4 -o patch.msh
"""

from __future__ import annotations

import argparse
import math
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
    "PUNCH",
    "PUNCH_BOTTOM",
    "PUNCH_TOP",
    "build_patch_test",
    "build_punch",
    "main",
]

# Physical groups (cell tags).
BLOCK = 1
PUNCH = 2
# Physical groups (facet tags).
BLOCK_BOTTOM = 11  # clamped
BLOCK_TOP = 12  # contact master: the whole top face of the block
PUNCH_BOTTOM = 13  # contact slave
PUNCH_TOP = 14  # loaded / prescribed displacement

PHYSICAL_NAMES: dict[int, str] = {
    BLOCK: "block",
    PUNCH: "punch",
    BLOCK_BOTTOM: "block_bottom",
    BLOCK_TOP: "block_top",
    PUNCH_BOTTOM: "punch_bottom",
    PUNCH_TOP: "punch_top",
}

# Keyword arguments of `build_punch` for a small mesh (tests): about 1.6k P1 dofs.
COARSE: dict[str, float] = {"mesh_size_block": 0.125, "mesh_size_punch": 0.1}

_CELL_TYPES = ("hexahedron", "tetrahedron")
_TOL = 1e-5  # OCC pads bounding boxes by 1e-7


def build_punch(
    *,
    block_size: Sequence[float] = (1.0, 1.0, 0.5),
    punch_size: Sequence[float] = (0.4, 0.4, 0.3),
    gap: float = 0.0,
    mesh_size_block: float = 0.05,
    mesh_size_punch: float = 0.04,
    cell_type: str = "hexahedron",
    order: int = 1,
    name: str = "punch",
) -> None:
    """Mesh a block and a punch centred on its top, in a new current gmsh model.

    The punch edges generally fall inside block faces (non-matching meshes), which is what
    node-to-face contact is for. The default sizes give about 18k P1 dofs with hexahedra.

    Args:
        block_size: ``(Lx, Ly, Lz)`` of the block ``[0, Lx] x [0, Ly] x [-Lz, 0]``.
        punch_size: ``(px, py, pz)`` of the punch; its footprint must fit on the block top.
        gap: Height of the punch bottom above the block top (negative: initial overlap).
        mesh_size_block: Target edge length in the block.
        mesh_size_punch: Target edge length in the punch (finer than the block is the usual choice
            for a slave body).
        cell_type: ``"hexahedron"`` (transfinite, recombined) or ``"tetrahedron"`` (unstructured).
        order: Geometric order 1 or 2 (27-node hexahedra, 10-node tetrahedra).
        name: Name of the gmsh model to create.

    Raises:
        ValueError: Bad sizes, cell type or order.
    """
    lx, ly, lz = _positive_triple(block_size, "block_size")
    px, py, pz = _positive_triple(punch_size, "punch_size")
    if px > lx + _TOL or py > ly + _TOL:
        raise ValueError(
            f"punch_size footprint ({px}, {py}) does not fit on the block top ({lx}, {ly})"
        )
    _check_common(cell_type, order, gap)
    for value, what in ((mesh_size_block, "mesh_size_block"), (mesh_size_punch, "mesh_size_punch")):
        if not (math.isfinite(value) and value > 0.0):
            raise ValueError(f"{what} must be a positive number, got {value!r}")

    x0, y0 = 0.5 * (lx - px), 0.5 * (ly - py)
    _new_model(name)
    block = gmsh.model.occ.addBox(0.0, 0.0, -lz, lx, ly, lz)
    punch = gmsh.model.occ.addBox(x0, y0, gap, px, py, pz)
    gmsh.model.occ.synchronize()

    if cell_type == "hexahedron":
        _transfinite_box(block, _divisions((lx, ly, lz), mesh_size_block), recombine=True)
        _transfinite_box(punch, _divisions((px, py, pz), mesh_size_punch), recombine=True)
    else:
        for volume, size in ((block, mesh_size_block), (punch, mesh_size_punch)):
            points = gmsh.model.getBoundary([(3, volume)], combined=False, recursive=True)
            gmsh.model.mesh.setSize(points, size)

    _tag_groups(block, punch, (lx, ly, lz), (x0, y0, px, py, pz), gap)
    _generate(order)


def build_patch_test(
    *,
    block_size: Sequence[float] = (1.0, 1.0, 0.5),
    punch_height: float = 0.25,
    divisions: int | Sequence[int] = 4,
    punch_divisions: int | Sequence[int] | None = None,
    block_layers: int = 2,
    punch_layers: int = 2,
    gap: float = 0.0,
    cell_type: str = "hexahedron",
    order: int = 1,
    name: str = "patch_test",
) -> None:
    """Mesh the flat-punch patch test, in a new current gmsh model.

    The punch covers the whole block top (``[0, Lx] x [0, Ly]``), so a uniform pressure on the
    punch top must come out as a uniform contact pressure. With ``punch_divisions=None`` both
    bodies get the same in-plane divisions: the punch bottom and block top meshes match node for
    node (for tetrahedra: same triangles too). Same physical groups as `build_punch`.

    Args:
        block_size: ``(Lx, Ly, Lz)`` of the block ``[0, Lx] x [0, Ly] x [-Lz, 0]``.
        punch_height: Height of the punch ``[0, Lx] x [0, Ly] x [gap, gap + punch_height]``.
        divisions: In-plane element divisions of the block, one int or ``(nx, ny)``.
        punch_divisions: In-plane divisions of the punch; ``None`` means equal to ``divisions``.
        block_layers: Element layers through the block thickness.
        punch_layers: Element layers through the punch height.
        gap: Height of the punch bottom above the block top.
        cell_type: ``"hexahedron"`` or ``"tetrahedron"`` (each hexahedron split into tetrahedra).
        order: Geometric order 1 or 2.
        name: Name of the gmsh model to create.

    Raises:
        ValueError: Bad sizes, divisions, cell type or order.
    """
    lx, ly, lz = _positive_triple(block_size, "block_size")
    if not (math.isfinite(punch_height) and punch_height > 0.0):
        raise ValueError(f"punch_height must be a positive number, got {punch_height!r}")
    _check_common(cell_type, order, gap)
    nx, ny = _division_pair(divisions, "divisions")
    mx, my = _division_pair(
        divisions if punch_divisions is None else punch_divisions, "punch_divisions"
    )
    for value, what in ((block_layers, "block_layers"), (punch_layers, "punch_layers")):
        if int(value) != value or value < 1:
            raise ValueError(f"{what} must be a positive integer, got {value!r}")

    _new_model(name)
    block = gmsh.model.occ.addBox(0.0, 0.0, -lz, lx, ly, lz)
    punch = gmsh.model.occ.addBox(0.0, 0.0, gap, lx, ly, punch_height)
    gmsh.model.occ.synchronize()
    recombine = cell_type == "hexahedron"
    _transfinite_box(block, (nx, ny, int(block_layers)), recombine=recombine)
    _transfinite_box(punch, (mx, my, int(punch_layers)), recombine=recombine)
    _tag_groups(block, punch, (lx, ly, lz), (0.0, 0.0, lx, ly, punch_height), gap)
    _generate(order)


def _new_model(name: str) -> None:
    """Add a fresh gmsh model (current from now on) and set the mesh options used here."""
    gmsh.model.add(name)
    for option, value in (
        ("Mesh.RecombineAll", 0),
        ("Mesh.Recombine3DAll", 0),
        ("Mesh.SubdivisionAlgorithm", 0),
        ("Mesh.SecondOrderIncomplete", 0),
        ("Mesh.MeshSizeFromPoints", 1),
        ("Mesh.MeshSizeExtendFromBoundary", 1),
        ("Mesh.MeshSizeFromCurvature", 0),
        ("Mesh.MeshSizeMin", 0.0),
        ("Mesh.MeshSizeMax", 1e22),
        ("Mesh.MeshSizeFactor", 1.0),
    ):
        gmsh.option.setNumber(option, value)


def _check_common(cell_type: str, order: int, gap: float) -> None:
    """Validate the options shared by both builders."""
    if cell_type not in _CELL_TYPES:
        raise ValueError(f"cell_type must be one of {_CELL_TYPES}, got {cell_type!r}")
    if order not in (1, 2):
        raise ValueError(f"order must be 1 or 2, got {order!r}")
    if not math.isfinite(gap):
        raise ValueError(f"gap must be finite, got {gap!r}")


def _positive_triple(values: Sequence[float], what: str) -> tuple[float, float, float]:
    """Three positive finite floats or a ValueError naming the parameter."""
    values = tuple(float(v) for v in values)
    if len(values) != 3 or not all(math.isfinite(v) and v > 0.0 for v in values):
        raise ValueError(f"{what} must be three positive numbers, got {values!r}")
    return values


def _division_pair(divisions: int | Sequence[int], what: str) -> tuple[int, int]:
    """``(nx, ny)`` from one int or a pair, each a positive integer."""
    pair = (divisions, divisions) if isinstance(divisions, (int, float)) else tuple(divisions)
    if len(pair) != 2 or not all(int(n) == n and n >= 1 for n in pair):
        raise ValueError(f"{what} must be a positive integer or a pair of them, got {divisions!r}")
    return int(pair[0]), int(pair[1])


def _divisions(lengths: Sequence[float], size: float) -> tuple[int, ...]:
    """Element counts per box direction closest to a target edge length (at least one)."""
    return tuple(max(1, round(length / size)) for length in lengths)


def _transfinite_box(volume: int, divisions: Sequence[int], *, recombine: bool) -> None:
    """Make an OCC box volume transfinite with ``divisions[axis]`` elements along each axis."""
    surfaces = gmsh.model.getBoundary([(3, volume)], combined=False, oriented=False)
    curves = gmsh.model.getBoundary(surfaces, combined=False, oriented=False)
    for curve in {abs(tag) for _, tag in curves}:
        box = gmsh.model.getBoundingBox(1, curve)
        axis = max(range(3), key=lambda k: box[k + 3] - box[k])
        gmsh.model.mesh.setTransfiniteCurve(curve, int(divisions[axis]) + 1)
    for _, surface in surfaces:
        gmsh.model.mesh.setTransfiniteSurface(surface)
        if recombine:
            gmsh.model.mesh.setRecombine(2, surface)
    gmsh.model.mesh.setTransfiniteVolume(volume)


def _surface_at(volume: int, axis: int, value: float) -> int:
    """The boundary surface of a box volume lying in the plane ``x[axis] = value``."""
    found = []
    for _, surface in gmsh.model.getBoundary([(3, volume)], combined=False, oriented=False):
        box = gmsh.model.getBoundingBox(2, surface)
        if abs(box[axis] - value) < _TOL and abs(box[axis + 3] - value) < _TOL:
            found.append(abs(surface))
    if len(found) != 1:
        raise RuntimeError(f"volume {volume}: expected one face at x[{axis}]={value}, got {found}")
    return found[0]


def _tag_groups(
    block: int,
    punch: int,
    block_size: tuple[float, float, float],
    punch_box: tuple[float, float, float, float, float],
    gap: float,
) -> None:
    """Create the physical groups of both builders."""
    _, _, lz = block_size
    _, _, _, _, pz = punch_box
    groups = {
        (3, BLOCK): [block],
        (3, PUNCH): [punch],
        (2, BLOCK_BOTTOM): [_surface_at(block, 2, -lz)],
        (2, BLOCK_TOP): [_surface_at(block, 2, 0.0)],
        (2, PUNCH_BOTTOM): [_surface_at(punch, 2, gap)],
        (2, PUNCH_TOP): [_surface_at(punch, 2, gap + pz)],
    }
    for (dim, tag), entities in groups.items():
        gmsh.model.addPhysicalGroup(dim, entities, tag)
        gmsh.model.setPhysicalName(dim, tag, PHYSICAL_NAMES[tag])


def _generate(order: int) -> None:
    """Generate the 3D mesh, raise its order, and number nodes contiguously."""
    gmsh.model.mesh.generate(3)
    if order > 1:
        gmsh.model.mesh.setOrder(order)
    gmsh.model.mesh.renumberNodes()
    gmsh.model.mesh.renumberElements()


def main(argv: Sequence[str] | None = None) -> None:
    """Write a punch (or patch-test) mesh to a .msh file."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "-o", "--output", type=Path, default=Path("punch.msh"), help="default: punch.msh"
    )
    parser.add_argument("--cell-type", choices=_CELL_TYPES, default="hexahedron")
    parser.add_argument("--order", type=int, choices=(1, 2), default=1)
    parser.add_argument("--gap", type=float, default=0.0)
    parser.add_argument("--block-size", type=float, default=0.05, help="block mesh size")
    parser.add_argument("--punch-size", type=float, default=0.04, help="punch mesh size")
    parser.add_argument("--coarse", action="store_true", help="small mesh for tests")
    parser.add_argument("--patch", action="store_true", help="matching patch-test mesh")
    parser.add_argument("--divisions", type=int, default=4, help="patch test in-plane divisions")
    args = parser.parse_args(argv)

    with gmsh_session(terminal=True):
        if args.patch:
            build_patch_test(
                divisions=args.divisions, gap=args.gap, cell_type=args.cell_type, order=args.order
            )
        else:
            sizes = (
                dict(COARSE)
                if args.coarse
                else {"mesh_size_block": args.block_size, "mesh_size_punch": args.punch_size}
            )
            build_punch(gap=args.gap, cell_type=args.cell_type, order=args.order, **sizes)
        write_msh(args.output)


if __name__ == "__main__":
    main()
