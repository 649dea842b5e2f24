"""Gmsh models and .msh files to dolfinx meshes with cell and facet tags.

dolfinx 0.5.2 imports only the cells and facets that belong to gmsh physical groups, and its
``gmshio.read_from_msh`` is broken; this module wraps ``gmshio.model_to_mesh`` instead.

Prisms (6-node wedges, e.g. from ``extrude(..., recombine=True)`` of a triangulated surface),
alone or beside hexahedra, are read as hexahedra with one collapsed edge, as the deck runner reads
C3D6 (``kernels/collapsed_wedges.py``, docs/method.md §30 and §32): one mesh of hexahedra on every
dolfinx release. Their triangles are facets (quadrilaterals with a repeated corner) that facet
tags, contact surfaces and ``ds`` take like any other.

Second-order prisms (gmsh's 15-node type 18 and 18-node type 13, alone) become a mesh of 18-node
prisms on dolfinx 0.11 (docs/method.md §40): a 15-node prism's quadrilateral centres are placed
by the quad8 map (CalculiX C3D15's geometry), an 18-node prism keeps gmsh's. dolfinx 0.11 has no
facets on prism meshes (two facet types), so the tagged faces come back as a
:class:`~dolfinx_ntf.fem.wedge_faces.PrismFaces` (rows of input nodes, outward) instead of facet
tags; ``fem.serendipity_wedge.wedge15_space`` and ``fem.wedge_faces.prism_face_forces`` solve on
them. Older releases refuse such models (NotImplementedError).

Shared rules:
    * Every public function is collective over ``comm``. gmsh is touched on rank ``rank`` only,
      so the other ranks need neither gmsh initialized nor a model. ``comm`` is the only
      communicator used: ``MPI.COMM_SELF`` on one process of several builds a serial mesh there,
      provided every process imported dolfinx (its import initializes PETSc, collective over
      COMM_WORLD; docs/method.md §44).
    * Errors found on ``rank`` (missing file, unreadable file, no physical groups, mixed cell types,
      builder failures) are broadcast so that *all* ranks raise the same exception type instead of
      deadlocking in the next collective.
    * gmsh is initialized when needed (quietly: ``General.Terminal = 0``) and finalized again only
      if this module initialized it; a session the caller opened is left open with its current
      model and terminal setting restored.
    * Facet tags hold the facets of the tagged surfaces seen by each rank, ghosts included.
"""

from __future__ import annotations

import contextlib
import functools
import itertools
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from mpi4py import MPI

import gmsh
import numpy as np

import basix
import dolfinx.mesh
from dolfinx.mesh import Mesh

from dolfinx_ntf import compat
from dolfinx_ntf.compat import MeshTags
from dolfinx_ntf.fem.collapsed_wedges import create_collapsed_mesh
from dolfinx_ntf.fem.serendipity_wedge import (
    add_wedge_centres,
    require_quadratic_prisms,
    wedge15_rule,
)
from dolfinx_ntf.fem.wedge_faces import WEDGE_FACES, PrismFaces
from dolfinx_ntf.kernels.collapsed_wedges import (
    WedgeRotationError,
    collapse_wedges,
    collapsed_jacobians,
    wedge_rotations,
)

__all__ = ["gmsh_session", "mesh_from_gmsh", "model_to_mesh", "read_msh", "write_msh"]

_model_counter = itertools.count()
#: gmsh's serendipity cell types, which dolfinx has no coordinate element for.
_INCOMPLETE = {16: "8-node quadrilaterals", 17: "20-node hexahedra"}
#: gmsh element types of the prism path: 3-node triangles, 4-node quadrilaterals, 8-node
#: hexahedra, 6-node prisms.
_TRIANGLE, _QUADRILATERAL, _HEXAHEDRON, _PRISM = 2, 3, 5, 6
#: Second-order prisms (gmsh element type: what it is), read as 18-node prisms on dolfinx 0.11.
_OTHER_PRISMS = {13: "18-node prisms", 18: "15-node prisms"}
#: Their faces: 6-node triangles, 9-node and 8-node quadrilaterals (gmsh element types).
_QUADRATIC_FACES = {9: 6, 10: 9, 16: 8}
#: A second-order prism mirrored (triangle 1-3-2 below 4-6-5), the same element: basix's nodes.
_MIRROR = np.array([0, 2, 1, 3, 5, 4, 7, 6, 8, 9, 11, 10, 13, 12, 14, 16, 15, 17])
#: gmsh's hexahedron (and ccx's C3D8) corner order to dolfinx's.
_HEX_TO_DOLFINX = np.array([0, 1, 3, 2, 4, 5, 7, 6])


def _track_initialization() -> dict[str, bool] | None:
    """For gmsh without ``isInitialized`` (4.8): follow ``gmsh.initialize``/``finalize`` calls.

    Any other API call before ``initialize`` or after ``finalize`` reads a context gmsh 4.8 does
    not have, and its error handler then calls ``exit(1)`` at random (measured: silent exits of
    Python with status 1). The wrappers record the state instead; a session opened before this
    module was imported is not seen.
    """
    if hasattr(gmsh, "isInitialized"):
        return None
    state = {"initialized": False}
    initialize, finalize = gmsh.initialize, gmsh.finalize
    if getattr(initialize, "_dolfinx_ntf_tracked", False):
        return initialize._dolfinx_ntf_state

    def tracked_initialize(*args, **kwargs):
        initialize(*args, **kwargs)
        state["initialized"] = True

    def tracked_finalize(*args, **kwargs):
        state["initialized"] = False
        finalize(*args, **kwargs)

    tracked_initialize._dolfinx_ntf_tracked = True
    tracked_initialize._dolfinx_ntf_state = state
    gmsh.initialize, gmsh.finalize = tracked_initialize, tracked_finalize
    return state


_gmsh_state = _track_initialization()


@functools.cache
def _prism18_derivatives() -> np.ndarray:
    """``(3, 9, 18)`` derivatives of basix's degree-2 prism functions at ccx's 9 points."""
    element = basix.create_element(
        basix.ElementFamily.P, basix.CellType.prism, 2, basix.LagrangeVariant.equispaced
    )
    return element.tabulate(1, wedge15_rule()[0])[1:4, :, :, 0]


def _gmsh_is_initialized() -> bool:
    """Whether the gmsh API is initialized (gmsh 4.8 has no ``gmsh.isInitialized``)."""
    probe = getattr(gmsh, "isInitialized", None)
    if probe is not None:
        return bool(probe())
    return bool(_gmsh_state and _gmsh_state["initialized"])


@contextlib.contextmanager
def gmsh_session(*, terminal: bool = False) -> Iterator[None]:
    """Context in which the gmsh API is usable, on the calling process only (not collective).

    Initializes gmsh if it is not yet initialized and finalizes it on exit in that case. In a
    session opened by the caller, the current model and ``General.Terminal`` are restored on exit
    (models added inside stay unless removed).

    Args:
        terminal: Let gmsh print its messages.
    """
    started = not _gmsh_is_initialized()
    if started:
        gmsh.initialize()
        previous_model, previous_terminal = None, None
    else:
        previous_model = gmsh.model.getCurrent()
        previous_terminal = gmsh.option.getNumber("General.Terminal")
    gmsh.option.setNumber("General.Terminal", int(terminal))
    try:
        yield
    finally:
        if started:
            gmsh.finalize()
        else:
            if previous_model in gmsh.model.list():
                gmsh.model.setCurrent(previous_model)
            gmsh.option.setNumber("General.Terminal", previous_terminal)


def model_to_mesh(
    comm: MPI.Comm = MPI.COMM_WORLD, *, rank: int = 0, gdim: int = 3
) -> tuple[Mesh, MeshTags, MeshTags | PrismFaces]:
    """Distributed dolfinx mesh and tags from the current gmsh model on ``rank``.

    Cells are the elements of the physical groups of the highest dimension, tagged with the group
    numbers; facets those of the physical groups one dimension lower. Collective.

    Args:
        comm: Communicator of the mesh.
        rank: Rank holding the gmsh model (with its mesh generated).
        gdim: Geometric dimension of the mesh.

    Returns:
        ``(mesh, cell_tags, facet_tags)``; for 15- or 18-node prisms ``(mesh, cell_tags,
        faces)`` with ``faces`` a :class:`~dolfinx_ntf.fem.wedge_faces.PrismFaces`.

    Prisms, alone or beside hexahedra, become hexahedra with a collapsed edge (the module's
    docstring); their facets may then be triangles and quadrilaterals. Second-order prisms
    become 18-node prisms (dolfinx 0.11 and later).

    Raises:
        ValueError: The model has no physical groups or no mesh, an entity sits in two physical
            groups of the same dimension, the cells (facets) are not all of one element type
            (other than prisms beside hexahedra), prisms cannot be collapsed, or a second-order
            prism has a Jacobian ``<= 0`` at one of ccx's 9 points (naming them).
        NotImplementedError: Second-order prisms on dolfinx older than 0.11.
    """
    _check_rank(comm, rank)
    if gdim not in (1, 2, 3):
        raise ValueError(f"gdim must be 1, 2 or 3, got {gdim!r}")
    error, path = None, "dolfinx"
    if comm.rank == rank:
        try:
            path = _prepare_model()
        except ValueError as exc:
            error = exc
    _raise_everywhere(comm, rank, error)
    path = comm.bcast(path, root=rank)
    if path == "prisms":
        return _collapsed_prism_mesh(comm, rank, gdim)
    if path == "quadratic prisms":
        return _quadratic_prism_mesh(comm, rank, gdim)
    return compat.model_to_mesh(gmsh.model, comm, rank, gdim)


def read_msh(
    path: str | Path, comm: MPI.Comm = MPI.COMM_WORLD, *, rank: int = 0, gdim: int = 3
) -> tuple[Mesh, MeshTags, MeshTags | PrismFaces]:
    """Distributed dolfinx mesh and tags from a gmsh .msh file read on ``rank``. Collective.

    Args:
        path: The .msh file (path as seen from ``rank``).
        comm: Communicator of the mesh.
        rank: Rank that reads the file with the gmsh API.
        gdim: Geometric dimension of the mesh.

    Returns:
        ``(mesh, cell_tags, facet_tags)`` with the physical group numbers as tag values
        (second-order prisms: the faces as a ``PrismFaces``, see `model_to_mesh`).

    Raises:
        FileNotFoundError: ``path`` is not a file.
        ValueError: gmsh cannot read the file, or the file has no physical groups (see
            `model_to_mesh`).
    """
    _check_rank(comm, rank)
    path = Path(path)
    with _on_rank(comm, rank):
        added = False
        try:
            error: Exception | None = None
            if comm.rank == rank:
                if not path.is_file():
                    error = FileNotFoundError(f"gmsh mesh file not found: '{path}'")
                else:
                    gmsh.model.add(f"dolfinx_ntf_read_{next(_model_counter)}")
                    added = True
                    try:
                        gmsh.merge(str(path))
                    except Exception as exc:  # gmsh raises bare Exception
                        error = ValueError(f"gmsh cannot read mesh file '{path}': {exc}")
            _raise_everywhere(comm, rank, error)
            try:
                return model_to_mesh(comm, rank=rank, gdim=gdim)
            except ValueError as exc:
                raise ValueError(f"mesh file '{path}': {exc}") from exc
        finally:
            if added:
                gmsh.model.remove()


def mesh_from_gmsh(
    build: Callable[..., Any],
    comm: MPI.Comm = MPI.COMM_WORLD,
    *,
    rank: int = 0,
    gdim: int = 3,
    **kwargs: Any,
) -> tuple[Mesh, MeshTags, MeshTags | PrismFaces]:
    """Run a gmsh model builder on ``rank`` and distribute its mesh. Collective.

    Typical use with the builders of ``dolfinx_ntf.meshes``:
    ``mesh, cell_tags, facet_tags = mesh_from_gmsh(build_punch, comm, cell_type="tetrahedron")``.

    Args:
        build: Called as ``build(**kwargs)`` on ``rank`` inside a gmsh session; it must leave the
            meshed model current (it may add a new model). Models it adds are removed afterwards.
        comm: Communicator of the mesh.
        rank: Rank that runs ``build``.
        gdim: Geometric dimension of the mesh.
        **kwargs: Passed to ``build``.

    Returns:
        ``(mesh, cell_tags, facet_tags)`` (second-order prisms: the faces as a ``PrismFaces``,
        see `model_to_mesh`).

    Raises:
        Exception: Whatever ``build`` raised, on every rank (as the same type where possible).
        ValueError: See `model_to_mesh`.
    """
    _check_rank(comm, rank)
    with _on_rank(comm, rank):
        error: Exception | None = None
        models_before: list[str] = []
        if comm.rank == rank:
            models_before = gmsh.model.list()
            try:
                build(**kwargs)
            except Exception as exc:
                error = exc
        try:
            _raise_everywhere(comm, rank, error)
            return model_to_mesh(comm, rank=rank, gdim=gdim)
        finally:
            if comm.rank == rank:
                for name in gmsh.model.list():
                    if name not in models_before:
                        gmsh.model.setCurrent(name)
                        gmsh.model.remove()


@contextlib.contextmanager
def _on_rank(comm: MPI.Comm, rank: int) -> Iterator[None]:
    """A gmsh session on ``rank`` only; a no-op context elsewhere."""
    if comm.rank == rank:
        with gmsh_session():
            yield
    else:
        yield


def _check_rank(comm: MPI.Comm, rank: int) -> None:
    """Reject a root rank outside the communicator (same answer on every rank)."""
    if not 0 <= rank < comm.size:
        raise ValueError(f"rank must be in [0, {comm.size}), got {rank!r}")


def _raise_everywhere(comm: MPI.Comm, rank: int, error: Exception | None) -> None:
    """Broadcast an error found on ``rank`` and raise it on all ranks.

    ``rank`` re-raises its own exception object (traceback kept); the others raise the same type
    with the same message, or a RuntimeError if that type cannot be rebuilt from a message.
    """
    shared = comm.bcast(None if error is None else (type(error), str(error)), root=rank)
    if shared is None:
        return
    if comm.rank == rank:
        raise error
    kind, message = shared
    try:
        rebuilt = kind(message)
    except Exception:
        rebuilt = RuntimeError(f"{kind.__name__} on rank {rank}: {message}")
    raise rebuilt


def _prepare_model() -> str:
    """Check the current gmsh model can go through dolfinx's ``model_to_mesh``; renumber nodes.

    dolfinx reads the elements of every physical group, keeps the highest dimension as cells and
    the next one as facets, assumes one element type for each and contiguous node tags. Returns
    ``"dolfinx"`` then; ``"prisms"`` for 6-node prisms (with or without hexahedra, the
    collapsed-hexahedron path), ``"quadratic prisms"`` for 15- or 18-node prisms (§40).

    Raises:
        ValueError: Naming the model and the offending group or entity.
    """
    model = gmsh.model.getCurrent() or "<default>"
    groups = gmsh.model.getPhysicalGroups()
    if not groups:
        raise ValueError(
            f"gmsh model '{model}' has no physical groups: dolfinx imports only the cells of "
            "physical groups (add them with gmsh.model.addPhysicalGroup)"
        )
    tdim = max(dim for dim, _ in groups)
    prisms = quadratic = False
    for dim in (tdim, tdim - 1):
        owner: dict[int, int] = {}
        types: set[int] = set()
        for group_dim, group in groups:
            if group_dim != dim:
                continue
            for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, group):
                if entity in owner:
                    raise ValueError(
                        f"gmsh model '{model}': entity ({dim}, {entity}) is in physical groups "
                        f"{owner[entity]} and {group}; dolfinx would duplicate its elements"
                    )
                owner[entity] = group
                entity_types, _, _ = gmsh.model.mesh.getElements(dim, entity)
                if len(entity_types) > 1:
                    raise ValueError(
                        f"gmsh model '{model}': entity ({dim}, {entity}) of physical group {group} "
                        f"mixes element types {list(entity_types)}"
                    )
                types.update(int(t) for t in entity_types)
        if dim == tdim == 3 and types & set(_OTHER_PRISMS):
            if len(types) > 1:
                names = [gmsh.model.mesh.getElementProperties(t)[0] for t in sorted(types)]
                raise ValueError(
                    f"gmsh model '{model}': physical groups of dimension 3 mix element types "
                    f"{names}; second-order prisms are read alone (15- or 18-node, one kind)"
                )
            quadratic = True
            continue
        if quadratic:
            other = sorted(types - set(_QUADRATIC_FACES))
            if other:
                names = [gmsh.model.mesh.getElementProperties(t)[0] for t in other]
                raise ValueError(
                    f"gmsh model '{model}': the tagged faces of second-order prisms must be "
                    f"6-node triangles and 8- or 9-node quadrilaterals, got {names}"
                )
            continue
        if dim == tdim == 3 and _PRISM in types and types <= {_PRISM, _HEXAHEDRON}:
            prisms = True
            continue
        if prisms and types <= {_TRIANGLE, _QUADRILATERAL}:
            continue
        if len(types) > 1:
            names = [gmsh.model.mesh.getElementProperties(t)[0] for t in sorted(types)]
            raise ValueError(
                f"gmsh model '{model}': physical groups of dimension {dim} mix element types "
                f"{names}; dolfinx needs one cell type"
            )
        incomplete = sorted(types & set(_INCOMPLETE)) if dim == tdim else []
        if incomplete:
            raise ValueError(
                f"gmsh model '{model}': its cells are {_INCOMPLETE[incomplete[0]]} (gmsh's "
                "incomplete second order, Mesh.SecondOrderIncomplete = 1), which dolfinx meshes "
                "cannot hold; generate complete second-order cells (Mesh.SecondOrderIncomplete "
                "= 0: 9-node quadrilaterals, 27-node hexahedra)"
            )
        if dim == tdim and not types:
            raise ValueError(
                f"gmsh model '{model}': the physical groups of dimension {tdim} have no elements "
                "(generate the mesh first)"
            )
    node_tags, _, _ = gmsh.model.mesh.getNodes()
    if not np.array_equal(np.sort(node_tags), np.arange(1, node_tags.size + 1)):
        gmsh.model.mesh.renumberNodes()
    return "quadratic prisms" if quadratic else ("prisms" if prisms else "dolfinx")


def _group_elements(dim: int) -> dict[int, list[tuple[np.ndarray, np.ndarray, np.ndarray]]]:
    """Elements of the physical groups of ``dim`` by gmsh type: ``(tags, rows, group)`` lists.

    ``rows`` hold 0-based node indices (node tags are contiguous after :func:`_prepare_model`).
    """
    found: dict[int, list[tuple[np.ndarray, np.ndarray, np.ndarray]]] = {}
    for group_dim, group in gmsh.model.getPhysicalGroups():
        if group_dim != dim:
            continue
        for entity in gmsh.model.getEntitiesForPhysicalGroup(dim, group):
            types, tags, nodes = gmsh.model.mesh.getElements(dim, entity)
            for kind, element_tags, node_tags in zip(types, tags, nodes):
                element_tags = np.asarray(element_tags, dtype=np.int64)
                rows = np.asarray(node_tags, dtype=np.int64).reshape(element_tags.size, -1) - 1
                values = np.full(element_tags.size, group, dtype=np.int32)
                found.setdefault(int(kind), []).append((element_tags, rows, values))
    return found


def _stacked(parts: list, width: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(tags, rows, groups)`` of a list from :func:`_group_elements` joined (empty if none)."""
    if not parts:
        return np.zeros(0, np.int64), np.zeros((0, width), np.int64), np.zeros(0, np.int32)
    return tuple(np.concatenate([p[i] for p in parts]) for i in range(3))  # type: ignore[return-value]


def _prism_cells(model: str) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Points, hexahedra (dolfinx order), cell groups and tagged facet keys of a prism model.

    Prisms turned so their collapsed edges build (``kernels/collapsed_wedges.py``) and, if the
    triangle ``1-2-3`` turns clockwise seen from ``4-5-6``, mirrored (the same element).
    Facet keys: sorted corner nodes, -1 first for a triangle; then the facet's group.

    Raises:
        ValueError: a prism is flat or inverted at an integration point, or its collapsed edges
            cannot be placed (naming gmsh element tags).
    """
    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    points = np.zeros((node_tags.size, 3))
    points[np.asarray(node_tags, dtype=np.int64) - 1] = np.asarray(coords).reshape(-1, 3)
    cells = _group_elements(3)
    _, hexes, hex_groups = _stacked(cells.get(_HEXAHEDRON, []), 8)
    prism_tags, prisms, prism_groups = _stacked(cells.get(_PRISM, []), 6)
    det = collapsed_jacobians(points[collapse_wedges(prisms, np.zeros(prisms.shape[0], int))])
    mirrored = np.all(det < 0.0, axis=1)
    prisms[mirrored] = prisms[mirrored][:, [0, 2, 1, 3, 5, 4]]
    bad = np.flatnonzero(np.any(det <= 0.0, axis=1) & ~mirrored)
    if bad.size:
        raise ValueError(
            f"gmsh model '{model}': prism {int(prism_tags[bad[0]])} (and {bad.size - 1} more) is "
            "flat or inverted at an integration point of its collapsed hexahedron"
        )
    try:
        rotation = wedge_rotations(prisms, shared=True)
    except WedgeRotationError as exc:
        raise ValueError(
            f"gmsh model '{model}': prism {int(prism_tags[exc.index])}: {exc} (dolfinx cannot "
            "build a mesh of hexahedra collapsed otherwise; docs/method.md §32)"
        ) from None
    hexahedra = np.vstack([hexes, collapse_wedges(prisms, rotation)])[:, _HEX_TO_DOLFINX]
    groups = np.concatenate([hex_groups, prism_groups])
    facets = _group_elements(2)
    _, triangles, tri_groups = _stacked(facets.get(_TRIANGLE, []), 3)
    _, quads, quad_groups = _stacked(facets.get(_QUADRILATERAL, []), 4)
    keys = np.vstack(
        [np.column_stack([np.full(triangles.shape[0], -1), np.sort(triangles, axis=1)]),
         np.sort(quads, axis=1)]
    )  # fmt: skip
    tagged = np.column_stack([keys, np.concatenate([tri_groups, quad_groups])])
    return points, hexahedra, groups, tagged


def _collapsed_prism_mesh(comm: MPI.Comm, rank: int, gdim: int) -> tuple[Mesh, MeshTags, MeshTags]:
    """Mesh and tags of a prism model on ``rank``, prisms as collapsed hexahedra. Collective.

    The cell groups and tagged facets are broadcast (set-up data, one integer per cell and five
    per tagged facet); each process tags its own and ghost cells and facets.
    """
    if gdim != 3:
        raise ValueError(f"a mesh of prisms needs gdim = 3, got {gdim!r}")
    error, groups, tagged = None, None, None
    points, cells = np.zeros((0, gdim)), np.zeros((0, 8), np.int64)
    if comm.rank == rank:
        try:
            points, cells, groups, tagged = _prism_cells(gmsh.model.getCurrent() or "<default>")
        except ValueError as exc:
            error = exc
    _raise_everywhere(comm, rank, error)
    groups, tagged = comm.bcast((groups, tagged), root=rank)
    domain = compat.coordinate_element("hexahedron", 1, gdim)
    mesh = create_collapsed_mesh(comm, cells, points[:, :gdim], domain, rank)
    tdim = mesh.topology.dim
    cell_tags = _cell_tags(mesh, groups)

    mesh.topology.create_entities(tdim - 1)
    facet_map = mesh.topology.index_map(tdim - 1)
    facets = np.arange(facet_map.size_local + facet_map.num_ghosts, dtype=np.int32)
    nodes = np.asarray(mesh.geometry.input_global_indices, dtype=np.int64)[
        compat.entities_to_geometry(mesh, tdim - 1, facets)
    ]
    key = np.sort(nodes, axis=1)
    repeat = np.zeros(key.shape, dtype=bool)
    repeat[:, 1:] = key[:, 1:] == key[:, :-1]
    key = np.sort(np.where(repeat, -1, key), axis=1)  # a triangle: -1 and its three corners
    both = np.vstack([tagged[:, :4], key])
    _, inverse = np.unique(both, axis=0, return_inverse=True)
    inverse = inverse.ravel()
    value = np.full(both.shape[0], -1, dtype=np.int64)
    value[inverse[: tagged.shape[0]]] = tagged[:, 4]
    found = value[inverse[tagged.shape[0] :]]
    keep = np.flatnonzero(found >= 0)
    facet_tags = dolfinx.mesh.meshtags(mesh, tdim - 1, facets[keep], found[keep].astype(np.int32))
    return mesh, cell_tags, facet_tags


def _quadratic_prism_cells(
    model: str,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, PrismFaces]:
    """Points, 18-node prisms (dolfinx order), cell groups and tagged faces of a gmsh model.

    gmsh's 15- and 18-node prisms number their nodes as basix's degree-2 prism (vertices, edges
    0-1, 0-2, 0-3, 1-2, 1-4, 2-5, 3-4, 3-5, 4-5, then the quadrilateral centres: derived from the
    node positions, ``tests/meshes/test_gmsh_quadratic_prisms.py``). A prism whose triangle
    ``1-2-3`` turns clockwise seen from ``4-5-6`` is mirrored; 15-node prisms get their face
    centres by the quad8 map (C3D15's geometry), 18-node ones keep gmsh's.

    Raises:
        ValueError: a prism with a Jacobian ``<= 0`` at one of ccx's 9 points, or a tagged face
            that bounds no prism (naming gmsh element tags).
    """
    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    points = np.zeros((node_tags.size, 3))
    points[np.asarray(node_tags, dtype=np.int64) - 1] = np.asarray(coords).reshape(-1, 3)
    found = _group_elements(3)
    kind = next(iter(found))
    tags, cells, groups = _stacked(found[kind], 18 if kind == 13 else 15)
    det = _prism_jacobians(cells, points)
    mirrored = np.all(det < 0.0, axis=1)
    cells[mirrored] = cells[mirrored][:, _MIRROR[: cells.shape[1]]]
    if kind == 18:
        cells, points = add_wedge_centres(cells, points)
    bad = np.flatnonzero(np.any(_prism_jacobians(cells, points) <= 0.0, axis=1))
    if bad.size:
        raise ValueError(
            f"gmsh model '{model}': prism {int(tags[bad[0]])} (and {bad.size - 1} more) has a "
            "Jacobian <= 0 at an integration point (flat, folded or inverted)"
        )
    return points, cells, groups, _tagged_faces(model, cells)


def _prism_jacobians(cells: np.ndarray, points: np.ndarray) -> np.ndarray:
    """``(C, 9)`` Jacobian determinants of 15- or 18-node prisms at ccx's 9 points.

    15-node rows are measured with their face centres placed by the quad8 map.
    """
    if cells.shape[1] == 15:
        cells, points = add_wedge_centres(cells, points)
    x = points[cells]  # (C, 18, 3)
    jacobian = np.einsum("aqn,cnd->cqda", _prism18_derivatives(), x)
    return np.linalg.det(jacobian)


def _tagged_faces(model: str, cells: np.ndarray) -> PrismFaces:
    """The tagged faces of the physical groups of dimension 2, oriented by their prisms."""
    local = [np.array(f) for f in WEDGE_FACES]
    rows = [cells[:, f] for f in local]  # (C, 6) twice, (C, 9) three times
    minus = np.full((cells.shape[0], 1), -1)
    keys = np.vstack(
        [np.hstack([minus, np.sort(r[:, :3], axis=1)]) for r in rows[:2]]
        + [np.sort(r[:, :4], axis=1) for r in rows[2:]]
    )
    padded = np.vstack([np.pad(r, ((0, 0), (0, 9 - r.shape[1])), constant_values=-1) for r in rows])
    out: dict[bool, tuple[list, list]] = {True: ([], []), False: ([], [])}
    for kind, parts in _group_elements(2).items():
        tags, faces, groups = _stacked(parts, _QUADRATIC_FACES[kind])
        triangle = kind == 9
        key = np.sort(faces[:, : 3 if triangle else 4], axis=1)
        if triangle:
            key = np.column_stack([np.full(key.shape[0], -1), key])
        both = np.vstack([keys, key])
        _, inverse = np.unique(both, axis=0, return_inverse=True)
        inverse = inverse.ravel()
        where = np.full(both.shape[0], -1, dtype=np.int64)
        where[inverse[: keys.shape[0]]] = np.arange(keys.shape[0])
        match = where[inverse[keys.shape[0] :]]
        if np.any(match < 0):
            k = int(np.flatnonzero(match < 0)[0])
            raise ValueError(
                f"gmsh model '{model}': element {int(tags[k])} of physical group "
                f"{int(groups[k])} is no face of a prism"
            )
        out[triangle][0].append(padded[match, : 6 if triangle else 9])
        out[triangle][1].append(groups)
    tri, quad = out[True], out[False]
    return PrismFaces(
        triangles=np.vstack(tri[0]) if tri[0] else np.zeros((0, 6), np.int64),
        triangle_tags=np.concatenate(tri[1]) if tri[1] else np.zeros(0, np.int32),
        quadrilaterals=np.vstack(quad[0]) if quad[0] else np.zeros((0, 9), np.int64),
        quadrilateral_tags=np.concatenate(quad[1]) if quad[1] else np.zeros(0, np.int32),
    )


def _cell_tags(mesh: Mesh, groups: np.ndarray) -> MeshTags:
    """Tags of this process's cells (owned and ghosts): ``groups`` of their input cells."""
    tdim = mesh.topology.dim
    cell_map = mesh.topology.index_map(tdim)
    num_cells = cell_map.size_local + cell_map.num_ghosts
    original = np.asarray(mesh.topology.original_cell_index, dtype=np.int64)[:num_cells]
    local = np.arange(original.size, dtype=np.int32)
    return dolfinx.mesh.meshtags(mesh, tdim, local, groups[original].astype(np.int32))


def _quadratic_prism_mesh(
    comm: MPI.Comm, rank: int, gdim: int
) -> tuple[Mesh, MeshTags, PrismFaces]:
    """Mesh of 18-node prisms, cell tags and tagged faces of a gmsh model on ``rank``.

    Collective. The faces are broadcast (the same on every process).
    """
    require_quadratic_prisms("gmsh's 15- and 18-node prisms", "§32.5, §40")
    if gdim != 3:
        raise ValueError(f"a mesh of prisms needs gdim = 3, got {gdim!r}")
    error, groups, faces = None, None, None
    points, cells = np.zeros((0, 3)), np.zeros((0, 18), np.int64)
    if comm.rank == rank:
        try:
            points, cells, groups, faces = _quadratic_prism_cells(
                gmsh.model.getCurrent() or "<default>"
            )
        except ValueError as exc:
            error = exc
    _raise_everywhere(comm, rank, error)
    groups, faces = comm.bcast((groups, faces), root=rank)
    domain = compat.coordinate_element("prism", 2, 3)
    mesh = compat.create_mesh(comm, cells.astype(np.int64), points, domain)
    return mesh, _cell_tags(mesh, groups), faces


def write_msh(path: str | Path) -> None:
    """Write the current gmsh model to an ASCII ``.msh`` file (on the calling process only)."""
    gmsh.option.setNumber("Mesh.Binary", 0)
    gmsh.write(str(path))
    print(f"wrote {path}: {len(gmsh.model.mesh.getNodes()[0])} nodes")
