"""The one place that knows which dolfinx is installed: 0.5.2 (Debian 12), 0.9 (Debian 13) or 0.11
(Debian unstable).

Every other module of dolfinx_ntf, and its demos, tests and benchmarks, call these helpers instead
of the version-specific dolfinx API, so the code reads the same on all releases. What differs:

=====================================  ===============================  ==============================  ==============================
what                                   dolfinx 0.5.2                    dolfinx 0.9                     dolfinx 0.11
=====================================  ===============================  ==============================  ==============================
vector space                           ``VectorFunctionSpace(mesh,      ``functionspace(mesh, ("P", k,  as 0.9
                                       ("P", k))``                      (3,)))``
coordinate element of ``create_mesh``  ``ufl.Mesh(ufl.VectorElement(    ``basix.ufl.element(...,        as 0.9
                                       ...))``                          shape=(3,))``
``create_mesh`` argument order         ``(comm, cells, x, element)``    as 0.5.2                        ``(comm, cells, element, x)``
cell partitioner from a graph one      ``create_cell_partitioner(f)``   ``(f, ghost_mode)``             ``(f, ghost_mode, max links)``
C++ mesh object                        ``mesh._mesh``                   ``mesh._cpp_object``            as 0.9
PETSc vector of a Function             ``u.vector``                     ``u.x.petsc_vec``               as 0.9
``fem.petsc.create_vector`` takes      the linear form                  the linear form                 its function space
Newton solver                          ``nls.petsc.NewtonSolver``       as 0.5.2                        deprecated; dolfinx_ntf has
                                                                                                        its own (``solvers.newton_loop``)
``LinearProblem``                      no options prefix                no options prefix               ``petsc_options_prefix`` needed
gmsh reader                            ``io.gmshio``: a tuple           as 0.5.2                        ``io.gmsh``: ``MeshData``
cell dofmaps                           ``AdjacencyList`` (``.array``)   2D numpy arrays                 as 0.9
form compiler / JIT option names       ``form_compiler_params``,        ``..._options``                 as 0.9
                                       ``jit_params``
class names for type hints             ``DirichletBCMetaClass``, ...    ``DirichletBC``, ...            as 0.9
sparsity graph                         ``AdjacencyList``                ``(array, offsets)``            as 0.9
pattern's column map (extra ghosts)    ``column_index_map()``           as 0.5.2                        ``index_map(1)`` once finalized
geometry dofmap                        ``geometry.dofmap``              as 0.5.2                        ``geometry.dofmaps[0]``
scalar space of one component          scalar space, same numbering     ``V.sub(i).collapse()``         as 0.9, dof maps per cell type
                                       (``collapse`` crashes on a
                                       process without cells)
quadrature space (e.g. stresses)       ``ufl.VectorElement(             ``basix.ufl.                    as 0.9
                                       "Quadrature", ...,               quadrature_element(...,
                                       quad_scheme="default")``         scheme="default")``
reference quadrature points            ``basix.make_quadrature(type,    ``make_quadrature(cell, deg)``  as 0.9
                                       cell, deg)``
a cut through facets it cannot match   vertices duplicated (joined      joined (a global exchange of    as 0.9
                                       only through ghosts of matched   unmatched facets' vertices)
                                       facets): ``create_mesh``'s
                                       ``unmatched`` adds the ghosts
=====================================  ===============================  ==============================  ==============================

A user's own UFL code differs the same way (element and space creation, ``LinearProblem``'s
prefix); :func:`vector_space`, :func:`scalar_space` and :func:`linear_problem` are public for that
reason.
"""

from __future__ import annotations

import typing
import weakref

from mpi4py import MPI
from petsc4py import PETSc

import numpy as np

import dolfinx
import dolfinx.cpp
import dolfinx.fem
import dolfinx.fem.petsc
import dolfinx.mesh
import ufl

__all__ = [
    "DOLFINX_VERSION",
    "JOINS_UNMATCHED_FACETS",
    "DirichletBC",
    "Form",
    "MeshTags",
    "boundary_values",
    "cell_dofs",
    "component_space",
    "coordinate_element",
    "cpp_mesh",
    "create_mesh",
    "create_vector",
    "discontinuous_space",
    "entities_to_geometry",
    "evaluate_expression",
    "geometry_dofs",
    "incident_entities",
    "jit_keywords",
    "linear_problem",
    "model_to_mesh",
    "petsc_vector",
    "quadrature_points",
    "quadrature_space",
    "scalar_space",
    "space_degree",
    "space_family",
    "sparsity_graph",
    "vector_space",
]

#: (major, minor) of the installed dolfinx.
DOLFINX_VERSION: tuple[int, int] = tuple(int(p) for p in dolfinx.__version__.split(".")[:2])
_LEGACY = DOLFINX_VERSION < (0, 7)
#: dolfinx 0.10 made ``NonlinearProblem`` a SNES wrapper, ``LinearProblem`` need a prefix and
#: renamed ``io.gmshio`` to ``io.gmsh``.
_V010 = DOLFINX_VERSION >= (0, 10)
#: dolfinx 0.11 changed ``create_mesh``'s and ``create_vector``'s arguments.
_V011 = DOLFINX_VERSION >= (0, 11)

#: Whether ``create_mesh`` joins the vertices of facets it does not match across processes by
#: itself (0.9 and later: through a global exchange); 0.5.2 joins a cut's vertices only through
#: the ghost cells of matched facets (``create_mesh``'s ``unmatched``, docs/method.md §37).
JOINS_UNMATCHED_FACETS: bool = not _LEGACY

if _LEGACY:
    DirichletBC = dolfinx.fem.DirichletBCMetaClass
    Form = dolfinx.fem.FormMetaClass
    MeshTags = dolfinx.mesh.MeshTagsMetaClass
else:
    DirichletBC = dolfinx.fem.DirichletBC
    Form = dolfinx.fem.Form
    MeshTags = dolfinx.mesh.MeshTags


def vector_space(
    mesh: dolfinx.mesh.Mesh, family: str = "Lagrange", degree: int = 1
) -> dolfinx.fem.FunctionSpace:
    """A vector-valued space with one component per geometric dimension (e.g. displacements)."""
    if _LEGACY:
        return dolfinx.fem.VectorFunctionSpace(mesh, (family, degree))
    return dolfinx.fem.functionspace(mesh, (family, degree, (mesh.geometry.dim,)))


def scalar_space(
    mesh: dolfinx.mesh.Mesh, family: str = "Lagrange", degree: int = 1
) -> dolfinx.fem.FunctionSpace:
    """A scalar space."""
    if _LEGACY:
        return dolfinx.fem.FunctionSpace(mesh, (family, degree))
    return dolfinx.fem.functionspace(mesh, (family, degree))


#: dolfinx 0.5.2's scalar spaces of :func:`component_space`, by (mesh identity, family, degree).
#: An entry lives as long as its space, and the space holds its mesh: a key's mesh identity
#: cannot be reused while the entry exists.
_COMPONENT_SPACES: weakref.WeakValueDictionary = weakref.WeakValueDictionary()


def component_space(
    V: dolfinx.fem.FunctionSpace, component: int
) -> tuple[dolfinx.fem.FunctionSpace, np.ndarray]:
    """The scalar space of one component of a vector space and the dofs of ``V`` it maps to.

    What ``V.sub(component).collapse()`` gives. On dolfinx 0.5.2 ``collapse`` crashes with a
    segmentation fault on a process that holds no cells, so there the scalar space of the same
    element is built instead: its numbering is the blocked numbering of ``V`` (checked on every
    process, collectively), so its dof ``k`` is ``V``'s dof ``bs * k + component``. That space is
    built once per mesh, family and degree (each build runs the form compiler's JIT, a few
    milliseconds of start-up) and shared by the components and the callers.
    """
    if not _LEGACY:
        Q, dofs = V.sub(component).collapse()
        if _V011:  # a list of dof maps, one per cell type
            dofs = dofs[0]
        return Q, np.asarray(dofs, dtype=np.int64)
    key = (id(V.mesh), space_family(V), space_degree(V))
    Q = _COMPONENT_SPACES.get(key)
    if Q is None:
        Q = scalar_space(V.mesh, key[1], key[2])
        _COMPONENT_SPACES[key] = Q
    bs = V.dofmap.index_map_bs
    same = (
        np.array_equal(cell_dofs(Q), cell_dofs(V))
        and Q.dofmap.index_map.size_local == V.dofmap.index_map.size_local
        and np.array_equal(Q.dofmap.index_map.ghosts, V.dofmap.index_map.ghosts)
    )
    if not V.mesh.comm.allreduce(same, op=MPI.LAND):
        Q, dofs = V.sub(component).collapse()
        return Q, np.asarray(dofs, dtype=np.int64)
    num = Q.dofmap.index_map.size_local + Q.dofmap.index_map.num_ghosts
    return Q, bs * np.arange(num, dtype=np.int64) + component


def coordinate_element(cell_name: str, degree: int = 1, gdim: int = 3) -> typing.Any:
    """The coordinate element that ``dolfinx.mesh.create_mesh`` takes for Lagrange geometry."""
    if _LEGACY:
        return ufl.Mesh(ufl.VectorElement("Lagrange", cell_name, degree))
    import basix.ufl

    return basix.ufl.element("Lagrange", cell_name, degree, shape=(gdim,))


def quadrature_space(
    mesh: dolfinx.mesh.Mesh, degree: int, shape: tuple[int, ...] = ()
) -> dolfinx.fem.FunctionSpace:
    """Values of shape ``shape`` at the points of the default quadrature rule of ``degree``.

    A form integrates such a Function exactly at its points with the measure
    ``dx(metadata={"quadrature_degree": degree, "quadrature_scheme": "default"})``;
    :func:`quadrature_points` gives the same points on the reference cell.
    """
    cell = mesh.ufl_cell()
    if _LEGACY:
        if shape == ():
            element = ufl.FiniteElement("Quadrature", cell, degree, quad_scheme="default")
        elif len(shape) == 1:
            element = ufl.VectorElement(
                "Quadrature", cell, degree, dim=shape[0], quad_scheme="default"
            )
        else:
            element = ufl.TensorElement(
                "Quadrature", cell, degree, shape=shape, quad_scheme="default"
            )
        return dolfinx.fem.FunctionSpace(mesh, element)
    import basix.ufl

    element = basix.ufl.quadrature_element(
        mesh.topology.cell_type.name, value_shape=tuple(shape), scheme="default", degree=degree
    )
    return dolfinx.fem.functionspace(mesh, element)


def discontinuous_space(
    mesh: dolfinx.mesh.Mesh, degree: int, shape: tuple[int, ...] = ()
) -> dolfinx.fem.FunctionSpace:
    """A discontinuous Lagrange space of ``degree`` with values of shape ``shape``."""
    if _LEGACY:
        cell = mesh.ufl_cell()
        family = "DQ" if cell.cellname() in ("quadrilateral", "hexahedron") else "DG"
        if shape == ():
            element = ufl.FiniteElement(family, cell, degree)
        elif len(shape) == 1:
            element = ufl.VectorElement(family, cell, degree, dim=shape[0])
        else:
            element = ufl.TensorElement(family, cell, degree, shape=shape)
        return dolfinx.fem.FunctionSpace(mesh, element)
    return dolfinx.fem.functionspace(mesh, ("DG", degree, tuple(shape)))


def quadrature_points(mesh: dolfinx.mesh.Mesh, degree: int) -> np.ndarray:
    """Reference points of the default quadrature rule of ``degree`` on the mesh's cells.

    The points of :func:`quadrature_space` and of forms integrated with that rule, in their
    order (e.g. for a ``dolfinx.fem.Expression`` evaluated at them).
    """
    import basix

    cell = getattr(basix.CellType, mesh.topology.cell_type.name)
    if _LEGACY:
        points, _ = basix.make_quadrature(basix.QuadratureType.Default, cell, degree)
    else:
        points, _ = basix.make_quadrature(cell, degree)
    return np.asarray(points)


def space_degree(V: dolfinx.fem.FunctionSpace) -> int:
    """Polynomial degree of a (vector) Lagrange space."""
    element = V.ufl_element()
    return int(element.degree() if _LEGACY else element.degree)


def space_family(V: dolfinx.fem.FunctionSpace) -> str:
    """Family name of a space's element: 'Lagrange' ('P'), 'Discontinuous Lagrange', ..."""
    element = V.ufl_element()
    if _LEGACY:
        return str(element.family())
    name = str(element.basix_element.family.name)
    discontinuous = bool(element.basix_element.discontinuous)
    return {"P": "Discontinuous Lagrange" if discontinuous else "Lagrange"}.get(name, name)


def cpp_mesh(mesh: dolfinx.mesh.Mesh) -> typing.Any:
    """The C++ mesh object that ``dolfinx.cpp`` functions take."""
    return mesh._mesh if _LEGACY else mesh._cpp_object


def tags_on_mesh(tags: MeshTags, mesh: dolfinx.mesh.Mesh) -> bool:
    """Whether ``tags`` were made on ``mesh`` (the same topology object, not an equal one).

    dolfinx 0.5 tags hold their mesh, later ones its topology; both hand out the C++ object that
    ``mesh.topology`` wraps (a Python wrapper from dolfinx 0.10 on).
    """
    topology = tags.mesh.topology if hasattr(tags, "mesh") else tags.topology
    ours = mesh.topology
    return getattr(topology, "_cpp_object", topology) is getattr(ours, "_cpp_object", ours)


def entities_to_geometry(mesh: dolfinx.mesh.Mesh, dim: int, entities: np.ndarray) -> np.ndarray:
    """Geometry nodes of the closure of each entity, shape (num_entities, nodes per entity)."""
    entities = np.asarray(entities, dtype=np.int32)
    if entities.size == 0:  # dolfinx 0.9 divides by zero on an empty list
        cmap = mesh.geometry.cmaps[0] if _V011 else mesh.geometry.cmap  # 0.11: one per cell type
        layout = cmap.create_dof_layout()
        if _V011:  # no num_entity_closure_dofs
            per_entity = len(layout.entity_closure_dofs(dim, 0))
        else:
            per_entity = layout.num_entity_closure_dofs(dim)
        return np.empty((0, per_entity), dtype=np.int32)
    mesh.topology.create_connectivity(dim, mesh.topology.dim)  # dolfinx 0.9 needs it
    nodes = dolfinx.cpp.mesh.entities_to_geometry(cpp_mesh(mesh), dim, entities, False)
    return np.asarray(nodes).reshape(entities.size, -1)


def cell_dofs(V: dolfinx.fem.FunctionSpace) -> np.ndarray:
    """Block dofs of every local cell (owned and ghost), shape (num_cells, dofs per cell)."""
    dofs = V.dofmap.list
    if _LEGACY:  # an empty list (a process without cells) has no row width
        return dofs.array.reshape(dofs.num_nodes, V.dofmap.dof_layout.num_dofs)
    return np.asarray(dofs)


def geometry_dofs(mesh: dolfinx.mesh.Mesh) -> np.ndarray:
    """Geometry nodes of every local cell, shape (num_cells, nodes per cell)."""
    dofs = mesh.geometry.dofmaps[0] if _V011 else mesh.geometry.dofmap  # 0.11: one per cell type
    if _LEGACY:  # an empty list (a process without cells) has no row width
        return dofs.array.reshape(dofs.num_nodes, mesh.geometry.cmap.create_dof_layout().num_dofs)
    return np.asarray(dofs)


def incident_entities(
    mesh: dolfinx.mesh.Mesh, entities: np.ndarray, dim: int, incident_dim: int
) -> np.ndarray:
    """Entities of dimension ``incident_dim`` incident to ``entities`` of dimension ``dim``."""
    entities = np.asarray(entities, dtype=np.int32)
    where = mesh if _LEGACY else mesh.topology
    return dolfinx.mesh.compute_incident_entities(where, entities, dim, incident_dim)


def evaluate_expression(
    expression: dolfinx.fem.Expression, mesh: dolfinx.mesh.Mesh, cells: np.ndarray
) -> np.ndarray:
    """Values of a ``dolfinx.fem.Expression`` at its points in ``cells``."""
    cells = np.asarray(cells, dtype=np.int32)
    return expression.eval(cells) if _LEGACY else expression.eval(mesh, cells)


def boundary_values(bc: DirichletBC) -> dolfinx.fem.Function:
    """The Function that holds a Dirichlet condition's prescribed values."""
    return bc.value if _LEGACY else bc.g


def petsc_vector(u: dolfinx.fem.Function) -> PETSc.Vec:
    """The PETSc vector that wraps a Function's values (ghosted)."""
    return u.vector if _LEGACY else u.x.petsc_vec


def jit_keywords(
    form_compiler_options: dict | None = None, jit_options: dict | None = None
) -> dict[str, dict]:
    """Keyword arguments of ``dolfinx.fem.form`` for these options."""
    if _LEGACY:
        return {
            "form_compiler_params": form_compiler_options or {},
            "jit_params": jit_options or {},
        }
    return {"form_compiler_options": form_compiler_options, "jit_options": jit_options}


def sparsity_graph(a: Form) -> tuple[np.ndarray, np.ndarray]:
    """CSR ``(offsets, columns)`` of a bilinear form's block sparsity pattern: owned rows with
    *global* block columns (in parallel the pattern's column map holds more ghosts than the space).
    """
    pattern = dolfinx.fem.create_sparsity_pattern(a)
    if _LEGACY:
        pattern.assemble()
        graph = pattern.graph
        offsets, columns = np.asarray(graph.offsets), np.asarray(graph.array)
    else:
        pattern.finalize()
        columns, offsets = (np.asarray(v) for v in pattern.graph)
    num_rows = pattern.index_map(0).size_local
    offsets = offsets[: num_rows + 1]
    # 0.11 has no column_index_map: a finalized pattern's index_map(1) is that map
    column_map = pattern.index_map(1) if _V011 else pattern.column_index_map()
    columns = column_map.local_to_global(columns[: offsets[-1]].astype(np.int32))
    return offsets, np.asarray(columns, dtype=np.int64)


def create_mesh(
    comm: typing.Any,
    cells: np.ndarray,
    points: np.ndarray,
    element: typing.Any,
    owners: np.ndarray | None = None,
    unmatched: np.ndarray | None = None,
) -> dolfinx.mesh.Mesh:
    """``dolfinx.mesh.create_mesh``; ``owners`` gives the process of each cell passed here (by
    default dolfinx's graph partitioner decides), e.g. to test chosen partitions.

    ``unmatched``: ``(k, 2)`` pairs of cells (global input numbers: the processes' cells in rank
    order; any process may pass any of them, and each passes an array or each None: collective)
    that share a face dolfinx's facet matching misses
    (``kernels.collapsed_wedges.unmatched_neighbours``). dolfinx 0.5.2 joins a cut's vertices
    only through the ghost cells of matched facets, so there each such pair is made a ghost of
    the other's process (docs/method.md §37); 0.9 and later join the vertices of unmatched
    facets themselves and ignore it."""
    pairs = None
    if not JOINS_UNMATCHED_FACETS and unmatched is not None:
        local = np.asarray(unmatched, dtype=np.int64).reshape(-1, 2)
        pairs = np.concatenate(comm.allgather(local))
        pairs = np.vstack([pairs, pairs[:, ::-1]]) if pairs.size else None
    if owners is None and pairs is None:
        return _create_mesh(comm, cells, points, element)
    graph_partitioner = dolfinx.cpp.graph.partitioner() if owners is None else None
    everyone = None
    if owners is not None:
        owners = np.ascontiguousarray(owners, dtype=np.int32)
        everyone = np.concatenate(comm.allgather(owners))

    def partition(_comm: typing.Any, _parts: int, graph: typing.Any, ghosting: bool) -> typing.Any:
        """Owner of each local cell, then (when asked) the owners of its neighbours."""
        if owners is None:
            dest = graph_partitioner(_comm, _parts, graph, ghosting)
        elif not ghosting:
            return dolfinx.cpp.graph.AdjacencyList_int32(owners)
        else:
            dest = _owner_destinations(owners, everyone, graph)
        if pairs is None or not ghosting:
            return dest
        return _ghosts_across(comm, dest, pairs)

    if _LEGACY:
        partitioner = dolfinx.cpp.mesh.create_cell_partitioner(partition)
    elif _V011:  # 2: at most two cells share a facet (no branching manifolds)
        partitioner = dolfinx.cpp.mesh.create_cell_partitioner(
            partition, dolfinx.mesh.GhostMode.none, 2
        )
    else:
        partitioner = dolfinx.cpp.mesh.create_cell_partitioner(
            partition, dolfinx.mesh.GhostMode.none
        )
    return _create_mesh(comm, cells, points, element, partitioner=partitioner)


def _destinations(rows: np.ndarray, num_cells: int) -> typing.Any:
    """An ``AdjacencyList_int32`` of the ``(cell, rank)`` rows, sorted by cell (stable)."""
    rows = rows[np.argsort(rows[:, 0], kind="stable")]
    counts = np.bincount(rows[:, 0], minlength=num_cells)
    return dolfinx.cpp.graph.AdjacencyList_int32(
        rows[:, 1].astype(np.int32), np.concatenate([[0], np.cumsum(counts)]).astype(np.int32)
    )


def _owner_destinations(owners: np.ndarray, everyone: np.ndarray, graph: typing.Any) -> typing.Any:
    """Each local cell's owner, then the owners of its facet neighbours in the dual ``graph``."""
    offsets, links = np.asarray(graph.offsets), np.asarray(graph.array)
    node = np.repeat(np.arange(owners.size), np.diff(offsets))
    pairs = np.unique(np.column_stack([node, everyone[links]]), axis=0).reshape(-1, 2)
    pairs = pairs[pairs[:, 1] != owners[pairs[:, 0]]]
    rows = np.vstack([np.column_stack([np.arange(owners.size), owners]), pairs])
    return _destinations(rows, owners.size)


def _ghosts_across(comm: typing.Any, dest: typing.Any, pairs: np.ndarray) -> typing.Any:
    """``dest`` (owner, then ghost processes of each local cell) with, for each ``(i, j)`` of
    ``pairs`` (global cell numbers, both orders given) whose cells' owners differ, the owner of
    ``j`` added to ``i``'s ghost processes. Collective."""
    offsets, links = np.asarray(dest.offsets), np.asarray(dest.array)
    num_cells = offsets.size - 1
    owner = links[offsets[:-1]]
    everyone = np.concatenate(comm.allgather(owner))
    first = comm.exscan(num_cells) or 0
    mine = (pairs[:, 0] >= first) & (pairs[:, 0] < first + num_cells)
    cell, other = pairs[mine, 0] - first, everyone[pairs[mine, 1]]
    old = np.column_stack([np.repeat(np.arange(num_cells), np.diff(offsets)), links])
    new = np.unique(np.column_stack([cell, other])[other != owner[cell]], axis=0).reshape(-1, 2)
    known = old[:, 0].astype(np.int64) * comm.size + old[:, 1]
    new = new[~np.isin(new[:, 0] * comm.size + new[:, 1], known)]
    return _destinations(np.vstack([old, new]).astype(np.int64), num_cells)


def _create_mesh(
    comm: typing.Any, cells: np.ndarray, points: np.ndarray, element: typing.Any, **options: object
) -> dolfinx.mesh.Mesh:
    """``dolfinx.mesh.create_mesh`` with the arguments in the installed version's order."""
    if _V011:
        return dolfinx.mesh.create_mesh(comm, cells, element, points, **options)
    return dolfinx.mesh.create_mesh(comm, cells, points, element, **options)


def create_vector(L: Form) -> PETSc.Vec:
    """A ghosted PETSc vector for a linear form (``dolfinx.fem.petsc.create_vector``)."""
    if _V011:  # takes the space, no longer the form
        return dolfinx.fem.petsc.create_vector(L.function_spaces[0])
    return dolfinx.fem.petsc.create_vector(L)


def linear_problem(
    a: ufl.Form,
    L: ufl.Form,
    *,
    bcs: typing.Sequence[DirichletBC] = (),
    petsc_options: dict | None = None,
    petsc_options_prefix: str = "dolfinx_ntf_linear_",
) -> dolfinx.fem.petsc.LinearProblem:
    """``dolfinx.fem.petsc.LinearProblem``; the options prefix is needed from dolfinx 0.10 on."""
    keywords: dict[str, typing.Any] = {"bcs": list(bcs), "petsc_options": petsc_options or {}}
    if _V010:
        keywords["petsc_options_prefix"] = petsc_options_prefix
    return dolfinx.fem.petsc.LinearProblem(a, L, **keywords)


def model_to_mesh(
    model: typing.Any, comm: typing.Any, rank: int, gdim: int
) -> tuple[dolfinx.mesh.Mesh, MeshTags, MeshTags]:
    """Mesh, cell tags and facet tags of a gmsh model (``dolfinx.io.gmshio``, ``io.gmsh`` in 0.10).

    Imports gmsh's Python module: call only where gmsh is wanted.
    """
    if _V010:
        import dolfinx.io.gmsh

        data = dolfinx.io.gmsh.model_to_mesh(model, comm, rank, gdim=gdim)
        return data.mesh, data.cell_tags, data.facet_tags
    from dolfinx.io import gmshio

    return gmshio.model_to_mesh(model, comm, rank, gdim=gdim)
