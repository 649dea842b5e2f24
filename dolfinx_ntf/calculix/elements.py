"""The table of supported CalculiX solid elements, shared by reader, model, writer and .frd code.

See docs/method.md §8.5 and §13.2. One frozen :class:`ElementType` per ccx type holds everything
the package knows about it: node and face tables (reader), the dolfinx cell, degree and node
permutation (model, writer), ccx's volume integration rule (model, ``*EL PRINT``), and the frd
type number and stress extrapolation (``.frd``). Pure Python/numpy: no dolfinx import.

Conventions:
    - Node indices are 0-based element-local positions in ccx's node order.
    - Face tables are in CalculiX's *internal* face order (outward normal, node 1 of the face as
      ccx numbers it), verified against the ``.cel`` files written by ccx 2.20. The manual's
      ``*SURFACE``/``*DLOAD`` tables list the same nodes with the inward orientation
      (e.g. C3D8 S1 is ``1-2-3-4`` in the manual and ``4-3-2-1`` here).
    - Points are dolfinx reference coordinates: the unit cube for hexahedra (ccx's
      ``(xi, eta, zeta)`` in ``[-1, 1]^3`` maps to ``((xi+1)/2, (eta+1)/2, (zeta+1)/2)``) and the
      unit tetrahedron, whose vertices are ccx's corners 1..4 in order.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = [
    "AXISYMMETRIC_SECTOR",
    "C3D6_EXTRAPOLATION",
    "C3D8_EXTRAPOLATION",
    "C3D20_EXTRAPOLATION",
    "ELEMENT_TYPES",
    "REFUSED_ELEMENTS",
    "TWO_D_MODELS",
    "ElementType",
    "element_for_cell",
    "frozen_array",
    "nodal_extrapolation",
]


#: The 2D model of ccx's 2D element families (the first three letters of the type name).
TWO_D_MODELS = {"CPE": "plane strain", "CPS": "plane stress", "CAX": "axisymmetric"}

#: The sector (radians) ccx 2.20 expands CAX elements into: 2 degrees (manual, CAX8). Its printed
#: forces and spring energies are the sector's, about 1/180 of the whole ring's (docs/method.md
#: §23).
AXISYMMETRIC_SECTOR = np.pi / 90.0


def frozen_array(values: npt.ArrayLike, dtype: npt.DTypeLike) -> np.ndarray:
    """A read-only copy of ``values``."""
    array = np.array(values, dtype=dtype)
    array.flags.writeable = False
    return array


@dataclass(frozen=True, eq=False)
class ElementType:
    """A supported CalculiX solid element type.

    Attributes:
        name: ccx type name (``C3D4``, ``C3D8``, ``C3D8I``, ``C3D10``, ``C3D20``, ``C3D20R``).
        num_nodes: nodes per element.
        num_corners: corner (vertex) nodes per element, listed first.
        face_type: face type name of ``dolfinx_ntf.kernels.faces`` (``tri3``, ``quad4``, ``tri6``).
        faces: ``(num_faces, face_nodes)`` 0-based element-local node indices of faces S1..Sk,
            corners counter-clockwise seen from outside the element, then midside nodes.
        cell: dolfinx cell name (``tetrahedron``, ``hexahedron``).
        degree: degree of the dolfinx Lagrange space and coordinate element.
        to_dolfinx: ``(num_nodes,)`` dolfinx cell node ``k`` is ccx node ``to_dolfinx[k]``.
        mirrored_vertices: ccx corner ``i`` of a cell mirrored against ccx's orientation is dolfinx
            vertex ``mirrored_vertices[i]`` (the writer numbers such cells this way).
        midside_edges: the two corners (0-based) of the edge of each midside node, in ccx order.
        quadrature_degree: volume quadrature degree that gives ccx's integration rule.
        integration_points: ``(q, 3)`` ccx's integration points in ccx order (``*EL PRINT`` rows).
        frd_type: element type number in ``.frd`` files (cgx manual).
        extrapolation: ``(num_nodes, q)`` integration-point values -> nodal values, as ccx's
            ``.frd`` stresses (``nodal_extrapolation``).
        face_quadrature_degree: face quadrature degree of ``*DLOAD`` pressures (2x2 Gauss on
            quads, 3 points on triangles; C3D20 3x3).
        frd_order: the ccx nodes of an element in ``.frd`` order (ccx order but for C3D20:
            nodes 1..12, 17..20, 13..16, and C3D15: 1..9, 13..15, 10..12, as ccx 2.20 writes
            them).
        print_rows: 2D elements: the integration point of each ``*EL PRINT`` row ccx 2.20 prints
            (the points of the one layer of 3D elements it expands the element into, both
            layers the same in-plane points; docs/method.md §23); None for 3D elements.
    """

    name: str
    num_nodes: int
    num_corners: int
    face_type: str
    faces: np.ndarray
    cell: str
    degree: int
    to_dolfinx: np.ndarray
    mirrored_vertices: np.ndarray
    midside_edges: tuple[tuple[int, int], ...]
    quadrature_degree: int
    integration_points: np.ndarray
    frd_type: int
    extrapolation: np.ndarray
    face_quadrature_degree: int = 2
    frd_order: np.ndarray | None = None
    print_rows: np.ndarray | None = None

    @property
    def tdim(self) -> int:
        """The element's topological dimension (2 for ccx's 2D elements, else 3)."""
        return 2 if self.cell in ("triangle", "quadrilateral") else 3

    @property
    def model(self) -> str:
        """``solid`` (3D), ``plane strain`` (CPE), ``plane stress`` (CPS) or ``axisymmetric``."""
        return TWO_D_MODELS.get(self.name[:3], "solid")

    @property
    def frd_nodes(self) -> np.ndarray:
        """Column order of the ccx connectivity in ``.frd`` element records."""
        return np.arange(self.num_nodes) if self.frd_order is None else self.frd_order

    @property
    def num_faces(self) -> int:
        """Number of faces (labels S1..S<num_faces>)."""
        return int(self.faces.shape[0])

    @property
    def face_corners(self) -> int:
        """Number of corner nodes per face (2 for the edges of 2D elements)."""
        if self.face_type.startswith("line"):
            return 2
        return 3 if self.face_type.startswith("tri") else 4

    @property
    def face_sizes(self) -> np.ndarray:
        """``(num_faces,)`` nodes of each face (C3D15's triangles pad ``faces`` with -1)."""
        return np.sum(self.faces >= 0, axis=1)

    @property
    def face_corner_counts(self) -> np.ndarray:
        """``(num_faces,)`` corner nodes of each face (C3D15: 3 on S1, S2, 4 on S3..S5)."""
        sizes = self.face_sizes
        return np.where(sizes < self.faces.shape[1], sizes // 2, self.face_corners)

    @property
    def corner_vertices(self) -> np.ndarray:
        """ccx corner ``i`` is dolfinx vertex ``corner_vertices[i]``."""
        return np.argsort(self.to_dolfinx[: self.num_corners])


#: ccx 2.20's C3D8 extrapolation weight of an integration point by the number of coordinates in
#: which it lies on the other side of the node (0..3): the trilinear values (1 +- sqrt 3)^k / 8
#: rounded, summing to 0.99996 over the 8 points. Fitted to ccx's ``.frd`` files (ccx writes a
#: uniform stress of 10 as 9.9996); they reproduce ccx's nodal stresses to print precision
#: (docs/method.md §13.2).
C3D8_EXTRAPOLATION = (2.549, -0.683, 0.183, -0.04904)

#: ccx 2.20's ``(6, 2)`` extrapolation of a C3D6 wedge's two integration points (ccx's order) to
#: its nodes (ccx's order), measured from ccx's ``.frd`` files (docs/method.md §35): the odd nodes
#: 1, 3, 5 take ``1.1455 p1 - 0.1455 p2``, the even nodes 2, 4, 6 the mirror. The weights are the
#: linear field through points at ``-+sqrt(3/5)`` rounded (not the 2-point rule's ``-+1/sqrt 3``),
#: and the rows alternate where the two triangles would be expected: ccx's layout, reproduced as is.
C3D6_EXTRAPOLATION = np.array([[1.1455, -0.1455], [-0.1455, 1.1455]] * 3)
C3D6_EXTRAPOLATION.flags.writeable = False

# ccx node order of the 8 hexahedron corners in dolfinx reference coordinates.
_HEX_CORNERS = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]]
)
# ccx's 6-node triangle: midside nodes 4..6 on the edges 1-2, 2-3, 3-1; 8-node quadrilateral:
# midside nodes 5..8 on 1-2, 2-3, 3-4, 4-1.
_TRI_EDGES = ((0, 1), (1, 2), (2, 0))
_QUAD_EDGES = ((0, 1), (1, 2), (2, 3), (3, 0))
# ccx C3D10 midside nodes 5..10 sit on the edges between these ccx corners (manual fig. 55).
_TET_EDGES = ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))
# ccx C3D20 midside nodes 9..20 (manual): on 1-2, 2-3, 3-4, 4-1, 5-6, 6-7, 7-8, 8-5, 1-5, 2-6,
# 3-7, 4-8.
_HEX_EDGES = (
    (0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)
)  # fmt: skip


# ccx C3D15 midside nodes 7..15 (manual): on 1-2, 2-3, 3-1, 4-5, 5-6, 6-4, 1-4, 2-5, 3-6.
_WEDGE_EDGES = ((0, 1), (1, 2), (2, 0), (3, 4), (4, 5), (5, 3), (0, 3), (1, 4), (2, 5))
# ccx C3D15 corners in dolfinx's reference prism.
_WEDGE_CORNERS = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]])


def nodal_extrapolation(element_type: str, points: np.ndarray) -> np.ndarray:
    """``(nodes, points)`` matrix taking integration-point values to the element's nodes.

    C3D8: ccx's weights (``C3D8_EXTRAPOLATION``) of the trilinear field through the 2x2x2 Gauss
    values; C3D4: the constant; C3D10: the linear field through the 4 point values at the
    corners, midside nodes the mean of their edge's corners. ``points`` are the rule's points
    (dolfinx reference coordinates, ccx order).
    """
    if element_type == "C3D4":
        return np.ones((4, 1))
    if element_type in ("C3D8", "C3D8I"):
        sides = (points > 0.5).astype(int)
        distance = np.sum(_HEX_CORNERS[:, None, :] != sides[None, :, :], axis=2)
        return np.asarray(C3D8_EXTRAPOLATION)[distance]
    if element_type == "C3D10":
        affine = np.column_stack([np.ones(4), points])  # value = c0 + c . x through the points
        corners = np.array([[1, 0, 0, 0], [1, 1, 0, 0], [1, 0, 1, 0], [1, 0, 0, 1]], float)
        corner = corners @ np.linalg.inv(affine)
        midside = np.array([(corner[a] + corner[b]) / 2 for a, b in _TET_EDGES])
        return np.vstack([corner, midside])
    if element_type == "C3D20R":
        corner = nodal_extrapolation("C3D8", points)
        midside = np.array([(corner[a] + corner[b]) / 2 for a, b in _HEX_EDGES])
        return np.vstack([corner, midside])
    if element_type == "C3D20":
        return _c3d20_extrapolation(points)
    if element_type == "C3D15":
        # ccx 2.20's (fitted to its .frd stresses of one element under random nodal
        # displacements, to print precision): linear in the triangle through its 3 points,
        # linear along the axis by least squares through the 3 layers, at the 15 nodes
        nodes = np.vstack(
            [_WEDGE_CORNERS, [(_WEDGE_CORNERS[a] + _WEDGE_CORNERS[b]) / 2 for a, b in _WEDGE_EDGES]]
        )
        return _wedge_basis(nodes) @ np.linalg.pinv(_wedge_basis(points))
    if element_type[:3] in TWO_D_MODELS and element_type[3:] == "3":
        return np.ones((3, 1))
    if element_type[:3] in TWO_D_MODELS and element_type[3:] in ("8", "8R"):
        # corners: the bilinear field through the 2x2 points, or the quad8 field through the
        # 3x3 points (least squares, exact for quad8 fields); midside nodes the means
        if points.shape[0] == 4:
            corner = nodal_extrapolation(element_type[:3] + "4", points)
        else:
            corner = np.linalg.pinv(_quad8_shapes(points))[:4]
        return np.vstack([corner, [(corner[a] + corner[b]) / 2 for a, b in _QUAD_EDGES]])
    if element_type[:3] in TWO_D_MODELS and element_type[3:] == "6":
        # the linear field through the 3 point values, at the corners; midside nodes the means
        affine = np.column_stack([np.ones(3), points])
        corner = np.array([[1, 0, 0], [1, 1, 0], [1, 0, 1]], float) @ np.linalg.inv(affine)
        return np.vstack([corner, [(corner[a] + corner[b]) / 2 for a, b in _TRI_EDGES]])
    if element_type[:3] in TWO_D_MODELS and element_type[3:] == "4":
        # the bilinear field through the 2x2 Gauss values, at the corners
        corners = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
        sides = (points > 0.5).astype(int)
        distance = np.sum(corners[:, None, :] != sides[None, :, :], axis=2)
        s3 = np.sqrt(3.0)
        return np.array([(1 + s3) ** 2 / 4, -0.5, (1 - s3) ** 2 / 4])[distance]
    raise NotImplementedError(f"stress extrapolation of {element_type} is not supported")


#: ccx 2.20's C3D20 extrapolation weights from the 3x3x3 Gauss points, by how the point lies
#: from the node along each axis (n: the point layer nearest the node, m: the middle layer, f:
#: the farthest); a midside node's key starts with c (the point in the middle layer along its
#: edge) or o (an outer layer). They are the triquadratic values through the 27 points (products
#: of ``(1 + sqrt .6) / 1.2, -2/3, (1 - sqrt .6) / 1.2``; zero in the outer layers) changed by at
#: most 6e-6, fitted to ccx's ``.frd`` stresses of one element under random nodal displacements;
#: rows sum to 0.99996 at corners and 1.00005 at midside nodes, as ccx writes a uniform stress
#: (docs/method.md §13.5).
C3D20_EXTRAPOLATION = {
    "nnn": 3.2341145, "mnn": -1.4579587, "fnn": 0.4107842, "mmn": 0.6572575,
    "fmn": -0.1851893, "ffn": 0.0521753, "mmm": -0.2962968, "fmm": 0.0834806,
    "ffm": -0.0235225, "fff": 0.0066279,
    "cnn": 2.1869451, "cmn": -0.9858814, "cfn": 0.2777794, "cmm": 0.4444462, "cfm": -0.1252212,
    "cff": 0.0352856,
    "onn": 0.0000019, "omn": 0.0000015, "ofn": -0.0000001, "omm": 0.0000004, "ofm": 0.0000012,
    "off": 0.0000018,
}  # fmt: skip


def _wedge_basis(points: np.ndarray) -> np.ndarray:
    """``(q, 6)`` the products of ``1, x, y`` and ``1, z`` at reference prism ``points``."""
    x, y, z = points.T
    plane = np.column_stack([np.ones_like(x), x, y])
    axis = np.column_stack([np.ones_like(z), z])
    return np.einsum("qi,qj->qij", plane, axis).reshape(-1, 6)


def _quad8_shapes(points: np.ndarray) -> np.ndarray:
    """``(q, 8)`` quad8 serendipity shape functions at unit-square ``points`` (ccx node order)."""
    xi, eta = 2 * points[:, 0] - 1, 2 * points[:, 1] - 1
    corners = [(-1, -1), (1, -1), (1, 1), (-1, 1)]
    out = [(1 + xi * a) * (1 + eta * b) * (xi * a + eta * b - 1) / 4 for a, b in corners]
    out += [(1 - xi**2) * (1 - eta) / 2, (1 + xi) * (1 - eta**2) / 2]
    out += [(1 - xi**2) * (1 + eta) / 2, (1 - xi) * (1 - eta**2) / 2]
    return np.column_stack(out)


def _c3d20_extrapolation(points: np.ndarray) -> np.ndarray:
    """``(20, 27)`` ccx's C3D20 weights (``C3D20_EXTRAPOLATION``) for the 3x3x3 Gauss points."""
    nodes = np.vstack(
        [_HEX_CORNERS, [(_HEX_CORNERS[a] + _HEX_CORNERS[b]) / 2 for a, b in _HEX_EDGES]]
    )
    layer = np.digitize(points, [0.4, 0.6])  # 0, 1, 2: low, middle, high layer per axis
    weights = np.zeros((20, points.shape[0]))
    for i, node in enumerate(nodes):  # 20 x 27 table entries, built once at import
        for q in range(points.shape[0]):
            edge, key = "", []
            for axis in range(3):
                if node[axis] == 0.5:  # along a midside node's edge
                    edge = "c" if layer[q, axis] == 1 else "o"
                    continue
                near = 0 if node[axis] == 0 else 2
                key.append("m" if layer[q, axis] == 1 else ("n" if layer[q, axis] == near else "f"))
            weights[i, q] = C3D20_EXTRAPOLATION[edge + "".join(sorted(key, key="fmn".index))]
    return weights


_G = 1.0 / np.sqrt(3.0)
_A10, _B10 = 0.1381966011250105, 0.5854101966249685
_G3 = (-np.sqrt(0.6), 0.0, np.sqrt(0.6))
_TRI_POINTS = ((1 / 6, 1 / 6), (2 / 3, 1 / 6), (1 / 6, 2 / 3))

# C3D8 2x2x2 Gauss points in ccx order (xi fastest); C3D4 one point; C3D10 four points.
_POINTS = {
    "C3D4": [[0.25, 0.25, 0.25]],
    "C3D8": [
        [(x + 1) / 2, (y + 1) / 2, (z + 1) / 2]
        for z in (-_G, _G)
        for y in (-_G, _G)
        for x in (-_G, _G)
    ],
    "C3D10": [[_A10, _A10, _A10], [_B10, _A10, _A10], [_A10, _B10, _A10], [_A10, _A10, _B10]],
    # C3D20: 3x3x3 Gauss, xi fastest (checked against ccx's *EL PRINT); C3D20R as C3D8.
    "C3D20": [[(x + 1) / 2, (y + 1) / 2, (z + 1) / 2] for z in _G3 for y in _G3 for x in _G3],
    # C3D15: ccx's 9 points, the 3 triangle points fastest in each of the 3 Gauss layers (the
    # order ccx prints the C3D15 of a CPE6, docs/method.md §23; checked on C3D15, §34).
    "C3D15": [[a, b, (z + 1) / 2] for z in _G3 for a, b in _TRI_POINTS],
}
_POINTS["C3D20R"] = _POINTS["C3D8I"] = _POINTS["C3D8"]
# 2D elements: the in-plane points of ccx's expanded element (2x2 Gauss, xi fastest; one point).
for _family in TWO_D_MODELS:
    _POINTS[_family + "4"] = [[(x + 1) / 2, (y + 1) / 2] for y in (-_G, _G) for x in (-_G, _G)]
    _POINTS[_family + "3"] = [[1 / 3, 1 / 3]]
    _POINTS[_family + "6"] = [[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]
    _POINTS[_family + "8"] = [[(x + 1) / 2, (y + 1) / 2] for y in _G3 for x in _G3]
    _POINTS[_family + "8R"] = _POINTS[_family + "4"]


# ccx 2.20's .frd node order where it is not ccx's own (checked against ccx's .frd files):
# C3D20 nodes 1..12, 17..20, 13..16; C3D15 nodes 1..9, 13..15, 10..12.
_FRD_ORDERS = {
    20: [*range(12), 16, 17, 18, 19, 12, 13, 14, 15],
    15: [*range(9), 12, 13, 14, 9, 10, 11],
}


def _element_type(
    name: str,
    num_nodes: int,
    num_corners: int,
    face_type: str,
    faces: list[list[int]],
    *,
    cell: str,
    degree: int,
    to_dolfinx: list[int],
    mirrored_vertices: list[int],
    quadrature_degree: int,
    frd_type: int,
    face_quadrature_degree: int = 2,
    print_rows: list[int] | None = None,
) -> ElementType:
    points = frozen_array(_POINTS[name], np.float64)
    midside = {10: _TET_EDGES, 20: _HEX_EDGES, 6: _TRI_EDGES, 8: _QUAD_EDGES, 15: _WEDGE_EDGES}
    midside_edges = midside[num_nodes] if num_nodes > num_corners else ()
    return ElementType(
        name,
        num_nodes,
        num_corners,
        face_type,
        frozen_array(np.asarray(faces) - 1, np.int64),
        cell,
        degree,
        frozen_array(to_dolfinx, np.int64),
        frozen_array(mirrored_vertices, np.int64),
        midside_edges,
        quadrature_degree,
        points,
        frd_type,
        frozen_array(nodal_extrapolation(name, points), np.float64),
        face_quadrature_degree,
        frozen_array(_FRD_ORDERS[num_nodes], np.int64) if num_nodes in _FRD_ORDERS else None,
        None if print_rows is None else frozen_array(print_rows, np.int64),
    )


ELEMENT_TYPES: dict[str, ElementType] = {
    # Manual: S1 1-2-3, S2 1-4-2, S3 2-4-3, S4 3-4-1 (inward); reversed here to point outward.
    "C3D4": _element_type(
        "C3D4",
        4,
        4,
        "tri3",
        [[1, 3, 2], [1, 2, 4], [2, 3, 4], [1, 4, 3]],
        cell="tetrahedron",
        degree=1,
        to_dolfinx=[0, 1, 2, 3],
        mirrored_vertices=[0, 2, 1, 3],
        quadrature_degree=1,
        frd_type=3,
    ),
    # Midside nodes: 5 on 1-2, 6 on 2-3, 7 on 3-1, 8 on 1-4, 9 on 2-4, 10 on 3-4 (manual fig. 55).
    # dolfinx P2 tetrahedron edges are (v2,v3), (v1,v3), (v1,v2), (v0,v3), (v0,v2), (v0,v1).
    "C3D10": _element_type(
        "C3D10",
        10,
        4,
        "tri6",
        [[1, 3, 2, 7, 6, 5], [1, 2, 4, 5, 9, 8], [2, 3, 4, 6, 10, 9], [1, 4, 3, 8, 10, 7]],
        cell="tetrahedron",
        degree=2,
        to_dolfinx=[0, 1, 2, 3, 9, 8, 5, 7, 6, 4],
        mirrored_vertices=[0, 2, 1, 3],
        quadrature_degree=2,
        frd_type=6,
    ),
    # Manual: S1 1-2-3-4, S2 5-8-7-6, S3 1-5-6-2, S4 2-6-7-3, S5 3-7-8-4, S6 4-8-5-1 (inward).
    # dolfinx hexahedron vertices are in tensor order. C3D8I: C3D8's nodes, faces and Gauss
    # points; the model adds its incompatible modes (docs/method.md §22).
    **{
        name: _element_type(
            name,
            8,
            8,
            "quad4",
            [[4, 3, 2, 1], [5, 6, 7, 8], [1, 2, 6, 5], [2, 3, 7, 6], [3, 4, 8, 7], [4, 1, 5, 8]],
            cell="hexahedron",
            degree=1,
            to_dolfinx=[0, 1, 3, 2, 4, 5, 7, 6],
            mirrored_vertices=[4, 5, 7, 6, 0, 1, 3, 2],
            quadrature_degree=2,
            frd_type=1,
        )
        for name in ("C3D8", "C3D8I")
    },
    # C3D20 (3x3x3 Gauss) and C3D20R (2x2x2): corners as C3D8, midside nodes 9..20 on the edges
    # _HEX_EDGES; faces as C3D8's, then the midside nodes of edges c1-c2, c2-c3, c3-c4, c4-c1.
    # The dolfinx cell is a 27-node hexahedron: to_dolfinx gives its corners and edge nodes (v0-v1,
    # v0-v2, v0-v4, v1-v3, v1-v5, v2-v3, v2-v6, v3-v7, v4-v5, v4-v6, v5-v7, v6-v7); the model adds
    # the face and cell centres and constrains them to the serendipity space (docs/method.md §13.5).
    **{
        name: _element_type(
            name,
            20,
            8,
            "quad8",
            [
                [4, 3, 2, 1, 11, 10, 9, 12],
                [5, 6, 7, 8, 13, 14, 15, 16],
                [1, 2, 6, 5, 9, 18, 13, 17],
                [2, 3, 7, 6, 10, 19, 14, 18],
                [3, 4, 8, 7, 11, 20, 15, 19],
                [4, 1, 5, 8, 12, 17, 16, 20],
            ],
            cell="hexahedron",
            degree=2,
            to_dolfinx=[0, 1, 3, 2, 4, 5, 7, 6, 8, 11, 16, 9, 17, 10, 19, 18, 12, 15, 13, 14],
            mirrored_vertices=[4, 5, 7, 6, 0, 1, 3, 2],
            quadrature_degree=quadrature,
            frd_type=4,
            face_quadrature_degree=quadrature,
        )
        for name, quadrature in (("C3D20", 5), ("C3D20R", 2))
    },
    # C3D15 (dolfinx 0.11 only, docs/method.md §34): triangle 1-2-3 below 4-5-6, midside nodes
    # 7..15 on _WEDGE_EDGES. Faces (manual): S1 1-2-3 (reversed here to point outward), S2 4-5-6,
    # S3 1-2-5-4, S4 2-3-6-5, S5 3-1-4-6, then their midside nodes; the triangles are padded
    # with -1 to the quadrilaterals' 8 nodes (``ElementType.face_sizes``). The dolfinx cell is
    # an 18-node prism: vertices, edges v0-v1, v0-v2, v0-v3, v1-v2, v1-v4, v2-v5, v3-v4, v3-v5,
    # v4-v5, then the centres of the quadrilateral faces, which the model adds and constrains
    # to the serendipity space (fem/serendipity_wedge.py). ccx's 9 points (3 x 3).
    "C3D15": _element_type(
        "C3D15",
        15,
        6,
        "quad8",
        [
            [1, 3, 2, 9, 8, 7, 0, 0],
            [4, 5, 6, 10, 11, 12, 0, 0],
            [1, 2, 5, 4, 7, 14, 10, 13],
            [2, 3, 6, 5, 8, 15, 11, 14],
            [3, 1, 4, 6, 9, 13, 12, 15],
        ],
        cell="prism",
        degree=2,
        to_dolfinx=[0, 1, 2, 3, 4, 5, 6, 8, 12, 7, 13, 14, 9, 11, 10],
        mirrored_vertices=[3, 4, 5, 0, 1, 2],
        quadrature_degree=5,
        frd_type=5,
        face_quadrature_degree=5,
    ),
    # ccx's 2D elements (manual "Face numbering for quadrilateral elements": S1 1-2, S2 2-3,
    # S3 3-4, S4 4-1; triangles S1 1-2, S2 2-3, S3 3-1), run natively in 2D (docs/method.md §23).
    # ccx expands a 4-node element into one C3D8 and prints its 8 points (two equal layers of the
    # 2x2 in-plane points), a 3-node one into a C3D6 wedge with 2 points (one per layer).
    **{
        family + "4": _element_type(
            family + "4",
            4,
            4,
            "line2",
            [[1, 2], [2, 3], [3, 4], [4, 1]],
            cell="quadrilateral",
            degree=1,
            to_dolfinx=[0, 1, 3, 2],
            mirrored_vertices=[1, 0, 2, 3],
            quadrature_degree=2,
            frd_type=9,
            print_rows=[0, 1, 2, 3, 0, 1, 2, 3],
        )
        for family in TWO_D_MODELS
    },
    **{
        family + "3": _element_type(
            family + "3",
            3,
            3,
            "line2",
            [[1, 2], [2, 3], [3, 1]],
            cell="triangle",
            degree=1,
            to_dolfinx=[0, 1, 2],
            mirrored_vertices=[0, 2, 1],
            quadrature_degree=1,
            frd_type=7,
            print_rows=[0, 0],
        )
        for family in TWO_D_MODELS
    },
    # 8-node quadrilaterals (midside nodes 5..8 on 1-2, 2-3, 3-4, 4-1): Q2 quadrilaterals whose
    # centre the model adds and constrains to the serendipity space (fem/serendipity_quad.py);
    # ccx expands them into C3D20 (27 points: 3 layers of 3x3) or C3D20R (8: 2 layers of 2x2).
    # dolfinx Q2 quadrilateral edges are (v0,v1), (v0,v2), (v1,v3), (v2,v3).
    **{
        family + suffix: _element_type(
            family + suffix,
            8,
            4,
            "line3",
            [[1, 2, 5], [2, 3, 6], [3, 4, 7], [4, 1, 8]],
            cell="quadrilateral",
            degree=2,
            to_dolfinx=[0, 1, 3, 2, 4, 7, 5, 6],
            mirrored_vertices=[1, 0, 2, 3],
            quadrature_degree=quadrature,
            frd_type=10,
            print_rows=layers * list(range(points)),
        )
        for family in TWO_D_MODELS
        for suffix, quadrature, points, layers in (("8", 4, 9, 3), ("8R", 2, 4, 2))
    },
    # 6-node triangles (midside nodes 4 on 1-2, 5 on 2-3, 6 on 3-1), P2 triangles: ccx expands
    # them into C3D15 wedges and prints their 3 x 3 points (3 layers of the 3 in-plane points).
    # dolfinx P2 triangle edges are (v1,v2), (v0,v2), (v0,v1).
    **{
        family + "6": _element_type(
            family + "6",
            6,
            3,
            "line3",
            [[1, 2, 4], [2, 3, 5], [3, 1, 6]],
            cell="triangle",
            degree=2,
            to_dolfinx=[0, 1, 2, 4, 5, 3],
            mirrored_vertices=[0, 2, 1],
            quadrature_degree=2,
            frd_type=8,
            print_rows=[0, 1, 2, 0, 1, 2, 0, 1, 2],
        )
        for family in TWO_D_MODELS
    },
}
"""Supported element types by ccx name."""


#: Why some common ccx elements are refused (appended to the reader's refusal).
REFUSED_ELEMENTS = {
    "C3D8R": ": its one-point integration with hourglass control is not reproduced",
    **{
        family + suffix: ": its one-point integration with hourglass control is not reproduced "
        "(3-, 4-, 6- and 8-node CPE, CPS and CAX elements run)"
        for family in TWO_D_MODELS
        for suffix in ("4R",)
    },
}


_NOT_PLAIN = ("C3D20", "C3D20R", "C3D8I", "C3D15")


def element_for_cell(cell: str, degree: int) -> ElementType | None:
    """The ccx element of a degree-``degree`` Lagrange space on ``cell`` cells, or None.

    None for degree-2 hexahedra: a 27-node space is not C3D20's (docs/method.md §13.5); C3D8
    for degree-1 hexahedra (C3D8I needs its modes, which a plain space does not have). Only 3D
    elements: a 2D cell has several ccx elements (CPE, CPS, CAX).
    """
    for etype in ELEMENT_TYPES.values():
        if (
            etype.tdim == 3
            and etype.cell == cell
            and etype.degree == degree
            and etype.name not in _NOT_PLAIN
        ):
            return etype
    return None
