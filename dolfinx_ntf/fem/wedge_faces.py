"""Tagged faces of 18-node prism meshes as node tuples, and their pressure forces.

dolfinx 0.11 numbers a prism mesh's triangles and quadrilaterals as two facet types and gives
neither ``ds`` nor ``exterior_facet_indices`` on it ("Multiple entity types in mesh",
docs/method.md §34.4). The faces of such a mesh are therefore held as rows of mesh input nodes
(:class:`PrismFaces`, made by ``meshes/gmsh_io.py``), and a pressure on them becomes consistent
nodal forces (``kernels.faces.pressure_forces``, ccx's face rules), as the deck runner's C3D15
pressures (docs/method.md §40). :func:`prism_face_surface` gives them as a contact surface
(:class:`~dolfinx_ntf.fem.surfaces.FaceNodesSurface`, docs/method.md §40.6); the deck runner's
C3D15 surfaces are built by the same :func:`c3d15_face_surface` (§38).

Local nodes of basix's degree-2 prism (``fem/serendipity_wedge.py``): 0..5 the vertices, 6..14
the edges (0-1, 0-2, 0-3, 1-2, 1-4, 2-5, 3-4, 3-5, 4-5), 15..17 the quadrilateral face centres
(0-1-3-4, 0-2-3-5, 1-2-4-5). :data:`WEDGE_FACES` lists the five faces in CalculiX's face-local
order (corners counter-clockwise seen from outside, then the midside nodes; a quadrilateral's
centre last), ccx's C3D15 faces S1..S5.
"""

from __future__ import annotations

from dataclasses import dataclass

from mpi4py import MPI

import numpy as np

import dolfinx.fem

from dolfinx_ntf import compat
from dolfinx_ntf.fem.surfaces import FaceNodesSurface
from dolfinx_ntf.kernels.faces import QUAD8_GAUSS2, QUAD9, TRI6, pressure_forces

__all__ = [
    "WEDGE_FACES",
    "PrismFaces",
    "c3d15_face_surface",
    "prism_face_forces",
    "prism_face_surface",
]

#: The five faces of the 18-node prism (basix local nodes), outward, in ccx's order S1..S5:
#: triangles as tri6, quadrilaterals as quad9 (quad8 order, then the centre).
WEDGE_FACES: tuple[tuple[int, ...], ...] = (
    (0, 2, 1, 7, 9, 6),
    (3, 4, 5, 12, 14, 13),
    (0, 1, 4, 3, 6, 10, 12, 8, 15),
    (1, 2, 5, 4, 9, 11, 14, 10, 17),
    (2, 0, 3, 5, 7, 8, 13, 11, 16),
)

_G2 = 1.0 / np.sqrt(3.0)
#: ccx's rules for pressures on C3D15 faces (measured, docs/method.md §34.4): 3 points on the
#: 6-node triangles, 2 x 2 Gauss points on the quadrilaterals.
_TRI_RULE = (np.array([[1 / 6, 1 / 6], [2 / 3, 1 / 6], [1 / 6, 2 / 3]]), np.full(3, 1 / 6))
_QUAD_RULE = (np.array([[x, y] for y in (-_G2, _G2) for x in (-_G2, _G2)]), np.ones(4))
#: A quadrilateral centre's value from its face's 8 other nodes (the serendipity constraint).
_CENTRE_WEIGHTS = np.array([-0.25] * 4 + [0.5] * 4)


@dataclass(frozen=True)
class PrismFaces:
    """Tagged faces of a prism mesh as rows of input node indices (the same on every process).

    Node indices are the mesh's input indices (``mesh.geometry.input_global_indices``: gmsh node
    tag - 1; the face centres added to 15-node prisms after gmsh's nodes). Faces are oriented
    outward from the cell they bound.

    Attributes:
        triangles: ``(T, 6)`` 6-node triangles (tri6 order).
        triangle_tags: ``(T,)`` the physical group of each triangle.
        quadrilaterals: ``(Q, 9)`` quadrilaterals (quad8 order, then the centre node).
        quadrilateral_tags: ``(Q,)`` the physical group of each quadrilateral.
    """

    triangles: np.ndarray
    triangle_tags: np.ndarray
    quadrilaterals: np.ndarray
    quadrilateral_tags: np.ndarray

    @property
    def values(self) -> np.ndarray:
        """The tags present, sorted."""
        return np.union1d(self.triangle_tags, self.quadrilateral_tags)

    def find(self, tag: int) -> tuple[np.ndarray, np.ndarray]:
        """``(triangles, quadrilaterals)`` of physical group ``tag``.

        Raises:
            ValueError: no face has the tag (naming the tags there are).
        """
        tri = self.triangles[self.triangle_tags == tag]
        quad = self.quadrilaterals[self.quadrilateral_tags == tag]
        if tri.shape[0] + quad.shape[0] == 0:
            raise ValueError(f"PrismFaces: no face has tag {tag!r} (tags: {self.values.tolist()})")
        return tri, quad


def prism_face_forces(
    V: dolfinx.fem.FunctionSpace, faces: PrismFaces, tag: int, pressure: float
) -> dolfinx.fem.Function:
    """Consistent nodal forces of a uniform ``pressure`` on the faces tagged ``tag``.

    A positive pressure pushes against the outward normal. ccx's face rules (3 points on the
    triangles, 2 x 2 Gauss points on the quadrilaterals); a quadrilateral centre's share goes to
    its face's 8 other nodes with the serendipity weights (virtual work in C3D15's space), so the
    forces sit on C3D15's 15 nodes. Computed for all faces on every process (set-up data).

    Args:
        V: The vector degree-2 space on the 18-node prism mesh the faces were read with.
        faces: The mesh's tagged faces.
        tag: Physical group of the loaded faces.
        pressure: Pressure (force per area).

    Returns:
        A function whose values (owned and ghost dofs) are the nodal forces: add its owned
        values to an assembled right-hand side.
    """
    mesh = V.mesh
    if V.dofmap.index_map_bs != 3:
        raise ValueError("prism_face_forces: a 3-component vector space is needed")
    triangles, quads = faces.find(tag)
    input_index = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    x = mesh.geometry.x
    largest = max(input_index.max(initial=-1), triangles.max(initial=-1), quads.max(initial=-1))
    num_input = mesh.comm.allreduce(int(largest), op=MPI.MAX) + 1
    coords = np.zeros((num_input, 3))
    known = np.zeros(num_input, dtype=bool)
    coords[input_index], known[input_index] = x[:, :3], True
    # every process needs the coordinates of every loaded face: the nodes are gathered once
    coords, known = _gathered(mesh.comm, coords, known)
    loaded = np.concatenate([triangles.ravel(), quads.ravel()])
    if not np.all(known[loaded]):
        missing = int(loaded[~known[loaded]][0])
        raise ValueError(f"prism_face_forces: face node {missing} (input index) is not in the mesh")
    forces = np.zeros((num_input, 3))
    if triangles.size:
        f = pressure_forces(
            TRI6, coords[triangles], np.full(triangles.shape[0], pressure), _TRI_RULE
        )
        np.add.at(forces, triangles, f)
    if quads.size:
        f = pressure_forces(QUAD9, coords[quads], np.full(quads.shape[0], pressure), _QUAD_RULE)
        f = f[:, :8] + _CENTRE_WEIGHTS[None, :, None] * f[:, 8:9]
        np.add.at(forces, quads[:, :8], f)
    dof_of_node = _geometry_node_dofs(V)
    out = dolfinx.fem.Function(V)
    values = out.x.array.reshape(-1, 3)
    has = dof_of_node >= 0
    values[dof_of_node[has]] = forces[input_index[has]]
    return out


def _geometry_node_dofs(V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """The local block dof of ``V`` at each local geometry node (-1 for none)."""
    mesh = V.mesh
    dof_of_node = np.full(mesh.geometry.x.shape[0], -1, dtype=np.int64)
    dof_of_node[compat.geometry_dofs(mesh).ravel()] = compat.cell_dofs(V).ravel()
    return dof_of_node


def c3d15_face_surface(
    name: str,
    quadrilaterals: np.ndarray | None = None,
    triangles: np.ndarray | None = None,
) -> FaceNodesSurface:
    """A contact surface of C3D15 faces given by their nodes, with ccx's face rules.

    The quadrilaterals are 8-node faces whose spring areas take ccx's 2 x 2 Gauss points
    (``QUAD8_GAUSS2``, docs/method.md §38.2), the triangles 6-node faces; a surface of both
    kinds gives the triangles as the ``more`` faces (a slave, or a contact pair's master:
    docs/method.md §38.8). Shared by the deck runner (``calculix/model/c3d15.py``) and
    :func:`prism_face_surface`.

    Args:
        name: Label used in messages.
        quadrilaterals: ``(Q, 8)`` local block dofs in ccx's face order, or None where the
            surface has no quadrilaterals on any process (an array, maybe empty, where some
            process has them: every process gives the same kinds).
        triangles: ``(T, 6)`` local block dofs, or None likewise.
    """
    groups = [
        (face_type, faces)
        for face_type, faces in ((QUAD8_GAUSS2, quadrilaterals), (TRI6, triangles))
        if faces is not None
    ]
    if not groups:
        raise ValueError(f"c3d15_face_surface: surface '{name}' has no faces of either kind")
    (face_type, faces), *more = groups
    return FaceNodesSurface(face_type, faces, name, more=tuple(more))


def prism_face_surface(
    V: dolfinx.fem.FunctionSpace, faces: PrismFaces, tag: int, name: str | None = None
) -> FaceNodesSurface:
    """The faces tagged ``tag`` as a contact surface of ``V`` (a slave or a master).

    Each face becomes the block dofs of its nodes in ccx's order, outward (the quadrilaterals'
    centres left out: C3D15's quad8 faces, whose centre the face-centre constraints of
    :func:`~dolfinx_ntf.fem.serendipity_wedge.wedge15_space` fix), with ccx's face rules
    (:func:`c3d15_face_surface`). On several processes each process gives the faces whose nodes
    it holds (owned or ghost: those of its owned and ghost cells); the contact problem drops
    the faces two processes give. Pass the ``constraints`` of
    :func:`~dolfinx_ntf.fem.serendipity_wedge.wedge15_space` to the contact problem, so that its
    springs see C3D15's faces (docs/method.md §40.6).

    Args:
        V: The vector degree-2 space on the 18-node prism mesh the faces were read with
            (:func:`~dolfinx_ntf.fem.serendipity_wedge.wedge15_space`).
        faces: The mesh's tagged faces (``meshes.gmsh_io.mesh_from_gmsh``).
        tag: Physical group of the surface. Triangles and quadrilaterals both make a surface
            of two face types (a slave, or a contact pair's master, docs/method.md §38.8).
        name: Label used in messages (default ``"faces <tag>"``).

    Raises:
        ValueError: no face has the tag; a face node that is not a node of the mesh.
    """
    if V.dofmap.index_map_bs != 3:
        raise ValueError("prism_face_surface: a 3-component vector space is needed")
    name = f"faces {tag}" if name is None else name
    triangles, quads = faces.find(tag)
    mesh = V.mesh
    input_index = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)
    largest = max(input_index.max(initial=-1), triangles.max(initial=-1), quads.max(initial=-1))
    dof_of_input = np.full(int(largest) + 1, -1, dtype=np.int64)
    dof_of_input[input_index] = _geometry_node_dofs(V)
    given = np.concatenate([triangles.ravel(), quads.ravel()])
    held = np.isin(given, input_index).astype(np.int32)
    mesh.comm.Allreduce(MPI.IN_PLACE, held, op=MPI.MAX)
    if not np.all(held):
        missing = int(given[np.argmin(held)])
        raise ValueError(
            f"prism_face_surface: face node {missing} (input index) of tag {tag} is not a node "
            "of the mesh"
        )
    kinds = []
    for rows in (quads[:, :8], triangles):
        dofs = dof_of_input[rows]
        kinds.append(dofs[np.all(dofs >= 0, axis=1)] if rows.size else None)
    return c3d15_face_surface(name, quadrilaterals=kinds[0], triangles=kinds[1])


def _gathered(
    comm: MPI.Comm, coords: np.ndarray, known: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The coordinates of the input nodes any process holds, on every process."""
    if comm.size == 1:
        return coords, known
    weight = known.astype(float)
    total = comm.allreduce(coords * weight[:, None], op=MPI.SUM)
    count = comm.allreduce(weight, op=MPI.SUM)
    seen = count > 0
    total[seen] /= count[seen, None]
    return total, seen
