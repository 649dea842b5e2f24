"""Contact on the faces of gmsh's 15-node prisms in the Python API (docs/method.md §40.6).

A punch of 15-node prisms pressed into a block of them (``helpers.quadratic_prisms``): the tagged
faces as contact surfaces (``prism_face_surface``), C3D15's face centres eliminated through the
contact problem's ``constraints``, against ccx 2.20 on the same meshes written as a C3D15 deck
(quadrilaterals in contact, then triangles), and a flat punch under a uniform pressure. Older
releases refuse the model (no degree-2 prisms before dolfinx 0.11).
"""

from __future__ import annotations

import shutil

from mpi4py import MPI

import numpy as np
import pytest
from helpers.quadratic_prisms import (
    BLOCK_VOLUME,
    MASTER,
    PUNCH_TOP,
    PUNCH_VOLUME,
    SLAVE,
    build_prism_punch,
    clamped_dofs,
)

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.calculix.elements import ELEMENT_TYPES
from dolfinx_ntf.contact.pairing import slave_areas
from dolfinx_ntf.fem.serendipity_wedge import wedge15_metadata, wedge15_space
from dolfinx_ntf.fem.surfaces import resolve_master, resolve_slave
from dolfinx_ntf.fem.wedge_faces import (
    WEDGE_FACES,
    PrismFaces,
    prism_face_forces,
    prism_face_surface,
)
from dolfinx_ntf.kernels.faces import QUAD8_GAUSS2, TRI6
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

COMM = MPI.COMM_WORLD
ON_011 = compat.DOLFINX_VERSION >= (0, 11)
needs_011 = pytest.mark.skipif(not ON_011, reason="degree-2 prisms need dolfinx 0.11 (§32.5)")
#: The wedges' axis: along y the contact faces are quadrilaterals, along z triangles.
AXES = pytest.mark.parametrize("axis", ["y", "z"], ids=["quad8", "tri6"])
#: Block and punch materials (E, nu) and ccx's LINEAR law (slope, tension, c0) of the decks.
MATERIALS = {BLOCK_VOLUME: (1000.0, 0.3), PUNCH_VOLUME: (2000.0, 0.25)}
LAW = (50000.0, 1.0 / 70.0, 1e-3)
DEPTH = 0.02


def _total(value) -> np.ndarray:
    return COMM.allreduce(np.asarray(value, dtype=float), op=MPI.SUM)


def _residual(V, u, cell_tags) -> ufl.Form:
    """Small-strain elasticity of both bodies at ccx's 9 points of C3D15."""
    v = ufl.TestFunction(V)
    dx = ufl.Measure("dx", domain=V.mesh, subdomain_data=cell_tags, metadata=wedge15_metadata())
    eps = ufl.sym(ufl.grad(u))
    form = 0
    for tag, (e, nu) in MATERIALS.items():
        mu, lam = e / (2 * (1 + nu)), e * nu / ((1 + nu) * (1 - 2 * nu))
        sigma = lam * ufl.tr(eps) * ufl.Identity(3) + 2 * mu * eps
        form += ufl.inner(sigma, ufl.sym(ufl.grad(v))) * dx(tag)
    return form


def _pair(V, faces: PrismFaces) -> ntf.ContactPair:
    law = ntf.LinearLaw(*LAW)
    slave = prism_face_surface(V, faces, SLAVE, "punch bottom")
    master = prism_face_surface(V, faces, MASTER, "block top")
    return ntf.ContactPair(slave, master, ntf.SurfaceInteraction(law))


def _input_of_dof(V) -> np.ndarray:
    """The mesh input index (gmsh node tag - 1) of each local block dof of ``V``."""
    mesh = V.mesh
    out = np.full(V.dofmap.index_map.size_local + V.dofmap.index_map.num_ghosts, -1)
    dofs = np.full(mesh.geometry.x.shape[0], -1)
    dofs[compat.geometry_dofs(mesh).ravel()] = compat.cell_dofs(V).ravel()
    out[dofs] = np.asarray(mesh.geometry.input_global_indices)
    return out


@pytest.mark.mpi
@pytest.mark.skipif(ON_011, reason="dolfinx 0.11 reads second-order prisms")
def test_refused_before_011():
    with pytest.raises(NotImplementedError, match=r"dolfinx 0\.11 or later"):
        mesh_from_gmsh(build_prism_punch, COMM)


@pytest.mark.mpi
@needs_011
@AXES
def test_surfaces_are_the_tagged_faces(axis):
    """Each tag's faces in ccx's order: quad8 (2 x 2 area rule) or tri6, outward, areas summing
    to the face's area (serial); every face on some process, serial and on 2 processes."""
    mesh, _, faces = mesh_from_gmsh(build_prism_punch, COMM, axis=axis)
    V, constraints = wedge15_space(mesh)
    face_type = QUAD8_GAUSS2 if axis == "y" else TRI6
    X = V.tabulate_dof_coordinates()
    centres = np.concatenate([c.nodes[:, 0] for c in constraints])
    for tag, normal, area in ((SLAVE, -1.0, 0.85 * 0.5), (MASTER, 1.0, 2.0)):
        surface = prism_face_surface(V, faces, tag)
        assert surface.face_type is face_type and surface.more == ()
        assert not np.isin(surface.faces, centres).any()  # C3D15's faces: no quad9 centre
        rows = surface.faces
        x = X[rows]
        assert np.allclose(x[:, :, 2], 1.0, atol=1e-12)
        n = np.cross(x[:, 1] - x[:, 0], x[:, 2] - x[:, 0])[:, 2]
        assert np.all(np.sign(n) == normal)  # corners counter-clockwise seen from outside
        expected = len(faces.find(tag)[0]) + len(faces.find(tag)[1])
        keys = np.sort(_input_of_dof(V)[rows[:, : face_type.num_corners]], axis=1)
        everywhere = COMM.allgather(keys)
        assert np.unique(np.vstack(everywhere), axis=0).shape[0] == expected
        if COMM.size == 1:  # on several processes: the problem's distributed surface, below
            areas = slave_areas(resolve_slave(V, surface), X)
            assert areas.sum() == pytest.approx(area, rel=1e-12)
    assert resolve_master(V, prism_face_surface(V, faces, MASTER)).face_type is face_type
    with pytest.raises(ValueError, match="no face has tag 99"):
        prism_face_surface(V, faces, 99)


def _press(axis: str, comm: MPI.Comm):
    """The punch's top moved down by DEPTH in 2 increments: problem, space and ``u``."""
    mesh, cell_tags, faces = mesh_from_gmsh(build_prism_punch, comm, axis=axis)
    V, constraints = wedge15_space(mesh)
    u = dolfinx.fem.Function(V, name="u")
    base = clamped_dofs(V, lambda x: np.isclose(x[2], 0.0), constraints)
    top = clamped_dofs(V, lambda x: np.isclose(x[2], 1.5), constraints)
    moved = dolfinx.fem.Function(V)
    bcs = [
        dolfinx.fem.dirichletbc(np.zeros(3), base, V),
        dolfinx.fem.dirichletbc(moved, top),
    ]
    problem = ntf.ContactProblem(
        _residual(V, u, cell_tags), u, [_pair(V, faces)], bcs, constraints=constraints
    )
    solver = ntf.ContactNewtonSolver(comm, problem)

    def load(t: float) -> None:
        moved.x.array.reshape(-1, 3)[:, 2] = -DEPTH * t

    ntf.StaticStep(load, initial_increment=0.5, fixed=True).run(solver, u)
    return problem, V, u, mesh, cell_tags, faces


def _deck(mesh, cell_tags, faces: PrismFaces) -> tuple[str, np.ndarray]:
    """The serial mesh as a C3D15 deck of the same contact problem; the ccx node numbers."""
    inputs = np.asarray(mesh.geometry.input_global_indices)
    cells = inputs[compat.geometry_dofs(mesh)]
    ccx_cells = cells[:, np.argsort(ELEMENT_TYPES["C3D15"].to_dolfinx)] + 1
    used = np.unique(ccx_cells)
    coords = np.zeros((inputs.max() + 2, 3))
    coords[inputs + 1] = mesh.geometry.x
    lines = ["*NODE, NSET=NALL"]
    lines += [f"{n}, {coords[n, 0]:.17g}, {coords[n, 1]:.17g}, {coords[n, 2]:.17g}" for n in used]
    volume = np.zeros(cells.shape[0], dtype=int)
    volume[cell_tags.indices] = cell_tags.values
    for tag, name in ((BLOCK_VOLUME, "BLOCK"), (PUNCH_VOLUME, "PUNCH")):
        lines.append(f"*ELEMENT, TYPE=C3D15, ELSET={name}")
        lines += [
            f"{e + 1}, " + ", ".join(map(str, ccx_cells[e, :8])) + ",\n"
            + ", ".join(map(str, ccx_cells[e, 8:]))
            for e in np.flatnonzero(volume == tag)
        ]  # fmt: skip
    for name, z in (("BASE", 0.0), ("TOP", 1.5)):
        lines.append(f"*NSET, NSET={name}")
        lines += [f"{n}," for n in used[np.isclose(coords[used, 2], z)]]
    for tag, name in ((BLOCK_VOLUME, "BLOCK"), (PUNCH_VOLUME, "PUNCH")):
        e, nu = MATERIALS[tag]
        lines += [f"*MATERIAL, NAME=M{name}", "*ELASTIC", f"{e!r}, {nu!r}"]
        lines.append(f"*SOLID SECTION, ELSET={name}, MATERIAL=M{name}")
    keys = {}
    for e, row in enumerate(cells):
        for k, face in enumerate(WEDGE_FACES):
            keys[tuple(sorted(row[list(face[: 3 if k < 2 else 4])]))] = (e + 1, k + 1)
    for tag, name in ((SLAVE, "SLAVE"), (MASTER, "MASTER")):
        triangles, quads = faces.find(tag)
        lines.append(f"*SURFACE, NAME={name}")
        lines += [
            "{}, S{}".format(*keys[tuple(sorted(f))]) for f in [*triangles[:, :3], *quads[:, :4]]
        ]
    lines += [
        "*CONTACT PAIR, INTERACTION=SI, TYPE=NODE TO SURFACE",
        "SLAVE, MASTER",
        "*SURFACE INTERACTION, NAME=SI",
        "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR",
        ", ".join(repr(float(c)) for c in LAW),
        "*BOUNDARY",
        "BASE, 1, 3, 0.0",
        "TOP, 1, 2, 0.0",
        "*STEP, INC=100",
        "*STATIC, DIRECT",
        "0.5, 1.0",
        "*CONTROLS, PARAMETERS=FIELD",
        "1e-10, 1e-08, , , 1e-10, 1e-05, 1e-08, 1e-12",
        "*BOUNDARY",
        f"TOP, 3, 3, {-DEPTH!r}",
        "*NODE PRINT, NSET=NALL",
        "U",
        "*CONTACT PRINT",
        "CDIS, CSTR",
        "*END STEP",
        "",
    ]
    return "\n".join(lines), used


@needs_011
@pytest.mark.skipif(shutil.which("ccx") is None, reason="needs ccx 2.20")
@AXES
def test_punch_against_ccx(axis, tmp_path):
    """The punch pressed 0.02 into the block: U of every node, the clearance (CDIS) and the
    contact pressure (CSTR) at every slave node against ccx 2.20 on the same C3D15 deck.

    quad8 slave faces on quad8 master faces (the wedges along y) or tri6 on tri6 (along z);
    ccx's 2 x 2 area rule on the quadrilaterals, its 1/100, 24/100 and 1/999, 332/999 shares.
    The contact surfaces are the deck runner's of that deck face for face, and the deck runner
    prints ccx's digits (1e-6). The Python API ends 3e-6 to 6e-6 of the largest CDIS and CSTR
    off (docs/method.md §40.6): its Newton path is not ccx's (ccx's predictor: 2 iterations in
    the second increment, the API 4), and the spring areas are those of the iterate of the
    last pairing (§3.1), here 5.5e-6 larger than the deck runner's.
    """
    from dolfinx_ntf.calculix.ccx import dat_block, read_ccx_dat, run_ccx
    from dolfinx_ntf.calculix.job import run_job

    if COMM.size > 1:
        pytest.skip("the deck is written from the serial mesh")
    problem, V, u, mesh, cell_tags, faces = _press(axis, COMM)
    deck, used = _deck(mesh, cell_tags, faces)
    (tmp_path / "punch.inp").write_text(deck)
    run_ccx(tmp_path, "punch", timeout=300)
    blocks = read_ccx_dat(tmp_path, "punch")
    (tmp_path / "runner").mkdir()
    (tmp_path / "runner" / "punch.inp").write_text(deck)
    job = run_job("punch", tmp_path / "runner", comm=COMM, progress=False)
    assert job.completed
    runner = read_ccx_dat(tmp_path / "runner", "punch")
    # the same contact surfaces as the deck runner's, by ccx node numbers, face for face
    for role in ("slave", "master"):
        ours_surface = getattr(_pair(V, faces), role)
        theirs = getattr(job.model.pairs[0], role)
        ours_rows = _input_of_dof(V)[ours_surface.faces] + 1
        theirs_rows = job.model.dof_node[theirs.faces]
        assert ours_surface.face_type is theirs.face_type
        np.testing.assert_array_equal(np.unique(ours_rows, axis=0), np.unique(theirs_rows, axis=0))
    node = np.full(_input_of_dof(V).max() + 2, -1)
    node[_input_of_dof(V) + 1] = np.arange(_input_of_dof(V).size)
    displacement = dat_block(blocks, "U", time=1.0)
    assert np.array_equal(np.sort(displacement.labels), used)
    ours = u.x.array.reshape(-1, 3)[node[displacement.labels]]
    scale = np.abs(displacement.values).max()
    assert scale >= DEPTH
    errors = {"U": np.abs(ours - displacement.values).max() / scale}
    runner_errors = {"U": _difference(runner, displacement)}
    (result,) = ntf.contact_results(problem)
    order = np.argsort(_input_of_dof(V)[result.node])
    for name, values in (("CDIS", result.clearance), ("CSTR", result.pressure)):
        block = dat_block(blocks, name, time=1.0)
        labels = _input_of_dof(V)[result.node][order] + 1
        np.testing.assert_array_equal(labels, block.labels)  # the same springs
        scale = np.abs(block.values[:, 0]).max()
        assert scale > 0.0
        errors[name] = np.abs(values[order] - block.values[:, 0]).max() / scale
        runner_errors[name] = _difference(runner, block)
    print(f"{axis}: {len(result.node)} springs; API {errors}; deck runner {runner_errors}")
    assert result.pressure.max() > 0.0 and result.clearance.min() < 0.0  # pressed
    assert all(e < 1e-6 for e in runner_errors.values()), runner_errors
    assert all(e < 1e-5 for e in errors.values()), errors  # 3.9e-7 U, 5.5e-6 CDIS, CSTR


def _difference(blocks: list, reference) -> float:
    """Largest difference of ``blocks``' block like ``reference`` from it, over its largest."""
    from dolfinx_ntf.calculix.ccx import dat_block

    block = dat_block(blocks, reference.name, time=1.0)
    np.testing.assert_array_equal(block.labels, reference.labels)
    return float(np.abs(block.values - reference.values).max() / np.abs(reference.values).max())


@pytest.mark.mpi
@needs_011
@AXES
def test_flat_punch_carries_a_uniform_pressure(axis):
    """A flat punch covering the block's top, a uniform pressure ``p`` on its top, rollers on
    x = 0, y = 0 and z = 0: the spring areas sum to the top's area ``A``, the springs carry
    the load (their normal forces sum to ``p A`` to 1e-9) and the punch moves down, serial and
    on 2 processes.

    The contact pressure is not uniform (docs/method.md §40.6): ccx's shares of the quadratic
    faces (1/100, 24/100; 1/999, 332/999) are not the consistent loads of a uniform pressure
    (negative at the corners), so a uniform stress is no solution of the node-to-face springs.
    """
    comm = COMM
    mesh, cell_tags, faces = mesh_from_gmsh(
        build_prism_punch, comm, axis=axis, punch=(0.0, 0.0, 2.0, 1.0)
    )
    V, constraints = wedge15_space(mesh)
    u = dolfinx.fem.Function(V, name="u")
    bcs = []
    for c in range(3):
        dofs = clamped_dofs(V, lambda x, c=c: np.isclose(x[c], 0.0), constraints, c)
        bcs.append(dolfinx.fem.dirichletbc(0.0, dofs, V.sub(c)))
    problem = ntf.ContactProblem(
        _residual(V, u, cell_tags), u, [_pair(V, faces)], bcs, constraints=constraints
    )
    state = problem.states[0]  # the slave faces sent to the owners of their nodes
    owned = state.slave.nodes < V.dofmap.index_map.size_local
    areas = slave_areas(state.slave, problem.reference_coordinates)[owned]
    assert _total(areas.sum()) == pytest.approx(2.0, rel=1e-12)
    p = 5.0
    unit = prism_face_forces(V, faces, PUNCH_TOP, 1.0)
    problem.nodal_loads = dolfinx.fem.Function(V)
    solver = ntf.ContactNewtonSolver(comm, problem)

    def load(t: float) -> None:
        problem.nodal_loads.x.array[:] = p * t * unit.x.array

    ntf.StaticStep(load, initial_increment=0.5, fixed=True).run(solver, u)
    (result,) = ntf.contact_results(problem)
    owned = result.node < V.dofmap.index_map.size_local
    assert _total(result.force[owned, 2].sum()) == pytest.approx(p * 2.0, rel=1e-9)
    x = V.tabulate_dof_coordinates()
    top = np.isclose(x[:, 2], 1.5)
    uz = u.x.array.reshape(-1, 3)[top, 2]
    low = comm.allreduce(uz.min(initial=np.inf), op=MPI.MIN)
    high = comm.allreduce(uz.max(initial=-np.inf), op=MPI.MAX)
    assert high < 0.0
    pressure = result.pressure[owned]
    smallest = comm.allreduce(pressure.min(initial=np.inf), op=MPI.MIN)
    largest = comm.allreduce(pressure.max(initial=-np.inf), op=MPI.MAX)
    print(f"{axis}: top uz {low:.6e} .. {high:.6e}; CSTR {smallest:.6g} .. {largest:.6g}")


@pytest.mark.mpi
@needs_011
def test_a_tag_of_triangles_and_quadrilaterals():
    """The block's top (triangles) and end (quadrilaterals) under one tag: a slave surface of
    two face types whose areas sum to both faces' (serial), refused by ``resolve_master`` (one
    face type; contact pairs take it through ``master_face_groups``); a face node outside the
    mesh is named."""
    from helpers.quadratic_prisms import END, TOP, build_prism_block

    mesh, _, faces = mesh_from_gmsh(build_prism_block, COMM)
    V, _ = wedge15_space(mesh)
    both = PrismFaces(
        faces.triangles,
        np.where(faces.triangle_tags == TOP, 99, faces.triangle_tags),
        faces.quadrilaterals,
        np.where(faces.quadrilateral_tags == END, 99, faces.quadrilateral_tags),
    )
    surface = prism_face_surface(V, both, 99, "top and end")
    assert surface.face_type is QUAD8_GAUSS2 and [t for t, _ in surface.more] == [TRI6]
    with pytest.raises(NotImplementedError, match="a master surface of one face type only"):
        resolve_master(V, surface)
    slave = resolve_slave(V, surface)
    assert [g.face_type for g in slave.face_groups] == [QUAD8_GAUSS2, TRI6]
    if COMM.size == 1:
        X = V.tabulate_dof_coordinates()
        assert slave_areas(slave, X).sum() == pytest.approx(2.0 + 1.0, rel=1e-12)
    far = np.array(faces.triangles)
    far[0, 0] = 10**6
    outside = PrismFaces(far, faces.triangle_tags, faces.quadrilaterals, faces.quadrilateral_tags)
    tag = int(faces.triangle_tags[0])
    with pytest.raises(ValueError, match=rf"face node 1000000 \(input index\) of tag {tag} is not"):
        prism_face_surface(V, outside, tag)
