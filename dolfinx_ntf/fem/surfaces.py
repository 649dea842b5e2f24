"""Contact surfaces of a dolfinx mesh as faces of displacement nodes (dolfinx glue).

A *node* here is a block dof of the vector displacement space ``V`` (P1 or P2): the spring elements
move with the displacement dofs, so surfaces are expressed in ``V``'s local block numbering (owned
and ghost). Faces come out in CalculiX order: corners counter-clockwise seen from outside the body,
then midside nodes (see ``faces.py``).

Users name surfaces with :class:`FacetSurface` (facet-tag values, the face-based surfaces of
CalculiX) or :class:`NodeSurface` (a vertex set, CalculiX's ``*SURFACE, TYPE=NODE``);
:class:`FaceNodesSurface` gives a face-based surface by its faces' nodes where dolfinx numbers no
facets (prism meshes on dolfinx 0.11, docs/method.md §38). :func:`resolve_master` and
:func:`resolve_slave` turn them into numbering-level data for the pure-numpy layers.
"""

from __future__ import annotations

import typing
from dataclasses import dataclass, field

from mpi4py import MPI

import numpy as np

import dolfinx.cpp
import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat, validation
from dolfinx_ntf.kernels.edges import EdgeType, edge_type_from_num_nodes
from dolfinx_ntf.kernels.faces import FaceType, face_type_from_num_nodes

__all__ = [
    "NO_FACET",
    "FaceNodesSurface",
    "FacetSurface",
    "NodeSurface",
    "SlaveSurface",
    "SurfaceFaces",
    "boundary_faces",
    "faces_touching",
    "facet_cells",
    "master_face_groups",
    "reference_coordinates",
    "resolve_master",
    "resolve_slave",
]


@dataclass(frozen=True)
class FacetSurface:
    """A face-based surface: the facets of ``tags`` whose value is in ``values``.

    Args:
        tags: Facet tags of the mesh (e.g. from :func:`dolfinx_ntf.meshes.gmsh_io.mesh_from_gmsh`).
        values: One tag value or several; each must occur in ``tags`` (on some process).
    """

    tags: compat.MeshTags
    values: typing.Sequence[int] | int

    def __post_init__(self) -> None:
        """Check the tags and values (a ``TypeError`` or ``ValueError`` naming the value)."""
        # dolfinx 0.5.2's gmshio returns C++ MeshTags objects: check what is used, not the class.
        if not all(hasattr(self.tags, name) for name in ("dim", "indices", "values")):
            raise TypeError(
                "FacetSurface: tags must be the facet MeshTags of the mesh, got "
                f"{validation.describe(self.tags)}"
            )
        self.value_list()

    def value_list(self) -> list[int]:
        """The tag values as a list."""
        values = [self.values] if np.isscalar(self.values) else self.values
        if isinstance(values, (str, bytes)) or not isinstance(values, typing.Iterable):
            raise TypeError(
                f"FacetSurface: values must be an int or a list of ints, got "
                f"{validation.describe(self.values)}"
            )
        values = list(values)
        if not values:
            raise ValueError(
                "FacetSurface: values is empty; give the facet tag value(s) of the surface"
            )
        for i, value in enumerate(values):
            if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)):
                raise TypeError(
                    f"FacetSurface: values must be integer tag values, but entry {i} is "
                    f"{validation.describe(value)}"
                )
        return [int(v) for v in values]


@dataclass(frozen=True)
class NodeSurface:
    """A node-based slave surface (CalculiX ``*SURFACE, TYPE=NODE``): local mesh vertex indices.

    Args:
        vertices: Indices of mesh vertices (this process's local numbering, as
            ``dolfinx.mesh.locate_entities(mesh, 0, marker)`` returns them). They must lie on the
            boundary of the mesh; non-integer, negative or out-of-range indices are errors.
        name: Label used in messages.
        midside_nodes: Local block dofs of the displacement space at the surface's other nodes
            (midside nodes of quadratic elements, which a ccx node set lists too, or the deck
            runner's nodes in no element, §29.6); they are slave nodes as well and must lie on
            the boundary. As in ccx, they take no share of the faces' area (their springs get
            the fallback area, docs/method.md §2.2). One process only.
        faceless: Every node of the surface takes no share of the faces' area: all springs get
            the fallback area (``ContactPair.fallback_area``). ccx does this to the node sets
            of 2D elements, whose 2D nodes belong to none of its expanded 3D elements
            (docs/method.md §26.3).
        exterior: The exterior faces of the mesh given by their nodes, for meshes whose facets
            dolfinx does not number (C3D15's prisms, docs/method.md §38); this process's, each
            process the same face types. None: dolfinx's exterior facets.
    """

    vertices: np.ndarray = field(repr=False)
    name: str = "nodes"
    midside_nodes: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int32), repr=False)
    faceless: bool = False
    exterior: FaceNodesSurface | None = field(default=None, repr=False)

    def __post_init__(self) -> None:
        """Check the indices and store them as an int32 array."""
        validation.check_type(self.name, str, "NodeSurface: name")
        validation.check_type(self.faceless, bool, "NodeSurface: faceless")
        if self.exterior is not None:
            validation.check_type(self.exterior, FaceNodesSurface, "NodeSurface: exterior")
        owner = f"NodeSurface '{self.name}'"
        object.__setattr__(self, "vertices", validation.vertex_indices(self.vertices, owner))
        midside = np.asarray(self.midside_nodes).ravel()
        if midside.size and (
            not np.issubdtype(midside.dtype, np.integer) or int(midside.min()) < 0
        ):
            raise ValueError(f"{owner}: midside_nodes must be non-negative block dof indices")
        object.__setattr__(self, "midside_nodes", midside.astype(np.int32))

    @classmethod
    def from_marker(
        cls,
        mesh: dolfinx.mesh.Mesh,
        marker: typing.Callable[[np.ndarray], np.ndarray],
        name: str = "nodes",
    ) -> NodeSurface:
        """The vertices where ``marker(x)`` is true (``x`` of shape (3, num_points))."""
        return cls(dolfinx.mesh.locate_entities(mesh, 0, marker), name)


#: The facet index of a face that is no dolfinx facet of this process: another process's face,
#: or a face given by its nodes (:class:`FaceNodesSurface`). Facet-based code skips it.
NO_FACET = -1


@dataclass(frozen=True)
class SurfaceFaces:
    """Faces of one face type as node (block dof) connectivity in CalculiX order."""

    face_type: FaceType | EdgeType
    faces: np.ndarray  # (F, n) local block dofs
    facets: np.ndarray  # (F,) local facet index of each face, NO_FACET for none

    @property
    def nodes(self) -> np.ndarray:
        """Sorted unique nodes of the faces."""
        return np.unique(self.faces)


@dataclass(frozen=True)
class FaceNodesSurface:
    """A face-based surface given by the nodes of its faces instead of dolfinx facets.

    For meshes whose facets dolfinx does not number: dolfinx 0.11 gives a prism mesh two facet
    types, and ``ds``, ``exterior_facet_indices`` and ``connectivity(2, 0)`` raise "Multiple
    entity types in mesh" there (C3D15 decks, docs/method.md §38). Its faces have no facet
    index (``NO_FACET``), so facet-based outputs (the recovered pressure) leave them out.

    Args:
        face_type: The type of every face (e.g. ``TRI6`` or ``QUAD8`` of ``kernels.faces``).
        faces: ``(F, n)`` local block dofs of the displacement space, one row per face in
            CalculiX order: corners counter-clockwise seen from outside the body, then the
            midside nodes. On several processes each gives the faces of its cells (owned and
            ghost); a process may give none.
        name: Label used in messages.
        more: Faces of further types, ``(face_type, faces)`` each, e.g. the triangles of a
            surface of triangles and quadrilaterals (C3D15). Every process gives the same
            types. A master of several types is searched as one surface, its springs per type
            (``master_face_groups``, docs/method.md §38.8).
    """

    face_type: FaceType
    faces: np.ndarray = field(repr=False)
    name: str = "faces"
    more: tuple[tuple[FaceType, np.ndarray], ...] = field(default=(), repr=False)

    def __post_init__(self) -> None:
        """Check the face types and the node rows; store them as int32 arrays."""
        validation.check_type(self.name, str, "FaceNodesSurface: name")
        object.__setattr__(self, "faces", self._checked(self.face_type, self.faces))
        more = tuple(self.more)
        for k, group in enumerate(more):
            if not isinstance(group, tuple) or len(group) != 2:
                raise TypeError(
                    f"FaceNodesSurface '{self.name}': more[{k}] must be a (face_type, faces) "
                    f"tuple, got {validation.describe(group)}"
                )
        groups = tuple((t, self._checked(t, f)) for t, f in more)
        types = [self.face_type, *(t for t, _ in groups)]
        if len({id(t) for t in types}) < len(types):
            raise ValueError(
                f"FaceNodesSurface '{self.name}': a face type is given twice "
                f"({', '.join(t.name for t in types)}); give the faces of each type once"
            )
        object.__setattr__(self, "more", groups)

    def _checked(self, face_type: object, faces: np.ndarray) -> np.ndarray:
        """``faces`` as a contiguous int32 ``(F, n)`` array of ``face_type`` (or an error)."""
        owner = f"FaceNodesSurface '{self.name}'"
        validation.check_type(face_type, FaceType, f"{owner}: face_type")
        faces = np.asarray(faces)
        n = face_type.num_nodes
        if faces.size == 0:
            faces = np.zeros((0, n), dtype=np.int32)
        if faces.ndim != 2 or faces.shape[1] != n or not np.issubdtype(faces.dtype, np.integer):
            raise ValueError(
                f"{owner}: faces must be an integer array of shape (F, {n}) for "
                f"{face_type.name} faces, got shape {faces.shape} and dtype {faces.dtype}"
            )
        if faces.size and int(faces.min()) < 0:
            raise ValueError(f"{owner}: faces must hold block dofs >= 0, got {int(faces.min())}")
        return np.ascontiguousarray(faces, dtype=np.int32)

    def surface_faces(self, V: dolfinx.fem.FunctionSpace, what: str) -> SurfaceFaces:
        """The faces as :class:`SurfaceFaces` of ``V`` (a ``ValueError`` for a node outside V)."""
        return self._surface_faces(V, what, self.face_type, self.faces)

    def face_groups(self, V: dolfinx.fem.FunctionSpace, what: str) -> tuple[SurfaceFaces, ...]:
        """The faces of every type as :class:`SurfaceFaces` of ``V``, the first type first."""
        more = (self._surface_faces(V, what, t, f) for t, f in self.more)
        return (self.surface_faces(V, what), *more)

    def _surface_faces(
        self, V: dolfinx.fem.FunctionSpace, what: str, face_type: FaceType, faces: np.ndarray
    ) -> SurfaceFaces:
        index_map = V.dofmap.index_map
        num_nodes = index_map.size_local + index_map.num_ghosts
        if faces.size and int(faces.max()) >= num_nodes:
            raise ValueError(
                f"{what}: FaceNodesSurface '{self.name}' has node {int(faces.max())}, "
                f"outside 0..{num_nodes - 1} (the displacement space's nodes on this process)"
            )
        facets = np.full(faces.shape[0], NO_FACET, dtype=np.int32)
        return SurfaceFaces(face_type, faces, facets)


@dataclass(frozen=True)
class SlaveSurface:
    """Slave nodes and the faces (edges of a 2D mesh) that give them spring area (§2.1).

    ``faceless`` marks slave nodes that take no share of the faces' area and get CalculiX's
    fallback area instead (ccx: the midside nodes of a node-based surface, §13.5); None: none.
    ``more_faces`` holds faces of further types (a C3D15 surface of 6-node triangles and 8-node
    quadrilaterals, docs/method.md §38.4): their areas add to the nodes' as ``faces``' do.
    """

    nodes: np.ndarray  # (S,) sorted local block dofs
    faces: SurfaceFaces
    faceless: np.ndarray | None = None  # (S,) bool
    thickness: float = 1.0  # 2D meshes: the spring areas are tributary lengths times this
    axisymmetric: bool = False  # 2D meshes: ring areas 2 pi ∫ r φ_p ds instead (§17.2)
    area_weights: str = "consistent"  # 2D meshes: "ccx" for ccx's expanded faces' shares (§23)
    more_faces: tuple[SurfaceFaces, ...] = ()

    @property
    def face_groups(self) -> tuple[SurfaceFaces, ...]:
        """``faces`` and ``more_faces``: the slave faces of each face type."""
        return (self.faces, *self.more_faces)


def reference_coordinates(V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """Reference coordinates of the nodes of ``V``, shape (num_local_blocks_with_ghosts, 3).

    Nodes at mesh vertices of a Lagrange space take the mesh's own coordinates: the push-forward
    of ``tabulate_dof_coordinates`` adds round-off (1e-17 off a plane ``z = 0``), which decides
    whether a slave node placed on a master face starts open or closed (docs/method.md §3.4).
    So do all nodes of a space with the geometry's nodes (C3D10, C3D20: the midside nodes).
    """
    X = V.tabulate_dof_coordinates().reshape(-1, 3).copy()
    if compat.space_family(V) not in ("Lagrange", "P", "Q", "CG"):
        return X
    mesh = V.mesh
    vertices = dolfinx.cpp.mesh.cell_num_vertices(mesh.topology.cell_type)
    cell_dofs, geometry = compat.cell_dofs(V), compat.geometry_dofs(mesh)
    for width in dict.fromkeys((cell_dofs.shape[1], vertices)):  # Lagrange: vertex nodes first
        if width > geometry.shape[1]:
            continue
        dofs = cell_dofs[:, :width].ravel()
        exact = mesh.geometry.x[geometry[:, :width].ravel()]
        scale = 1e-9 * np.ptp(exact, axis=0).max() if dofs.size else 0.0
        if dofs.size and np.allclose(X[dofs], exact, rtol=0.0, atol=scale):
            X[dofs] = exact
            break
    return X


def _cell_arrays(V: dolfinx.fem.FunctionSpace) -> tuple[np.ndarray, np.ndarray]:
    """Cell-to-node table of ``V`` and the facet-closure table of the reference cell."""
    mesh = V.mesh
    tdim = mesh.topology.dim
    cell_nodes = compat.cell_dofs(V)
    layout = V.dofmap.dof_layout
    num_facets_per_cell = dolfinx.cpp.mesh.cell_num_entities(mesh.topology.cell_type, tdim - 1)
    closure = np.array(
        [layout.entity_closure_dofs(tdim - 1, i) for i in range(num_facets_per_cell)]
    )
    return cell_nodes, closure


def boundary_faces(
    V: dolfinx.fem.FunctionSpace,
    facets: np.ndarray,
    *,
    what: str = "surface",
    reference: np.ndarray | None = None,
) -> SurfaceFaces:
    """Faces of boundary facets as nodes of ``V`` in CalculiX order, oriented out of their cell.

    Args:
        V: Vector displacement space (P1 or P2, tetrahedra or hexahedra).
        facets: Local facet indices; each must belong to exactly one cell.
        what: Name of the surface, used in error messages.
        reference: ``reference_coordinates(V)`` if the caller has them (computed otherwise: a
            pass over every node of ``V``).
    """
    mesh = V.mesh
    tdim = mesh.topology.dim
    if tdim not in (2, 3):
        raise ValueError(f"{what}: only 2D and 3D meshes are supported, got a {tdim}D mesh")
    facets = np.asarray(facets, dtype=np.int32)
    cells, local_facet = facet_cells(mesh, facets, what)

    cell_nodes, closure = _cell_arrays(V)
    closure_nodes = cell_nodes[cells[:, None], closure[local_facet]]
    X = reference_coordinates(V) if reference is None else reference
    if tdim == 2:
        return _boundary_edges(X, cell_nodes[cells], closure_nodes, facets)
    face_type = face_type_from_num_nodes(closure.shape[1])
    num_corners = face_type.num_corners
    corners = closure_nodes[:, :num_corners]
    if num_corners == 4:  # dolfinx quads are in tensor order: 0-1-3-2 goes round
        corners = corners[:, [0, 1, 3, 2]]

    # Orient the corner cycle so that its normal points away from the cell centre.
    xc = X[corners]
    normal = (
        np.cross(xc[:, 2] - xc[:, 0], xc[:, -1] - xc[:, 1])
        if num_corners == 4
        else np.cross(xc[:, 1] - xc[:, 0], xc[:, 2] - xc[:, 0])
    )
    outward = np.einsum("fi,fi->f", normal, xc.mean(axis=1) - X[cell_nodes[cells]].mean(axis=1))
    flip = outward < 0
    corners[flip, 1:] = corners[flip, 1:][:, ::-1]

    faces = corners
    if face_type.num_nodes > num_corners:
        faces = np.hstack([corners, _midside_nodes(X, corners, closure_nodes[:, num_corners:])])
    return SurfaceFaces(face_type, np.ascontiguousarray(faces, dtype=np.int32), facets)


def _boundary_edges(
    X: np.ndarray, cell_nodes: np.ndarray, closure_nodes: np.ndarray, facets: np.ndarray
) -> SurfaceFaces:
    """Boundary edges of a 2D mesh: corners with the body on the left, then the midside node."""
    edge_type = edge_type_from_num_nodes(closure_nodes.shape[1])
    corners = closure_nodes[:, :2].copy()
    tangent = X[corners[:, 1], :2] - X[corners[:, 0], :2]
    outward = X[corners, :2].mean(axis=1) - X[cell_nodes, :2].mean(axis=1)
    flip = tangent[:, 1] * outward[:, 0] - tangent[:, 0] * outward[:, 1] < 0  # (t_y, -t_x)·o
    corners[flip] = corners[flip, ::-1]
    faces = np.hstack([corners, closure_nodes[:, 2:]])
    return SurfaceFaces(edge_type, np.ascontiguousarray(faces, dtype=np.int32), facets)


def facet_cells(
    mesh: dolfinx.mesh.Mesh, facets: np.ndarray, what: str
) -> tuple[np.ndarray, np.ndarray]:
    """The cell of each boundary facet and the facet's local index in it.

    Raises a ValueError naming ``what`` if a facet lies between two cells.
    """
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    mesh.topology.create_connectivity(tdim, tdim - 1)
    f_to_c = mesh.topology.connectivity(tdim - 1, tdim)
    c_to_f = mesh.topology.connectivity(tdim, tdim - 1)
    num_cells_of_facet = f_to_c.offsets[facets + 1] - f_to_c.offsets[facets]
    interior = np.flatnonzero(num_cells_of_facet != 1)
    if interior.size:
        x = dolfinx.mesh.compute_midpoints(mesh, tdim - 1, facets[interior[:1]])[0]
        raise ValueError(
            f"{what}: {interior.size} facet(s) lie between two cells, not on the boundary "
            f"(first at ({x[0]:.6g}, {x[1]:.6g}, {x[2]:.6g}))"
        )
    cells = f_to_c.array[f_to_c.offsets[facets]]
    facets_per_cell = dolfinx.cpp.mesh.cell_num_entities(mesh.topology.cell_type, tdim - 1)
    cell_facets = c_to_f.array.reshape(-1, facets_per_cell)
    local_facet = np.argmax(cell_facets[cells] == facets[:, None], axis=1)
    return cells, local_facet


def _midside_nodes(X: np.ndarray, corners: np.ndarray, others: np.ndarray) -> np.ndarray:
    """Midside nodes in CalculiX order (edge c0-c1, c1-c2, ...), then any centre node.

    The closure order of edge dofs is dolfinx's, so each edge's node is found as the candidate
    nearest the edge midpoint in the reference configuration (exact for straight edges, robust for
    curved ones).
    """
    num_corners = corners.shape[1]
    midpoints = 0.5 * (X[corners] + X[np.roll(corners, -1, axis=1)])  # (F, c, 3)
    distance = np.linalg.norm(
        midpoints[:, :, None, :] - X[others][:, None, :, :], axis=-1
    )  # (F, c, m)
    choice = np.argmin(distance[:, :, :num_corners], axis=2)
    edge_nodes = np.take_along_axis(others, choice, axis=1)
    if np.any(np.sort(choice, axis=1) != np.arange(num_corners)):
        raise ValueError("could not match midside nodes to face edges (distorted quadratic faces)")
    return np.hstack([edge_nodes, others[:, num_corners:]])


def _tagged_facets(surface: FacetSurface, mesh: dolfinx.mesh.Mesh, what: str) -> np.ndarray:
    """Local facets of a facet surface; tag values absent on every process are an error."""
    tags = surface.tags
    tdim = mesh.topology.dim
    if not compat.tags_on_mesh(tags, mesh):
        raise ValueError(
            f"{what}: the facet tags were made on another mesh than the displacement's (build "
            "them on the mesh of u's function space; equal meshes are still different meshes)"
        )
    if tags.dim != tdim - 1:
        given = {0: "vertex tags", tdim: "cell tags"}.get(tags.dim, "edge tags")
        facets = "edges" if tdim == 2 else "faces"
        raise ValueError(
            f"{what}: MeshTags of dimension {tags.dim} given ({given}), facet tags "
            f"(dimension {tdim - 1}, the {facets} of the {tdim}D mesh) needed"
        )
    values = surface.value_list()
    facets = tags.indices[np.isin(tags.values, values)]
    # A process may hold no facet of a value that others have: decide on the global set.
    present = set().union(*mesh.comm.allgather(set(np.unique(tags.values).tolist())))
    missing = [v for v in values if v not in present]
    if missing:
        raise ValueError(
            f"{what}: facet tag value(s) {missing} not found in the facet tags "
            f"(values present: {sorted(present)})"
        )
    return facets


def resolve_master(
    V: dolfinx.fem.FunctionSpace,
    surface: FacetSurface | FaceNodesSurface,
    what: str = "master",
    *,
    reference: np.ndarray | None = None,
) -> SurfaceFaces:
    """Master faces of a face-based surface (``reference``: as :func:`boundary_faces` takes it)."""
    if isinstance(surface, FaceNodesSurface):
        if surface.more:
            types = ", ".join(g.face_type.name for g in surface.face_groups(V, what))
            raise NotImplementedError(
                f"{what}: FaceNodesSurface '{surface.name}' holds faces of several types "
                f"({types}): here a master surface of one face type only is supported (contact "
                "pairs take several, master_face_groups)"
            )
        return surface.surface_faces(V, what)
    if not isinstance(surface, FacetSurface):
        raise ValueError(
            f"{what}: the master surface must be a FacetSurface or a FaceNodesSurface "
            f"(face-based), got {type(surface).__name__}"
        )
    facets = _tagged_facets(surface, V.mesh, what)
    return boundary_faces(V, facets, what=what, reference=reference)


def master_face_groups(
    V: dolfinx.fem.FunctionSpace,
    surface: FacetSurface | FaceNodesSurface,
    what: str = "master",
    *,
    reference: np.ndarray | None = None,
) -> tuple[SurfaceFaces, ...]:
    """Master faces of each face type (one group but for a ``FaceNodesSurface`` with ``more``).

    Args:
        V: The displacement space.
        surface: The face-based master surface.
        what: Label for messages.
        reference: As :func:`boundary_faces` takes it.
    """
    if isinstance(surface, FaceNodesSurface) and surface.more:  # docs/method.md §38.8
        return surface.face_groups(V, what)
    return (resolve_master(V, surface, what, reference=reference),)


def resolve_slave(
    V: dolfinx.fem.FunctionSpace,
    surface: FacetSurface | NodeSurface | FaceNodesSurface,
    what: str = "slave",
    *,
    reference: np.ndarray | None = None,
) -> SlaveSurface:
    """Slave nodes and area faces (docs/method.md §2.1).

    Face-based: the listed faces; slave nodes are all their nodes. Node-based: the slave faces are
    all exterior faces of the mesh with at least one corner among the slave nodes.
    ``reference``: as :func:`boundary_faces` takes it.
    """
    if isinstance(surface, FaceNodesSurface):
        first, *more = surface.face_groups(V, what)
        nodes = np.unique(np.concatenate([first.faces.ravel(), *(g.faces.ravel() for g in more)]))
        return SlaveSurface(nodes.astype(first.faces.dtype), first, more_faces=tuple(more))
    if isinstance(surface, FacetSurface):
        facets = _tagged_facets(surface, V.mesh, what)
        faces = boundary_faces(V, facets, what=what, reference=reference)
        return SlaveSurface(faces.nodes, faces)
    if not isinstance(surface, NodeSurface):
        raise TypeError(
            f"{what}: expected a FacetSurface, NodeSurface or FaceNodesSurface, got "
            f"{type(surface).__name__}"
        )
    vertices = surface.vertices
    mesh = V.mesh
    comm = mesh.comm
    label = f"{what}: node surface '{surface.name}'"
    num_vertices = mesh.topology.index_map(0).size_local + mesh.topology.index_map(0).num_ghosts
    outside = np.flatnonzero(vertices >= num_vertices)
    validation.raise_collectively(
        comm,
        ValueError(
            f"{label}: vertex index {int(vertices[outside[0]])} (entry {int(outside[0])}) is "
            f"outside 0..{num_vertices - 1} (the vertices of the mesh on this process)"
        )
        if outside.size
        else None,
    )
    if comm.allreduce(int(vertices.size + surface.midside_nodes.size), op=MPI.SUM) == 0:
        raise ValueError(f"{label} has no vertices")
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(0, tdim)
    nodes = np.unique(dolfinx.fem.locate_dofs_topological(V, 0, vertices))
    X = reference_coordinates(V) if reference is None else reference
    if surface.exterior is not None:  # no facet numbering (C3D15's prisms, §38)
        groups = surface.exterior.face_groups(V, what)
    else:
        mesh.topology.create_connectivity(tdim - 1, tdim)
        exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
        groups = (boundary_faces(V, exterior, what=what, reference=X),)
    corners = np.concatenate([g.faces[:, : g.face_type.num_corners].ravel() for g in groups])
    to_global = V.dofmap.index_map.local_to_global
    _check_on_boundary(comm, label, nodes, corners, X, to_global)
    faces, *more = (faces_touching(g, np.isin(np.arange(X.shape[0]), nodes)) for g in groups)
    more = tuple(more)
    midside = surface.midside_nodes
    if comm.allreduce(int(midside.size), op=MPI.MAX):
        on_faces = np.isin(midside, np.concatenate([g.faces.ravel() for g in groups]))
        if comm.size > 1:  # on global numbers: another process may hold the node's faces
            held = np.asarray(to_global(midside[on_faces].astype(np.int32)), dtype=np.int64)
            held = np.concatenate(comm.allgather(held))
            on_faces = np.isin(np.asarray(to_global(midside.astype(np.int32))), held)
        outside = midside[~on_faces]
        if outside.size:
            x = reference_coordinates(V)[outside[0]]
            raise ValueError(
                f"{label}: {outside.size} midside node(s) are not on the boundary (first at "
                f"({x[0]:.6g}, {x[1]:.6g}, {x[2]:.6g}))"
            )
        nodes = np.union1d(nodes, midside).astype(nodes.dtype)
        faceless = np.ones(nodes.size, bool) if surface.faceless else np.isin(nodes, midside)
        return SlaveSurface(nodes, faces, faceless, more_faces=more)
    if surface.faceless:
        return SlaveSurface(nodes, faces, np.ones(nodes.size, dtype=bool), more_faces=more)
    return SlaveSurface(nodes, faces, more_faces=more)


def faces_touching(faces: SurfaceFaces, marked: np.ndarray) -> SurfaceFaces:
    """The faces with a corner among the ``marked`` nodes (a flag per local node)."""
    touching = marked[faces.faces[:, : faces.face_type.num_corners]].any(axis=1)
    return SurfaceFaces(faces.face_type, faces.faces[touching], faces.facets[touching])


def _check_on_boundary(
    comm: MPI.Comm,
    label: str,
    nodes: np.ndarray,
    corners: np.ndarray,
    X: np.ndarray,
    to_global: typing.Callable[[np.ndarray], np.ndarray],
) -> None:
    """Node-surface vertices inside the mesh: an error if all are, a warning if some are.

    Decided on global node numbers: a vertex a process holds without its boundary faces (held by
    another process) is on the boundary all the same.
    """
    node_ids = np.asarray(to_global(nodes.astype(np.int32)), dtype=np.int64)
    boundary = np.asarray(to_global(nodes[np.isin(nodes, corners)].astype(np.int32)))
    all_nodes = np.unique(np.concatenate(comm.allgather(node_ids)))
    on_boundary = np.concatenate(comm.allgather(boundary)).astype(np.int64)
    interior_ids = np.setdiff1d(all_nodes, on_boundary)
    interior = nodes[np.isin(node_ids, interior_ids)]
    num_interior = int(interior_ids.size)
    if num_interior == 0:
        return
    total = int(all_nodes.size)
    where = ""
    if interior.size:
        x = X[interior[0]]
        where = f" (first at ({x[0]:.6g}, {x[1]:.6g}, {x[2]:.6g}))"
    if num_interior == total:
        raise ValueError(
            f"{label}: none of its {total} vertices lies on the boundary of the mesh{where}; "
            "slave nodes must be on the surface of a body"
        )
    if comm.rank == 0:
        validation.warn(
            f"{label}: {num_interior} of its {total} vertices are inside the mesh, not on its "
            f"boundary{where}; they collect no spring area"
        )
