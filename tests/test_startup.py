"""Start-up of the deck runner (issue 26): what ``import dolfinx_ntf`` and the deck runner load,
and the shortcuts of the set-up (one scalar space per mesh, one reference-coordinate pass for the
surfaces, one search for the deck's references), each checked against the long way."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest

import dolfinx.fem
import dolfinx.mesh

from dolfinx_ntf import compat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.fem.surfaces import boundary_faces, reference_coordinates

ROOT = Path(__file__).resolve().parents[1]
BASE = (ROOT / "tests" / "data" / "calculix" / "two_cubes.inp").read_text()

#: Modules of features a static contact deck does not use: the deck runner must not import them.
OTHER_STEPS = (
    "dolfinx_ntf.solvers.dynamics",
    "dolfinx_ntf.solvers.modal_dynamics",
    "dolfinx_ntf.solvers.modes",
    "dolfinx_ntf.calculix.coupled",
    "dolfinx_ntf.calculix.modal_dat",
    "dolfinx_ntf.calculix.modal_increments",
    "dolfinx_ntf.calculix.writer",
    "dolfinx_ntf.calculix.compare",
)


def _modules_after(statement: str) -> set[str]:
    """The modules a fresh interpreter holds after ``statement`` (this checkout on the path)."""
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])
    )
    code = f"import json, sys\n{statement}\nprint(json.dumps(sorted(sys.modules)))"
    done = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-2000:]
    return set(json.loads(done.stdout.splitlines()[-1]))


@pytest.mark.serial
def test_import_of_the_package_loads_no_feature_module():
    loaded = _modules_after("import dolfinx_ntf")
    features = {m for m in loaded if m.startswith("dolfinx_ntf.")}
    assert features <= {"dolfinx_ntf._moved", "dolfinx_ntf.lazy_names", "dolfinx_ntf.logs"}, sorted(
        features
    )
    assert "scipy.sparse" not in loaded


@pytest.mark.serial
def test_deck_runner_loads_no_module_of_other_steps():
    loaded = _modules_after("import dolfinx_ntf.calculix.job")
    assert "dolfinx_ntf.contact.problem" in loaded  # what a contact deck needs is there
    assert not loaded & set(OTHER_STEPS), sorted(loaded & set(OTHER_STEPS))


@pytest.mark.serial
def test_every_public_name_resolves_to_its_module():
    import importlib

    import dolfinx_ntf as ntf

    for name in ntf.__all__:
        if name == "__version__":
            continue
        module = importlib.import_module(f"dolfinx_ntf.{ntf._LAZY[name]}")
        assert getattr(ntf, name) is getattr(module, name), name
    assert set(ntf.__all__) <= set(dir(ntf))
    assert ntf.contact.problem.ContactProblem is ntf.ContactProblem  # subpackages as attributes
    with pytest.raises(AttributeError, match="has no attribute 'NoSuchName'"):
        getattr(ntf, "NoSuchName")


@pytest.mark.mpi
def test_component_spaces_share_one_scalar_space_and_map_each_component():
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 2, 2, 3, dolfinx.mesh.CellType.hexahedron)
    V = compat.vector_space(mesh, "Lagrange", 1)
    u = dolfinx.fem.Function(V)
    u.interpolate(lambda x: np.vstack([x[0] + 10, 2 * x[1] - 3, x[2] * x[0]]))
    spaces = [compat.component_space(V, c) for c in range(3)]
    if compat.DOLFINX_VERSION < (0, 7):  # 0.5.2: one scalar space, built once
        assert all(Q is spaces[0][0] for Q, _ in spaces)
    for c, (Q, dofs) in enumerate(spaces):
        X = Q.tabulate_dof_coordinates()
        x = X[:, 0], X[:, 1], X[:, 2]
        expected = (x[0] + 10, 2 * x[1] - 3, x[2] * x[0])[c]
        assert np.allclose(u.x.array[dofs], expected, rtol=0.0, atol=1e-12)
    W = compat.vector_space(mesh, "Lagrange", 2)  # another degree: another scalar space
    Q2, dofs2 = compat.component_space(W, 1)
    assert Q2 is not spaces[0][0] and compat.space_degree(Q2) == 2
    assert dofs2.size == Q2.dofmap.index_map.size_local + Q2.dofmap.index_map.num_ghosts


@pytest.mark.mpi
def test_boundary_faces_with_given_reference_coordinates_are_the_computed_ones():
    mesh = dolfinx.mesh.create_unit_cube(MPI.COMM_WORLD, 3, 2, 2, dolfinx.mesh.CellType.hexahedron)
    V = compat.vector_space(mesh, "Lagrange", 2)
    mesh.topology.create_connectivity(2, 3)
    facets = dolfinx.mesh.locate_entities_boundary(mesh, 2, lambda x: np.isclose(x[2], 1.0))
    computed = boundary_faces(V, facets)
    given = boundary_faces(V, facets, reference=reference_coordinates(V))
    assert computed.face_type is given.face_type
    assert np.array_equal(computed.faces, given.faces)
    assert np.array_equal(computed.facets, given.facets)


def _deck(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "deck.inp"
    path.write_text(text)
    return path


def _line(path: Path, needle: str) -> int:
    return next(n for n, line in enumerate(path.read_text().splitlines(), 1) if needle in line)


@pytest.mark.serial
def test_the_first_bad_reference_of_the_deck_is_named(tmp_path):
    """Two undefined nodes on two cards and an undefined element: the first in deck order."""
    text = BASE.replace("TOP, 3, 3, -0.001", "TOP, 3, 3, -0.001\n77, 1, 1\n88, 2, 2")
    text = text.replace("*SURFACE, NAME=SLAVE\n2, S1", "*SURFACE, NAME=SLAVE\n2, S1\n9, S1")
    path = _deck(tmp_path, text)
    with pytest.raises(DeckError, match=rf"deck\.inp:{_line(path, '77, 1, 1')}: .*node 77, "):
        read_deck(path)
    path = _deck(tmp_path, text.replace("77, 1, 1\n", ""))
    with pytest.raises(DeckError, match=rf"deck\.inp:{_line(path, '88, 2, 2')}: .*node 88, "):
        read_deck(path)
    path = _deck(tmp_path, text.replace("77, 1, 1\n88, 2, 2\n", ""))
    with pytest.raises(DeckError, match=rf"deck\.inp:{_line(path, '9, S1')}: .*element 9, "):
        read_deck(path)
    deck = read_deck(_deck(tmp_path, BASE))  # and a good deck reads
    assert deck.node_ids.size == 16
