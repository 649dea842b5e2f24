"""gmsh models of dolfinx_ntf.meshes through gmsh_io: tags, volumes, areas, separate bodies.

Runs in serial and under ``mpirun -n 2``: every quantity is reduced over the communicator, and gmsh
only runs on rank 0.
"""

import math
from pathlib import Path

from mpi4py import MPI

import gmsh
import numpy as np
import pytest

import ufl
from dolfinx import fem

from dolfinx_ntf import compat
from dolfinx_ntf.meshes import gmsh_io, hertz, punch

pytestmark = pytest.mark.mpi

COMM = MPI.COMM_WORLD


def _cell_volumes(mesh, cell_tags):
    """Global volume per cell tag, from the assembled DG0 vector of cell volumes."""
    V = compat.scalar_space(mesh, "DG", 0)
    vector = fem.assemble_vector(fem.form(ufl.TestFunction(V) * ufl.dx))
    num_owned = mesh.topology.index_map(3).size_local
    volumes = np.zeros(num_owned)
    cells = np.arange(num_owned, dtype=np.int32)
    volumes[:] = vector.array[compat.cell_dofs(V)[cells, 0]]
    tag_of = np.full(num_owned, -1)
    owned = cell_tags.indices < num_owned
    tag_of[cell_tags.indices[owned]] = cell_tags.values[owned]
    assert COMM.allreduce(int(np.sum(tag_of < 0)), op=MPI.SUM) == 0, "untagged cells"
    tags = sorted(set(COMM.allreduce(np.unique(tag_of).tolist(), op=MPI.SUM)))
    return {t: COMM.allreduce(float(volumes[tag_of == t].sum()), op=MPI.SUM) for t in tags}


def _owned_facets(mesh, facet_tags, tag):
    num_owned = mesh.topology.index_map(2).size_local
    facets = facet_tags.indices[facet_tags.values == tag]
    return facets[facets < num_owned]


def _facet_vertex_coords(mesh, facets):
    """(F, v, 3) vertex coordinates of facets (vertex nodes only, also for P2 geometry)."""
    nodes = compat.entities_to_geometry(mesh, 2, facets.astype(np.int32))
    return mesh.geometry.x[nodes]


def _facet_stats(mesh, facet_tags):
    """Global count and flat-facet area per facet tag (owned facets only)."""
    tags = sorted(set(COMM.allreduce(np.unique(facet_tags.values).tolist(), op=MPI.SUM)))
    stats = {}
    for tag in tags:
        x = _facet_vertex_coords(mesh, _owned_facets(mesh, facet_tags, tag))
        if x.shape[1] == 3:
            area = 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
        else:  # quad in tensor order: the diagonals are 0-3 and 1-2
            area = 0.5 * np.linalg.norm(np.cross(x[:, 3] - x[:, 0], x[:, 2] - x[:, 1]), axis=1)
        stats[tag] = (COMM.allreduce(len(x), op=MPI.SUM), COMM.allreduce(area.sum(), op=MPI.SUM))
    return stats


def _global_vertices(mesh, cell_tags, tag):
    """Global vertex numbers of the cells with a tag, gathered on all ranks."""
    mesh.topology.create_connectivity(3, 0)
    c_to_v = mesh.topology.connectivity(3, 0)
    cells = cell_tags.indices[cell_tags.values == tag]
    local = np.unique(np.concatenate([c_to_v.links(c) for c in cells])) if len(cells) else []
    numbers = mesh.topology.index_map(0).local_to_global(np.asarray(local, dtype=np.int32))
    return set(np.concatenate(COMM.allgather(numbers)).tolist())


def _check_separate_bodies(mesh, cell_tags, a, b):
    va, vb = _global_vertices(mesh, cell_tags, a), _global_vertices(mesh, cell_tags, b)
    assert va and vb
    assert not va & vb, f"bodies {a} and {b} share {len(va & vb)} vertices"


@pytest.mark.parametrize("cell_type", ["hexahedron", "tetrahedron"])
def test_punch_coarse(cell_type):
    gap = 0.01
    mesh, ct, ft = gmsh_io.mesh_from_gmsh(
        punch.build_punch, COMM, cell_type=cell_type, gap=gap, **punch.COARSE
    )
    assert mesh.topology.cell_name() == cell_type
    volumes = _cell_volumes(mesh, ct)
    assert volumes.keys() == {punch.BLOCK, punch.PUNCH}
    assert math.isclose(volumes[punch.BLOCK], 1.0 * 1.0 * 0.5, rel_tol=1e-12)
    assert math.isclose(volumes[punch.PUNCH], 0.4 * 0.4 * 0.3, rel_tol=1e-12)
    stats = _facet_stats(mesh, ft)
    expected = {
        punch.BLOCK_BOTTOM: 1.0,
        punch.BLOCK_TOP: 1.0,
        punch.PUNCH_BOTTOM: 0.16,
        punch.PUNCH_TOP: 0.16,
    }
    assert stats.keys() == expected.keys()
    for tag, area in expected.items():
        assert stats[tag][0] > 0
        assert math.isclose(stats[tag][1], area, rel_tol=1e-12), tag
    # Slave on z = gap, centred over the block.
    x = _facet_vertex_coords(mesh, _owned_facets(mesh, ft, punch.PUNCH_BOTTOM)).reshape(-1, 3)
    assert np.allclose(x[:, 2], gap)
    lo = COMM.allreduce(x[:, :2].min(initial=np.inf), op=MPI.MIN)
    hi = COMM.allreduce(x[:, :2].max(initial=-np.inf), op=MPI.MAX)
    assert math.isclose(lo, 0.3) and math.isclose(hi, 0.7)
    _check_separate_bodies(mesh, ct, punch.BLOCK, punch.PUNCH)


@pytest.mark.parametrize(
    "cell_type,order", [("hexahedron", 1), ("tetrahedron", 1), ("hexahedron", 2)]
)
def test_patch_test_meshes_match(cell_type, order):
    mesh, ct, ft = gmsh_io.mesh_from_gmsh(
        punch.build_patch_test,
        COMM,
        cell_type=cell_type,
        order=order,
        divisions=(3, 4),
        block_layers=2,
        punch_layers=1,
    )
    volumes = _cell_volumes(mesh, ct)
    assert math.isclose(volumes[punch.BLOCK], 0.5, rel_tol=1e-12)
    assert math.isclose(volumes[punch.PUNCH], 0.25, rel_tol=1e-12)

    def faces(tag):
        x = _facet_vertex_coords(mesh, _owned_facets(mesh, ft, tag))
        local = {tuple(sorted(map(tuple, np.round(f[:, :2], 10).tolist()))) for f in x}
        return set().union(*COMM.allgather(local))

    master, slave = faces(punch.BLOCK_TOP), faces(punch.PUNCH_BOTTOM)
    per_quad = 1 if cell_type == "hexahedron" else 2
    assert len(master) == 3 * 4 * per_quad
    assert master == slave
    _check_separate_bodies(mesh, ct, punch.BLOCK, punch.PUNCH)


def test_patch_test_different_divisions():
    mesh, _ct, ft = gmsh_io.mesh_from_gmsh(
        punch.build_patch_test, COMM, divisions=4, punch_divisions=3
    )
    stats = _facet_stats(mesh, ft)
    assert stats[punch.BLOCK_TOP][0] == 16 and stats[punch.PUNCH_BOTTOM][0] == 9
    assert math.isclose(stats[punch.PUNCH_BOTTOM][1], 1.0)


def test_hertz_coarse_quarter():
    mesh, ct, ft = gmsh_io.mesh_from_gmsh(hertz.build_hertz, COMM, **hertz.COARSE)
    num_vertices = mesh.topology.index_map(0).size_global
    assert 600 < num_vertices < 1500  # ~3k P1 dofs
    volumes = _cell_volumes(mesh, ct)
    assert math.isclose(volumes[hertz.BLOCK], 2.0 * 2.0 * 1.5, rel_tol=1e-12)
    assert math.isclose(volumes[hertz.SPHERE], math.pi / 6, rel_tol=2e-2)  # quarter hemisphere
    assert volumes[hertz.SPHERE] < math.pi / 6  # flat facets cut into the sphere
    stats = _facet_stats(mesh, ft)
    expected = {
        hertz.BLOCK_BOTTOM: 4.0,
        hertz.BLOCK_TOP: 4.0,
        hertz.SPHERE_CONTACT: math.pi / 2,
        hertz.SPHERE_TOP: math.pi / 4,
        hertz.SYMMETRY_X: 3.0 + math.pi / 4,
        hertz.SYMMETRY_Y: 3.0 + math.pi / 4,
    }
    assert stats.keys() == expected.keys()
    for tag, area in expected.items():
        assert stats[tag][0] > 0
        assert math.isclose(stats[tag][1], area, rel_tol=2e-2), tag

    # Fine near the contact point, coarse far away (block top facets).
    x = _facet_vertex_coords(mesh, _owned_facets(mesh, ft, hertz.BLOCK_TOP))
    r = np.linalg.norm(x.mean(axis=1), axis=1)
    area = 0.5 * np.linalg.norm(np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0]), axis=1)
    near = COMM.allreduce(np.array([area[r < 0.1].sum(), np.sum(r < 0.1)]), op=MPI.SUM)
    far = COMM.allreduce(np.array([area[r > 1.5].sum(), np.sum(r > 1.5)]), op=MPI.SUM)
    assert near[1] > 0 and far[1] > 0
    assert near[0] / near[1] < 0.1 * far[0] / far[1]
    # Both bodies reach the contact point, each with its own vertex there.
    origin = []
    for tag in (hertz.SPHERE_CONTACT, hertz.BLOCK_TOP):
        pts = _facet_vertex_coords(mesh, _owned_facets(mesh, ft, tag)).reshape(-1, 3)
        origin.append(COMM.allreduce(np.linalg.norm(pts, axis=1).min(initial=np.inf), op=MPI.MIN))
    assert np.allclose(origin, 0.0)
    _check_separate_bodies(mesh, ct, hertz.BLOCK, hertz.SPHERE)


def test_hertz_hexahedra_and_quadratic_geometry():
    coarse = {"size_fine": 0.1, "size_coarse": 0.6, "refine_radius": 0.2}
    mesh, ct, _ft = gmsh_io.mesh_from_gmsh(
        hertz.build_hertz, COMM, cell_type="hexahedron", **coarse
    )
    assert mesh.topology.cell_name() == "hexahedron"
    volumes = _cell_volumes(mesh, ct)
    assert math.isclose(volumes[hertz.BLOCK], 6.0, rel_tol=1e-12)
    assert math.isclose(volumes[hertz.SPHERE], math.pi / 6, rel_tol=3e-2)
    _check_separate_bodies(mesh, ct, hertz.BLOCK, hertz.SPHERE)

    # Curved P2 geometry: the sphere volume is much closer than with flat tetrahedra.
    errors = []
    for order in (1, 2):
        mesh, ct, _ = gmsh_io.mesh_from_gmsh(
            hertz.build_hertz,
            COMM,
            order=order,
            quarter=False,
            size_fine=0.15,
            size_coarse=0.8,
            refine_radius=0.2,
        )
        errors.append(abs(_cell_volumes(mesh, ct)[hertz.SPHERE] / (2 * math.pi / 3) - 1))
    assert errors[1] < 0.1 * errors[0]


def test_read_msh_roundtrip_and_model_to_mesh(tmp_path):
    path = COMM.bcast(str(tmp_path / "punch.msh"), root=0)
    if COMM.rank == 0:
        with gmsh_io.gmsh_session():
            punch.build_punch(cell_type="tetrahedron", **punch.COARSE)
            gmsh.write(path)
            gmsh.model.remove()
    mesh, ct, ft = gmsh_io.read_msh(path, COMM)
    from_file = (
        _cell_volumes(mesh, ct),
        _facet_stats(mesh, ft),
        mesh.topology.index_map(3).size_global,
    )

    # The same model straight from gmsh, in a session opened by the caller: left open afterwards.
    if COMM.rank == 0:
        gmsh.initialize()
        gmsh.option.setNumber("General.Terminal", 0)
        punch.build_punch(cell_type="tetrahedron", **punch.COARSE)
    try:
        mesh, ct, ft = gmsh_io.model_to_mesh(COMM)
        if COMM.rank == 0:
            assert gmsh.model.getCurrent() == "punch"  # still usable
    finally:
        if COMM.rank == 0:
            gmsh.finalize()
    direct = (
        _cell_volumes(mesh, ct),
        _facet_stats(mesh, ft),
        mesh.topology.index_map(3).size_global,
    )
    assert from_file[2] == direct[2] > 0
    assert from_file[0] == pytest.approx(direct[0], rel=1e-12)
    for tag, (count, area) in direct[1].items():
        assert from_file[1][tag][0] == count
        assert from_file[1][tag][1] == pytest.approx(area, rel=1e-12)


def test_read_msh_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"no_such\.msh"):
        gmsh_io.read_msh(tmp_path / "no_such.msh", COMM)

    garbage = COMM.bcast(str(tmp_path / "garbage.msh"), root=0)
    no_groups = COMM.bcast(str(tmp_path / "no_groups.msh"), root=0)
    if COMM.rank == 0:
        Path(garbage).write_text("not a mesh\n")
        with gmsh_io.gmsh_session():
            gmsh.model.add("bare")
            gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
            gmsh.model.occ.synchronize()
            gmsh.model.mesh.generate(3)
            gmsh.option.setNumber("Mesh.SaveAll", 1)
            gmsh.write(no_groups)
            gmsh.option.setNumber("Mesh.SaveAll", 0)
            gmsh.model.remove()
    COMM.barrier()
    with pytest.raises(ValueError, match="cannot read"):
        gmsh_io.read_msh(garbage, COMM)
    with pytest.raises(ValueError, match="no physical groups"):
        gmsh_io.read_msh(no_groups, COMM)


def test_builder_errors_reach_all_ranks():
    with pytest.raises(ValueError, match="punch_size"):
        gmsh_io.mesh_from_gmsh(punch.build_punch, COMM, punch_size=(2.0, 0.4, 0.3))
    with pytest.raises(ValueError, match="cell_type"):
        gmsh_io.mesh_from_gmsh(hertz.build_hertz, COMM, cell_type="prism")
    with pytest.raises(ValueError, match="order"):
        gmsh_io.mesh_from_gmsh(punch.build_patch_test, COMM, order=3)
    with pytest.raises(ValueError, match="rank"):
        gmsh_io.read_msh("x.msh", COMM, rank=COMM.size)


def test_mixed_cell_types_rejected():
    def mixed():
        gmsh.model.add("mixed")
        a = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 1)
        b = gmsh.model.occ.addBox(2, 0, 0, 1, 1, 1)
        gmsh.model.occ.synchronize()
        for volume, recombine in ((a, True), (b, False)):
            surfaces = gmsh.model.getBoundary([(3, volume)], oriented=False)
            for _, curve in gmsh.model.getBoundary(surfaces, combined=False, oriented=False):
                gmsh.model.mesh.setTransfiniteCurve(abs(curve), 2)
            for _, surface in surfaces:
                gmsh.model.mesh.setTransfiniteSurface(surface)
                if recombine:
                    gmsh.model.mesh.setRecombine(2, surface)
            gmsh.model.mesh.setTransfiniteVolume(volume)
        gmsh.model.addPhysicalGroup(3, [a, b], 1)
        gmsh.model.mesh.generate(3)

    with pytest.raises(ValueError, match="mix element types"):
        gmsh_io.mesh_from_gmsh(mixed, COMM)
