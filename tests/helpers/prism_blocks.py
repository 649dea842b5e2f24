"""gmsh models of prism-meshed blocks for the prism tests: extruded triangulations on hexahedra.

``build_prism_on_hex`` makes a punch of prisms (a triangulated square extruded with
``recombine=True``) standing on a base of hexahedra (a transfinite, recombined box), or, with
``punch="hexahedron"`` / ``base="prism"``, the same geometry meshed the other way. Physical groups:
cells ``BASE``, ``PUNCH``; facets ``BASE_BOTTOM``, ``BASE_TOP``, ``PUNCH_BOTTOM``, ``PUNCH_TOP``.
"""

import gmsh

BASE, PUNCH = 1, 2
BASE_BOTTOM, BASE_TOP, PUNCH_BOTTOM, PUNCH_TOP = 11, 12, 13, 14


def _box(origin, size, divisions, cell, structured):
    """A box of ``cell`` ("hexahedron" or "prism") by extrusion: (volume, bottom, top) tags.

    Prisms: the square triangulated by gmsh's Delaunay mesher, or with ``structured`` the
    ``nx x ny`` grid with each square cut along one diagonal (the same cut for equal grids).
    OpenCASCADE boxes: two boxes that touch keep their own nodes (no fragment).
    """
    x0, y0, z0 = origin
    sx, sy, sz = size
    nx, ny, nz = divisions
    square = gmsh.model.occ.addRectangle(x0, y0, z0, sx, sy)
    out = gmsh.model.occ.extrude([(2, square)], 0, 0, sz, numElements=[nz], recombine=True)
    gmsh.model.occ.synchronize()
    curves = [abs(c[1]) for c in gmsh.model.getBoundary([(2, square)], oriented=False)]
    if cell == "hexahedron" or structured:
        for curve in curves:
            ends = gmsh.model.getBoundary([(1, curve)], oriented=False)
            a, b = (gmsh.model.getValue(0, p[1], []) for p in ends)
            along_x = abs(b[0] - a[0]) > abs(b[1] - a[1])
            gmsh.model.mesh.setTransfiniteCurve(curve, (nx if along_x else ny) + 1)
        gmsh.model.mesh.setTransfiniteSurface(square)
        if cell == "hexahedron":
            gmsh.model.mesh.setRecombine(2, square)
    else:
        gmsh.model.mesh.setSize(gmsh.model.getBoundary([(2, square)], recursive=True),
                                min(sx / nx, sy / ny))  # fmt: skip
    return out[1][1], square, out[0][1]


def build_prism_on_hex(
    base=((0.0, 0.0, -1.0), (1.0, 1.0, 1.0), (4, 4, 2)),
    punch=((0.2, 0.2, 0.0), (0.6, 0.6, 0.5), (3, 3, 2)),
    punch_cell="prism",
    base_cell="hexahedron",
    structured=False,
    order=1,
):
    """A new gmsh model: the punch (origin, size, divisions) on the base, meshed; see module.

    ``structured``: prisms on a grid cut along diagonals (see ``_box``); ``order``: gmsh's element
    order (2 makes 18-node prisms beside 27-node hexahedra, which the reader refuses).
    """
    gmsh.model.add("prism_on_hex")
    b_volume, b_bottom, b_top = _box(*base, base_cell, structured)
    p_volume, p_bottom, p_top = _box(*punch, punch_cell, structured)
    gmsh.model.mesh.generate(3)
    if order != 1:
        gmsh.model.mesh.setOrder(order)
    for dim, entities, tag in (
        (3, [b_volume], BASE), (3, [p_volume], PUNCH), (2, [b_bottom], BASE_BOTTOM),
        (2, [b_top], BASE_TOP), (2, [p_bottom], PUNCH_BOTTOM), (2, [p_top], PUNCH_TOP),
    ):  # fmt: skip
        gmsh.model.addPhysicalGroup(dim, entities, tag)
