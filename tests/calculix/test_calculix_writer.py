"""``write_inp``: problems exported as ccx decks, read back by ``read_deck`` and run by ccx."""

from __future__ import annotations

import functools
import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers import LOWER, LOWER_BOTTOM, LOWER_TOP, UPPER, UPPER_BOTTOM, UPPER_TOP, two_blocks

import dolfinx.fem
import dolfinx.mesh

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.calculix.ccx import read_ccx_dat, run_ccx
from dolfinx_ntf.calculix.deck import ELEMENT_TYPES, face_nodes, read_deck
from dolfinx_ntf.calculix.writer import (
    TIGHT_FIELD_CONTROLS,
    AmplitudeSpec,
    BoundarySpec,
    OutputSpec,
    PointLoadSpec,
    PressureSpec,
    StepSpec,
    _real,
    write_inp,
)
from dolfinx_ntf.fem.surfaces import boundary_faces

serial = pytest.mark.serial

E1, NU1, E2, NU2 = 1000.0, 0.3, 2000.0, 0.25
UPPER_BOX = ((0.1, 0.15, 0.0), (0.6, 0.6, 0.5), (3, 3, 2))
CASES = [("hexahedron", 1, "C3D8"), ("tetrahedron", 1, "C3D4"), ("tetrahedron", 2, "C3D10")]


def _space(cell: str, degree: int, mirror: bool = False):
    """Two blocks; ``mirror`` reflects x, making every dolfinx cell vertex order left-handed."""
    mesh, ct, ft = two_blocks(cell=cell, upper=UPPER_BOX, lower=((0, 0, -1), (1, 1, 1), (2, 2, 2)))
    if mirror:
        mesh.geometry.x[:, 0] = 1.0 - mesh.geometry.x[:, 0]
    return compat.vector_space(mesh, "Lagrange", degree), ct, ft


def _write_full(path, V, ct, ft, *, nodal_slave: bool = False):
    law = ntf.TabularLaw(pressures=[0.0, 10.0, 50.0], overclosures=[0.0, 1e-3, 2e-3])
    if nodal_slave:
        vertices = compat.incident_entities(V.mesh, ft.find(UPPER_BOTTOM), 2, 0)
        slave = ntf.NodeSurface(vertices)
    else:
        slave = ntf.FacetSurface(ft, UPPER_BOTTOM)
    pairs = [
        ntf.ContactPair(slave, ntf.FacetSurface(ft, LOWER_TOP), ntf.SurfaceInteraction(law)),
    ]
    top = ntf.FacetSurface(ft, UPPER_TOP)
    steps = [
        StepSpec(
            boundaries=[BoundarySpec(top, (0, 2), -0.01, name="press")],
            pressures=[PressureSpec(top, 2.5)],
            point_loads=[PointLoadSpec(np.array([0, 1], dtype=np.int32), 1, 0.125)],
            increments=4,
            nlgeom=True,
            amplitude=AmplitudeSpec((0.0, 1.0), (0.0, 2.0), name="ramp"),
            field_controls=TIGHT_FIELD_CONTROLS,
            output=OutputSpec(
                node_print=("U", "RF"), el_print=("S",), contact_elements=True, frequency=2
            ),
        ),
        StepSpec(period=2.0, increments=None, initial_increment=0.5, max_increment=1.0),
    ]
    numbering = write_inp(
        path,
        displacement_space=V,
        materials={LOWER: (E1, NU1), UPPER: (E2, NU2)},
        cell_tags=ct,
        pairs=pairs,
        fixed=[BoundarySpec(ntf.FacetSurface(ft, LOWER_BOTTOM))],
        steps=steps,
        heading="writer test\nsecond line",
    )
    return numbering, read_deck(path)


def _ids_of_facets(V, numbering, ft, tag):
    faces = boundary_faces(V, ft.find(tag))
    return numbering.node_ids[faces.faces]


@serial
@pytest.mark.parametrize("mirror", [False, True])
@pytest.mark.parametrize("cell,degree,etype", CASES)
def test_round_trip_mesh_and_materials(tmp_path, cell, degree, etype, mirror):
    V, ct, ft = _space(cell, degree, mirror)
    numbering, deck = _write_full(tmp_path / "job.inp", V, ct, ft)
    assert numbering.element_type == etype
    assert list(deck.elements) == [etype]

    # Nodes: one per block dof, at the dof coordinates (ids = block index + 1 in serial).
    X = V.tabulate_dof_coordinates().reshape(-1, 3)
    np.testing.assert_array_equal(numbering.node_ids, np.arange(1, X.shape[0] + 1))
    np.testing.assert_array_equal(deck.node_ids, numbering.node_ids)
    np.testing.assert_allclose(deck.node_coords, X, rtol=0, atol=1e-15)

    # Elements: same node sets as the dolfinx cells.
    block = deck.elements[etype]
    cell_dofs = compat.cell_dofs(V)
    order = np.argsort(block.ids)
    np.testing.assert_array_equal(block.ids[order], numbering.element_ids)
    np.testing.assert_array_equal(
        np.sort(block.connectivity[order], axis=1), np.sort(numbering.node_ids[cell_dofs], axis=1)
    )
    # Vertex nodes carry the mesh's own coordinates bit for bit (no tabulation round-off), so
    # that nodes placed exactly above other nodes stay exactly there in the deck.
    layout = V.dofmap.dof_layout
    num_vertices = compat.geometry_dofs(V.mesh).shape[1]
    vertex_dofs = cell_dofs[:, [layout.entity_dofs(0, v)[0] for v in range(num_vertices)]]
    np.testing.assert_array_equal(
        deck.node_coords[vertex_dofs], V.mesh.geometry.x[compat.geometry_dofs(V.mesh)]
    )

    # Orientation: every ccx face of every element points away from the element (ccx needs a
    # positive Jacobian). Face normals from the corner cross product.
    x = deck.node_coords[deck.node_index(block.connectivity)]
    table = ELEMENT_TYPES[etype]
    centre = x[:, : table.num_corners].mean(axis=1)
    corners = table.faces[:, : table.face_corners]
    fx = x[:, corners]  # (E, faces, corners, 3)
    if table.face_corners == 3:
        normal = np.cross(fx[:, :, 1] - fx[:, :, 0], fx[:, :, 2] - fx[:, :, 0])
    else:
        normal = np.cross(fx[:, :, 2] - fx[:, :, 0], fx[:, :, 3] - fx[:, :, 1])
    outward = np.einsum("efi,efi->ef", normal, fx.mean(axis=2) - centre[:, None])
    assert np.all(outward > 0)
    if etype == "C3D10":  # midside nodes 5..10 on edges 1-2, 2-3, 3-1, 1-4, 2-4, 3-4
        edges = np.array([[0, 1], [1, 2], [2, 0], [0, 3], [1, 3], [2, 3]])
        np.testing.assert_array_equal(x[:, 4:], x[:, edges].mean(axis=2))
    if cell == "tetrahedron":  # the split cube has both orientations: both tables are used
        dofs = cell_dofs[:, :4]
        det = np.linalg.det(X[dofs[:, 1:]] - X[dofs[:, :1]])
        assert np.any(det < 0) and np.any(det > 0)

    # Materials per cell tag.
    for tag, elastic in ((LOWER, (E1, NU1)), (UPPER, (E2, NU2))):
        section = next(s for s in deck.sections if s.elset == f"E{tag}")
        assert deck.materials[section.material].elastic == elastic
        expected = numbering.element_ids[ct.indices[ct.values == tag]]
        np.testing.assert_array_equal(np.sort(deck.elsets[f"E{tag}"]), np.sort(expected))
    assert deck.heading == "writer test\nsecond line"


@serial
@pytest.mark.parametrize("mirror", [False, True])
@pytest.mark.parametrize("cell,degree,etype", CASES)
def test_round_trip_contact_loads_steps(tmp_path, cell, degree, etype, mirror):
    V, ct, ft = _space(cell, degree, mirror)
    numbering, deck = _write_full(tmp_path / "job.inp", V, ct, ft)

    # Surfaces: the faces of the tagged facets, with ccx face labels giving the same nodes.
    for name, tag in (("SLAVE1", UPPER_BOTTOM), ("MASTER1", LOWER_TOP)):
        got = face_nodes(deck, name)
        expected = _ids_of_facets(V, numbering, ft, tag)
        assert got.shape == expected.shape
        key = lambda a: np.unique(np.sort(a, axis=1), axis=0)  # noqa: E731
        np.testing.assert_array_equal(key(got), key(expected))
    (pair,) = deck.contact_pairs
    assert (pair.slave, pair.master, pair.small_sliding) == ("SLAVE1", "MASTER1", False)
    behavior = deck.interactions[pair.interaction].behavior
    assert behavior.pressure_overclosure == "TABULAR"
    np.testing.assert_array_equal(behavior.table, [[0.0, 0.0], [10.0, 1e-3], [50.0, 2e-3]])

    # Constraints and loads.
    (fixed,) = deck.boundaries
    bottom = np.unique(_ids_of_facets(V, numbering, ft, LOWER_BOTTOM))
    np.testing.assert_array_equal(np.sort(fixed.nodes), bottom)
    assert (fixed.first_dof, fixed.last_dof, fixed.value) == (1, 3, 0.0)
    step1, step2 = deck.steps
    top = np.unique(_ids_of_facets(V, numbering, ft, UPPER_TOP))
    assert [
        (b.target, b.first_dof, b.last_dof, b.value, b.amplitude) for b in step1.boundaries
    ] == [
        ("PRESS", 1, 1, -0.01, "RAMP"),
        ("PRESS", 3, 3, -0.01, "RAMP"),
    ]
    np.testing.assert_array_equal(np.sort(step1.boundaries[0].nodes), top)
    (cload,) = step1.cloads
    np.testing.assert_array_equal(np.sort(cload.nodes), [1, 2])
    assert (cload.dof, cload.value) == (2, 0.125)
    top_faces = _ids_of_facets(V, numbering, ft, UPPER_TOP)
    loaded = []
    for load in step1.dloads:
        assert load.value == 2.5 and load.amplitude == "RAMP"
        block = deck.elements[etype]
        row = np.searchsorted(block.ids, load.elements)
        loaded.append(block.connectivity[row][:, ELEMENT_TYPES[etype].faces[load.face - 1]])
    loaded = np.concatenate(loaded)
    np.testing.assert_array_equal(
        np.unique(np.sort(loaded, axis=1), axis=0), np.unique(np.sort(top_faces, axis=1), axis=0)
    )
    amp = deck.amplitudes["RAMP"]
    np.testing.assert_array_equal(amp.times, [0.0, 1.0])
    np.testing.assert_array_equal(amp.values, [0.0, 2.0])

    # Steps.
    assert step1.nlgeom and not step2.nlgeom
    assert (step1.static.initial_increment, step1.static.period, step1.static.direct) == (
        0.25,
        1.0,
        True,
    )
    assert step1.max_increments == 100
    assert (step2.static.initial_increment, step2.static.period, step2.static.direct) == (
        0.5,
        2.0,
        False,
    )
    assert step2.static.maximum == 1.0 and step2.static.minimum is None
    controls = step1.field_controls()
    for name, value in TIGHT_FIELD_CONTROLS.items():
        assert controls[name] == value
    assert step1.contact_elements and step1.output_frequency == 2
    assert [(p.kind, p.keys) for p in step1.prints] == [
        ("NODE", ("U", "RF")),
        ("EL", ("S",)),
        ("CONTACT", ("CDIS", "CSTR", "CELS", "CNUM")),
    ]


@serial
def test_node_based_slave_and_laws(tmp_path):
    V, ct, ft = _space("hexahedron", 1)
    numbering, deck = _write_full(tmp_path / "job.inp", V, ct, ft, nodal_slave=True)
    surface = deck.surfaces["SLAVE1"]
    assert surface.type == "NODE"
    expected = np.unique(_ids_of_facets(V, numbering, ft, UPPER_BOTTOM))
    np.testing.assert_array_equal(np.sort(surface.nodes), expected)

    master = ntf.FacetSurface(ft, LOWER_TOP)
    laws = [
        ntf.ExponentialLaw(c0=0.01, p0=3.0),
        ntf.LinearLaw(slope=5e4, tension=0.0142857, c0=2e-3),
        ntf.LinearLaw.with_ccx_defaults(E1),
    ]
    pairs = [
        ntf.ContactPair(ntf.FacetSurface(ft, UPPER_BOTTOM), master, ntf.SurfaceInteraction(law))
        for law in laws
    ]
    pairs[-1] = ntf.ContactPair(pairs[-1].slave, master, pairs[-1].interaction, small_sliding=True)
    write_inp(tmp_path / "laws.inp", displacement_space=V, materials=(E1, NU1), pairs=pairs)
    deck = read_deck(tmp_path / "laws.inp")
    values = [deck.interactions[p.interaction].behavior for p in deck.contact_pairs]
    assert [(b.pressure_overclosure, b.values) for b in values] == [
        ("EXPONENTIAL", (0.01, 3.0)),
        ("LINEAR", (5e4, 0.0142857, 2e-3)),
        ("LINEAR", (50 * E1, E1 / 70000.0, 1e-3)),
    ]
    assert [p.small_sliding for p in deck.contact_pairs] == [False, False, True]
    assert next(iter(deck.materials.values())).elastic == (E1, NU1)
    assert deck.steps[0].static.direct and deck.steps[0].static.initial_increment == 1.0


@serial
def test_reals_fit_ccx_fields():
    for value in (0.1, -2.7755575615628914e-17, 1 / 3, -1e-300 / 3, 123456789.123456789, 0.0):
        text = _real(value, "x")
        assert len(text) <= 20
        assert float(text) == pytest.approx(value, rel=2e-13, abs=0)  # 14+ significant digits
    assert _real(0.1, "x") == "0.1"  # shortest round trip when it fits
    with pytest.raises(ValueError, match="x must be finite"):
        _real(float("nan"), "x")


@serial
def test_bad_input(tmp_path):
    V, ct, ft = _space("hexahedron", 1)
    path = tmp_path / "bad.inp"
    law = ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(E1))
    good_pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM), ntf.FacetSurface(ft, LOWER_TOP), law
    )
    mesh = V.mesh
    write = functools.partial(write_inp, path, displacement_space=V, materials=(E1, NU1))
    with pytest.raises(ValueError, match="no ccx element for degree-2 Lagrange on hexahedron"):
        write(displacement_space=compat.vector_space(mesh, "Lagrange", 2))
    with pytest.raises(ValueError, match="3D vector displacement space"):
        write(displacement_space=compat.scalar_space(mesh, "Lagrange", 1))
    with pytest.raises(ValueError, match="materials per cell tag need cell_tags"):
        write(materials={1: (E1, NU1)})
    with pytest.raises(ValueError, match=r"has tag 2, and materials are given for tags \[1\] only"):
        write(materials={1: (E1, NU1)}, cell_tags=ct)
    with pytest.raises(ValueError, match=r"needs E > 0 and -1 < nu < 0.5, got \(1000.0, 0.5\)"):
        write(materials=(E1, 0.5))
    with pytest.raises(ValueError, match=r"facet tag value\(s\) \[99\] not found"):
        write(pairs=[ntf.ContactPair(ntf.FacetSurface(ft, 99), good_pair.master, law)])
    with pytest.raises(ValueError, match="master surface must be a FacetSurface"):
        write(pairs=[ntf.ContactPair(good_pair.slave, ntf.NodeSurface(np.array([0])), law)])
    with pytest.raises(ValueError, match="model_change 'DELETE'"):
        write(steps=[StepSpec(model_change={1: "DELETE"})])
    mesh.topology.create_connectivity(2, 3)
    f_to_c = mesh.topology.connectivity(2, 3)
    inner = np.flatnonzero(np.diff(f_to_c.offsets) == 2)[:1].astype(np.int32)
    interior = dolfinx.mesh.meshtags(mesh, 2, inner, np.array([7], dtype=np.int32))
    with pytest.raises(ValueError, match=r"pressure 1: 1 facet\(s\) lie between two cells"):
        write(steps=[StepSpec(pressures=[PressureSpec(ntf.FacetSurface(interior, 7), 1.0)])])
    top = ntf.FacetSurface(ft, UPPER_TOP)
    with pytest.raises(ValueError, match=r"boundary 1: components must be a non-empty subset"):
        write(steps=[StepSpec(boundaries=[BoundarySpec(top, (3,))])])
    with pytest.raises(ValueError, match=r"point load 1: component must be 0, 1 or 2"):
        write(steps=[StepSpec(point_loads=[PointLoadSpec(top, 5, 1.0)])])
    with pytest.raises(ValueError, match=r"block dof indices outside 0\.\."):
        write(steps=[StepSpec(point_loads=[PointLoadSpec(np.array([10**6]), 0, 1.0)])])
    with pytest.raises(ValueError, match="the node set is empty"):
        write(steps=[StepSpec(point_loads=[PointLoadSpec(np.array([], dtype=np.int64), 0, 1.0)])])
    with pytest.raises(ValueError, match="node set name FIX is used twice"):
        write(fixed=[BoundarySpec(top, name="fix"), BoundarySpec(top, name="FIX")])
    with pytest.raises(ValueError, match="not a valid ccx name"):
        write(fixed=[BoundarySpec(top, name="a,b")])
    with pytest.raises(ValueError, match="at least one step"):
        write(steps=[])
    with pytest.raises(ValueError, match="increments must be an integer >= 1"):
        write(steps=[StepSpec(increments=0)])
    with pytest.raises(ValueError, match=r"unknown field control\(s\) \['R_x'\]"):
        write(steps=[StepSpec(field_controls={"R_x": 1.0})])
    with pytest.raises(ValueError, match=r"node_print keys \['S'\] not supported"):
        write(steps=[StepSpec(output=OutputSpec(node_print=("S",)))])
    with pytest.raises(ValueError, match="initial_increment <= period"):
        write(steps=[StepSpec(increments=None, initial_increment=2.0)])
    with pytest.raises(ValueError, match="amplitude RAMP needs as many values as times"):
        write(steps=[StepSpec(amplitude=AmplitudeSpec((0.0, 1.0), (1.0,), name="ramp"))])
    assert not path.exists()


# ----------------------------------------------------------------------------- with ccx


@serial
@pytest.mark.ccx
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")
@pytest.mark.parametrize("mirror", [False, True])
@pytest.mark.parametrize("cell,degree,etype", CASES)
def test_ccx_runs_written_deck_pressure_resultant(tmp_path, cell, degree, etype, mirror):
    """ccx runs the deck; the base reactions balance the top pressure (P face labels right)."""
    V, ct, _ft = _space(cell, degree, mirror)
    pressure = 3.0
    mesh = V.mesh
    # The lower block alone: fixed bottom, pressure on its top (area 1).
    lower_cells = ct.indices[ct.values == LOWER]
    sub, _cell_map, _, _ = dolfinx.mesh.create_submesh(mesh, 3, lower_cells)
    Vs = compat.vector_space(sub, "Lagrange", degree)
    sub.topology.create_connectivity(2, 3)
    exterior = dolfinx.mesh.exterior_facet_indices(sub.topology)
    z = dolfinx.mesh.compute_midpoints(sub, 2, exterior)[:, 2]
    values = np.where(np.isclose(z, 0.0), 2, np.where(np.isclose(z, -1.0), 1, 0)).astype(np.int32)
    keep = values > 0
    tags = dolfinx.mesh.meshtags(sub, 2, exterior[keep], values[keep])
    base = ntf.FacetSurface(tags, 1)
    steps = [
        StepSpec(
            pressures=[PressureSpec(ntf.FacetSurface(tags, 2), pressure)],
            output=OutputSpec(node_print=("RF",), node_set=base, contact_print=()),
        )
    ]
    write_inp(
        tmp_path / "block.inp",
        displacement_space=Vs,
        materials=(E1, NU1),
        fixed=[BoundarySpec(base)],
        steps=steps,
    )
    run_ccx(tmp_path, "block", timeout=120)
    (rf,) = [b for b in read_ccx_dat(tmp_path, "block") if b.name == "RF"]
    # The base reactions balance the pressure on the top (area 1, pushing down); a wrong face
    # label would load another face (a side: horizontal reaction; the bottom: none).
    assert rf.set == "S1OUT"
    assert rf.values.shape[0] == dolfinx.fem.locate_dofs_topological(Vs, 2, tags.find(1)).size
    total = rf.values.sum(axis=0)
    np.testing.assert_allclose(total, [0.0, 0.0, pressure * 1.0], atol=1e-6)


@pytest.mark.mpi
def test_write_inp_is_collective(tmp_path):
    """Under MPI every rank passes its local part and rank 0 writes one deck with global numbers."""
    comm = MPI.COMM_WORLD
    path = Path(comm.bcast(str(tmp_path), root=0)) / "parallel.inp"
    V, ct, ft = _space("tetrahedron", 2)
    mesh = V.mesh
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, UPPER_BOTTOM),
        ntf.FacetSurface(ft, LOWER_TOP),
        ntf.SurfaceInteraction(ntf.LinearLaw.with_ccx_defaults(E1)),
    )
    top = ntf.FacetSurface(ft, UPPER_TOP)
    numbering = write_inp(
        path,
        displacement_space=V,
        materials={LOWER: (E1, NU1), UPPER: (E2, NU2)},
        cell_tags=ct,
        pairs=[pair],
        fixed=[BoundarySpec(ntf.FacetSurface(ft, LOWER_BOTTOM))],
        steps=[StepSpec(pressures=[PressureSpec(top, 1.0)])],
    )
    comm.barrier()
    deck = read_deck(path)
    # Every local node (owned and ghost) is in the deck, at its coordinates; sizes are global.
    X = V.tabulate_dof_coordinates().reshape(-1, 3)
    np.testing.assert_allclose(deck.node_coords[deck.node_index(numbering.node_ids)], X, atol=1e-14)
    assert deck.node_ids.size == V.dofmap.index_map.size_global
    block = deck.elements["C3D10"]
    assert block.ids.size == mesh.topology.index_map(3).size_global
    owned = mesh.topology.index_map(3).size_local
    cell_dofs = compat.cell_dofs(V)[:owned]
    order = np.argsort(block.ids)
    rows = order[np.searchsorted(block.ids, numbering.element_ids[:owned], sorter=order)]
    np.testing.assert_array_equal(
        np.sort(block.connectivity[rows], axis=1), np.sort(numbering.node_ids[cell_dofs], axis=1)
    )
    # Surfaces: one face per tagged facet of the whole mesh, with the facet's nodes.
    for name, tag in (("SLAVE1", UPPER_BOTTOM), ("MASTER1", LOWER_TOP)):
        faces = boundary_faces(V, ft.find(tag))
        mine = faces.facets < mesh.topology.index_map(2).size_local
        local = np.sort(numbering.node_ids[faces.faces[mine]], axis=1)
        everything = np.concatenate(comm.allgather(local))
        got = np.sort(face_nodes(deck, name), axis=1)
        assert got.shape == everything.shape
        np.testing.assert_array_equal(np.unique(got, axis=0), np.unique(everything, axis=0))
