"""Tests of the CalculiX deck reader (dolfinx_ntf.calculix.deck): pure Python, no ccx needed."""

from __future__ import annotations

import dataclasses
import re
from pathlib import Path

import numpy as np
import pytest

from dolfinx_ntf.calculix.deck import (
    ELEMENT_TYPES,
    DeckError,
    external_faces,
    face_nodes,
    node_surface_faces,
    read_deck,
    surface_nodes,
)
from dolfinx_ntf.calculix.deck import mesh as mesh_cards

DATA = Path(__file__).parents[1] / "data" / "calculix"

# Reference coordinates of the ccx elements (manual figures: C3D8 fig. 49, C3D10 fig. 55).
_HEX = np.array(
    [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [1, 1, 1], [0, 1, 1]], float
)
_TET = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
_TET10 = np.vstack(
    [_TET] + [(_TET[a] + _TET[b]) / 2 for a, b in ((0, 1), (1, 2), (2, 0), (0, 3), (1, 3), (2, 3))]
)
_BASE = (DATA / "two_cubes.inp").read_text()


def _line_of(path: Path, needle: str) -> int:
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        if needle in line:
            return number
    raise AssertionError(f"{needle!r} not in {path}")


REFERENCE = {"C3D8": _HEX, "C3D4": _TET, "C3D10": _TET10}

# The manual's face tables (*SURFACE, *DLOAD), 1-based, inward orientation.
MANUAL_FACES = {
    "C3D8": [[1, 2, 3, 4], [5, 8, 7, 6], [1, 5, 6, 2], [2, 6, 7, 3], [3, 7, 8, 4], [4, 8, 5, 1]],
    "C3D4": [[1, 2, 3], [1, 4, 2], [2, 4, 3], [3, 4, 1]],
    "C3D10": [[1, 2, 3], [1, 4, 2], [2, 4, 3], [3, 4, 1]],
}


# ----------------------------------------------------------------------------- element faces


@pytest.mark.parametrize("name", ["C3D4", "C3D8", "C3D10"])
def test_faces_point_outward_and_match_manual_node_sets(name):
    etype = ELEMENT_TYPES[name]
    x = REFERENCE[name]
    centroid = x[: etype.num_corners].mean(axis=0)
    for k, face in enumerate(etype.faces):
        corners = x[face[: etype.face_corners]]
        # Newell normal of the corner polygon: right-hand rule over the face order
        normal = np.sum(np.cross(corners, np.roll(corners, -1, axis=0)), axis=0)
        outward = corners.mean(axis=0) - centroid
        assert normal @ outward > 0.0, f"{name} S{k + 1} points inward"
        manual = MANUAL_FACES[name][k]
        assert sorted(face[: etype.face_corners] + 1) == sorted(manual)
        # same cyclic order as the manual, reversed
        reversed_manual = manual[::-1]
        start = reversed_manual.index(face[0] + 1)
        rotated = reversed_manual[start:] + reversed_manual[:start]
        assert list(face[: etype.face_corners] + 1) == rotated


def test_c3d10_midside_nodes_follow_face_edges():
    etype = ELEMENT_TYPES["C3D10"]
    x = REFERENCE["C3D10"]
    for face in etype.faces:
        c = x[face[:3]]
        expected = [(c[0] + c[1]) / 2, (c[1] + c[2]) / 2, (c[2] + c[0]) / 2]
        np.testing.assert_allclose(x[face[3:]], expected)


def test_ccx_internal_face_start_nodes():
    # verified with ccx 2.20 .cel output: master C3D8 S2 is (5, 6, 7, 8), C3D4/C3D10 S1 (1, 3, 2)
    assert list(ELEMENT_TYPES["C3D8"].faces[1] + 1) == [5, 6, 7, 8]
    assert list(ELEMENT_TYPES["C3D8"].faces[0] + 1) == [4, 3, 2, 1]
    assert list(ELEMENT_TYPES["C3D4"].faces[0] + 1) == [1, 3, 2]
    assert list(ELEMENT_TYPES["C3D10"].faces[0] + 1) == [1, 3, 2, 7, 6, 5]


# ----------------------------------------------------------------------------- two cubes deck


def test_two_cubes_deck():
    deck = read_deck(DATA / "two_cubes.inp")
    assert deck.heading.startswith("Two C3D8 cubes")
    np.testing.assert_array_equal(deck.node_ids, [*range(1, 9), *range(11, 19)])
    np.testing.assert_allclose(deck.node_coords[deck.node_index([13])], [[0.75, 0.75, 1.0]])
    block = deck.elements["C3D8"]
    np.testing.assert_array_equal(block.ids, [1, 2])
    np.testing.assert_array_equal(block.connectivity[1], [11, 12, 13, 14, 15, 16, 17, 18])
    assert deck.num_elements == 2
    np.testing.assert_array_equal(face_nodes(deck, "MASTER"), [[5, 6, 7, 8]])
    np.testing.assert_array_equal(face_nodes(deck, "slave"), [[14, 13, 12, 11]])
    np.testing.assert_array_equal(surface_nodes(deck, "SLAVE"), [11, 12, 13, 14])
    assert deck.materials["STEEL"].elastic == (210000.0, 0.3)
    (pair,) = deck.contact_pairs
    assert (pair.slave, pair.master, pair.interaction, pair.small_sliding) == (
        "SLAVE", "MASTER", "SI", False
    )  # fmt: skip
    behavior = deck.interactions["SI"].behavior
    assert behavior.pressure_overclosure == "LINEAR"
    assert behavior.values == (1.0e7, 1.0, 1.0e-3)
    (step,) = deck.steps
    assert step.static.initial_increment == 0.5 and step.static.period == 1.0
    assert not step.nlgeom and step.max_increments == 100
    assert [(b.target, b.first_dof, b.last_dof, b.value) for b in step.boundaries] == [
        ("FIX", 1, 3, 0.0), ("TOP", 1, 2, 0.0), ("TOP", 3, 3, -0.001)
    ]  # fmt: skip
    np.testing.assert_array_equal(step.boundaries[2].nodes, [15, 16, 17, 18])
    assert [(p.kind, p.keys, p.set, p.totals) for p in step.prints] == [
        ("NODE", ("U", "RF"), "NALL", "NO"),
        ("NODE", ("RF",), "FIX", "YES"),
        ("EL", ("S",), "EALL", "NO"),
        ("CONTACT", ("CDIS", "CSTR", "CELS", "CNUM"), None, "NO"),
        ("CONTACT", ("CELS",), None, "ONLY"),
    ]
    assert step.contact_elements
    assert deck.ignored == ()


# ----------------------------------------------------------------------------- features deck


@pytest.fixture(scope="module")
def features():
    return read_deck(DATA / "features.inp")


def test_features_mesh_includes_and_continuations(features):
    deck = features
    assert deck.heading == "Feature deck for the parser tests\nsecond heading line"
    assert deck.node_ids.size == 12 + 10 + 4
    np.testing.assert_allclose(deck.node_coords[deck.node_index([2, 3, 4])],
                               [[1, 0, 0], [2, 0, 0], [0, 1, 0]])  # fmt: skip
    np.testing.assert_array_equal(deck.elements["C3D8"].connectivity[0], [1, 2, 5, 4, 7, 8, 11, 10])
    np.testing.assert_array_equal(deck.elements["C3D10"].connectivity[0], np.arange(101, 111))
    np.testing.assert_array_equal(deck.elements["C3D4"].ids, [11])
    assert deck.element_types([11, 1, 10]) == ["C3D4", "C3D8", "C3D10"]


def test_features_sets(features):
    nsets, elsets = features.nsets, features.elsets
    np.testing.assert_array_equal(nsets["BOTTOM"], [1, 2, 3, 4, 5, 6])
    np.testing.assert_array_equal(nsets["BOTH"], [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 1])
    np.testing.assert_array_equal(nsets["EVEN"], [2, 4, 6, 8, 10, 12])
    np.testing.assert_array_equal(elsets["LOWER"], [1, 2])
    np.testing.assert_array_equal(elsets["ALL"], [1, 2, 10, 11])
    assert "NALL" in nsets and nsets["NALL"].size == 26


def test_features_surfaces(features):
    deck = features
    np.testing.assert_array_equal(face_nodes(deck, "MASTER"), [[7, 8, 11, 10], [8, 9, 12, 11]])
    np.testing.assert_array_equal(face_nodes(deck, "SLAVEFACES"),
                                  [[101, 103, 102, 107, 106, 105]])  # fmt: skip
    snode = deck.surfaces["SNODE"]
    assert snode.type == "NODE"
    np.testing.assert_array_equal(snode.nodes, [7, 8, 9, 10, 11, 12, 201])
    with pytest.raises(ValueError, match="TYPE=NODE"):
        face_nodes(deck, "SNODE")
    with pytest.raises(ValueError, match="surface NOPE is not defined"):
        face_nodes(deck, "nope")


def test_features_materials_and_interactions(features):
    deck = features
    assert deck.materials["STEEL"].elastic == (210000.0, 0.3)
    assert deck.materials["STEEL"].extra == {"*DENSITY": ((7.8e-9,),), "*EXPANSION": ((1.2e-5,),)}
    assert deck.materials["SOFT"].elastic == (1000.0, 0.25)
    assert set(deck.materials["SOFT"].extra) == {"*CONDUCTIVITY", "*SPECIFIC HEAT"}
    assert [(s.elset, s.material) for s in deck.sections] == [("LOWER", "STEEL"), ("TETS", "SOFT")]
    exp = deck.interactions["EXP"]
    assert exp.behavior.values == (1e-3, 5.0)
    assert (exp.friction.mu, exp.friction.stick_slope) == (0.3, 1000.0)
    assert exp.extra == {}
    assert (exp.damping.coefficient, exp.damping.tangent_fraction) == (1e-3, 0.0)
    np.testing.assert_allclose(deck.interactions["TAB"].behavior.table,
                               [[0, 0], [10, 1e-3], [100, 2e-3]])  # fmt: skip
    assert deck.interactions["HARD"].behavior.pressure_overclosure == "HARD"
    assert deck.interactions["HARD"].behavior.values == ()
    assert deck.interactions["LIN"].behavior.values == (1e6, None, 1e-3)
    first, second = deck.contact_pairs
    assert (first.slave, first.master, first.adjust, first.small_sliding) == (
        "SLAVEFACES", "MASTER", 0.01, False
    )  # fmt: skip
    assert (second.interaction, second.adjust, second.small_sliding) == ("TAB", "BOTTOM", True)


def test_features_amplitudes_and_model_boundaries(features):
    deck = features
    ramp = deck.amplitudes["RAMP"]
    np.testing.assert_allclose(ramp.times, [0, 0.5, 1])
    np.testing.assert_allclose(ramp.values, [0, 1, 0.5])
    assert not ramp.total_time and deck.amplitudes["TOT"].total_time
    (fixed,) = deck.boundaries
    assert (fixed.first_dof, fixed.last_dof, fixed.value, fixed.op) == (1, 3, 0.0, "MOD")
    np.testing.assert_array_equal(fixed.nodes, [1, 2, 3, 4, 5, 6])


def test_features_step_one(features):
    step = features.steps[0]
    assert step.number == 1 and step.nlgeom and step.max_increments == 50
    assert step.static.initial_increment == 0.25 and step.static.direct
    assert (step.static.minimum, step.static.maximum) == (1e-5, 0.5)
    (bc,) = step.boundaries
    assert (bc.amplitude, bc.value, bc.op) == ("RAMP", -0.01, "MOD")
    assert step.cload_op == "NEW"
    assert [(c.target, c.dof, c.value) for c in step.cloads] == [("201", 3, -5.0), ("TOP", 1, 0.5)]
    assert [(d.face, d.value) for d in step.dloads] == [(2, 1.5), (1, 2.0)]
    np.testing.assert_array_equal(step.dloads[0].elements, [1, 2])
    assert step.controls == {"FIELD": ((1e-8, 1e-8, 0.01, None, 0.02, 1e-5, 1e-3, 1e-8),)}
    assert step.field_controls()["R_n"] == 1e-8 and step.field_controls()["q_u"] is None
    node, el, contact = step.prints
    assert (node.kind, node.keys, node.set, node.totals, node.frequency) == (
        "NODE", ("U", "RF"), "TOP", "YES", 2
    )  # fmt: skip
    assert (el.kind, el.keys, el.set) == ("EL", ("S",), "LOWER")
    assert (contact.keys, contact.totals) == (("CDIS", "CSTR", "CELS", "CNUM"), "ONLY")
    assert step.output_frequency == 3  # the last FREQUENCY wins, *OUTPUT included
    assert step.contact_elements
    assert [r.keyword for r in step.file_requests] == ["*NODE FILE", "*EL FILE"]


def test_features_step_two_carries_over(features):
    deck = features
    step = deck.steps[1]
    assert step.nlgeom  # NLGEOM stays on
    assert step.static.initial_increment == 1.0 and not step.static.direct
    assert step.boundary_op == "NEW"
    assert step.controls == {}  # *CONTROLS, RESET
    assert step.field_controls()["R_n"] == 0.005
    # node prints replaced; element and contact prints carried over, in ccx's order
    assert [(p.kind, p.set) for p in step.prints] == [("EL", "LOWER"), ("CONTACT", None),
                                                      ("NODE", "BOTTOM")]  # fmt: skip
    assert step.output_frequency == 3
    assert step.contact_elements  # file requests carried over
    (change,) = step.friction_changes
    friction = change.friction
    assert (change.interaction, friction.mu, friction.stick_slope) == ("EXP", 0.2, 500)
    (model,) = step.model_changes
    assert (model.action, model.slave, model.master) == ("REMOVE", "SNODE", "MASTER")
    kinds = [k for k, _, _ in deck.ignored]
    assert kinds == ["*OUTPUT", "*RESTART"]
    assert deck.ignored[0][1].endswith("features.inp")
    assert deck.ignored[0][2] == _line_of(DATA / "features.inp", "*OUTPUT, FIELD")
    np.testing.assert_array_equal(deck.time_points["TP"].times, [0.5, 1.0])


def test_node_surface_faces_rule_of_spec_2_1(tmp_path):
    deck = read_deck(DATA / "two_cubes.inp")
    faces = external_faces(deck)
    assert faces.shape == (12, 4)  # two separate cubes: every face is external
    # a nodal surface with one corner node collects the three faces of the upper cube at it
    text = _BASE.replace("*CONTACT PAIR", "*SURFACE, NAME=N1, TYPE=NODE\n11\n*CONTACT PAIR")
    (tmp_path / "nodal.inp").write_text(text)
    nodal = read_deck(tmp_path / "nodal.inp")
    got = node_surface_faces(nodal, "N1")
    assert got.shape == (3, 4) and np.all(np.any(got == 11, axis=1))
    np.testing.assert_array_equal(node_surface_faces(nodal, "SLAVE"), [[14, 13, 12, 11]])


def test_external_faces_skip_shared_face(tmp_path):
    # glue the cubes: the upper cube reuses the top nodes of the lower one
    glued = _BASE.replace("2, 11, 12, 13, 14, 15, 16, 17, 18", "2, 5, 6, 7, 8, 15, 16, 17, 18")
    (tmp_path / "glued.inp").write_text(glued)
    deck = read_deck(tmp_path / "glued.inp")
    faces = external_faces(deck)
    assert faces.shape == (10, 4)
    shared = {5, 6, 7, 8}
    assert not any(set(f) == shared for f in faces.tolist())


# ----------------------------------------------------------------------------- error paths

# (id, replacement (old, new) applied to two_cubes.inp, line marker of the expected error,
#  regex the message must contain)
BAD_DECKS = [
    ("element type", ("*ELEMENT, TYPE=C3D8, ELSET=EALL", "*ELEMENT, TYPE=C3D8R, ELSET=EALL"),
     "TYPE=C3D8R", r"element type C3D8R is not supported: its one-point integration"),
    ("equation", ("*MATERIAL, NAME=STEEL",
                  "*EQUATION\n2\n5,1,1.,6,1,-1.,7,1,1.\n*MATERIAL, NAME=STEEL"),
     "5,1,1.,6,1,-1.,7,1,1.\n", r"\*EQUATION: 2 terms \(node, dof, coefficient\) expected"),
    ("multistage tie", ("*STEP", "*TIE, NAME=T1, MULTISTAGE\nSLAVE, MASTER\n*STEP"), "*TIE",
     r"\*TIE, MULTISTAGE is not supported yet"),
    ("tie in a step", ("*STATIC\n0.5, 1.0", "*STATIC\n0.5, 1.0\n*TIE, NAME=T1\nSLAVE, MASTER"),
     "*TIE", r"\*TIE is a model definition keyword"),
    ("tie of an unknown surface", ("*STEP", "*TIE, NAME=T1\nSLAVE, MASTR\n*STEP"), "SLAVE, MASTR",
     r"surface MASTR is not defined"),
    ("cyclic symmetry without tie", ("*STEP", "*CYCLIC SYMMETRY MODEL, N=12\n0,0,0,0,0,1\n*STEP"),
     "*CYCLIC SYMMETRY MODEL", r"needs TIE=\.\.\. \(there are 0 \*TIE cards"),
    ("rigid body", ("*STEP", "*RIGID BODY, NSET=TOP, REF NODE=1\n*STEP"), "*RIGID BODY",
     r"\*RIGID BODY is not supported yet"),
    ("unknown keyword", ("*STEP", "*FOO BAR, X=1\n*STEP"), "*FOO BAR",
     r"unknown keyword \*FOO BAR"),
    ("unsupported keyword", ("*STATIC\n0.5, 1.0", "*BUCKLE\n2"), "*BUCKLE",
     r"\*BUCKLE is not supported yet"),
    ("explicit dynamics", ("*STATIC\n0.5, 1.0", "*DYNAMIC, EXPLICIT\n0.5, 1.0"), "*DYNAMIC",
     r"EXPLICIT is not supported yet"),
    ("dynamic alpha", ("*STATIC\n0.5, 1.0", "*DYNAMIC, ALPHA=-0.5\n0.5, 1.0"), "*DYNAMIC",
     r"ALPHA must be in \[-1/3, 0\]"),
    ("initial stress", ("*STEP", "*INITIAL CONDITIONS, TYPE=STRESS\n1, 1, 0, 0, 0, 0, 0, 0\n*STEP"),
     "*INITIAL CONDITIONS", r"not supported yet for TYPE=STRESS"),
    ("bad coordinate", ("3, 1.0, 1.0, 0.0", "3, 1.0, 1.x0, 0.0"), "3, 1.0, 1.x0",
     r"bad number '1\.X0'"),
    ("bad node number", ("12, 0.75, 0.25, 1.0", "12.5, 0.75, 0.25, 1.0"), "12.5, 0.75",
     r"bad node number '12\.5'"),
    ("unknown node in element",
     ("2, 11, 12, 13, 14, 15, 16, 17, 18", "2, 11, 12, 13, 14, 15, 16, 17, 99"),
     "2, 11, 12, 13, 14, 15, 16, 17, 99", r"node 99, which is not defined"),
    ("wrong node count", ("2, 11, 12, 13, 14, 15, 16, 17, 18", "2, 11, 12, 13, 14, 15, 16, 17"),
     "2, 11, 12, 13, 14, 15, 16, 17", r"element 2 has 7 nodes, C3D8 has 8"),
    ("unknown nset", ("FIX, 1, 3", "FIXX, 1, 3"), "FIXX, 1, 3", r"node set FIXX is not defined"),
    ("unknown element in surface", ("1, S2", "7, S2"), "7, S2", r"element 7, which is not defined"),
    ("bad face label", ("1, S2", "1, S9"), "1, S9", r"bad face label 'S9'"),
    ("missing interaction parameter", ("INTERACTION=SI, TYPE", "TYPE"), "*CONTACT PAIR",
     r"\*CONTACT PAIR needs the parameter INTERACTION"),
    ("surface to surface", ("TYPE=NODE TO SURFACE", "TYPE=SURFACE TO SURFACE"), "*CONTACT PAIR",
     r"TYPE=SURFACE TO SURFACE is not supported yet"),
    ("undefined master", ("SLAVE, MASTER", "SLAVE, MASTR"), "SLAVE, MASTR",
     r"master surface MASTR is not defined"),
    ("nodal master", ("SLAVE, MASTER", "SLAVE, NODES\n*SURFACE, NAME=NODES, TYPE=NODE\nTOP"),
     "SLAVE, NODES", r"master surface NODES must be made of element faces"),
    ("undefined interaction", ("*SURFACE INTERACTION, NAME=SI", "*SURFACE INTERACTION, NAME=SJ"),
     "SLAVE, MASTER", r"surface interaction SI is not defined"),
    ("orthotropic", ("*ELASTIC", "*ELASTIC, TYPE=ORTHO"), "*ELASTIC, TYPE=ORTHO",
     r"TYPE=ORTHO is not supported yet"),
    ("elastic outside material",
     ("*MATERIAL, NAME=STEEL\n",
      "*MATERIAL, NAME=STEEL\n*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL\n"),
     "*ELASTIC", r"\*ELASTIC must follow a \*MATERIAL card"),
    ("missing material", ("MATERIAL=STEEL", "MATERIAL=IRON"), "MATERIAL=IRON",
     r"material IRON is not defined"),
    ("dof", ("TOP, 1, 2", "TOP, 1, 5"), "TOP, 1, 5", r"degree of freedom 5 is not supported"),
    ("node print key", ("U, RF\n", "U, HFL\n"), "*NODE PRINT, NSET=NALL",
     r"\*NODE PRINT key HFL is not supported yet"),
    ("contact print key", ("CDIS, CSTR, CELS, CNUM", "CDIS, CF"), "*CONTACT PRINT\n",
     r"\*CONTACT PRINT key CF is not supported yet"),
    ("missing end step", ("*END STEP\n", ""), "*STEP", r"\*STEP without \*END STEP"),
    ("step keyword in model", ("*MATERIAL, NAME=STEEL", "*CLOAD\n1, 1, 1.\n*MATERIAL, NAME=STEEL"),
     "*CLOAD", r"\*CLOAD is a step keyword"),
    ("model keyword in step", ("*STATIC\n", "*NSET, NSET=X\n1\n*STATIC\n"), "*NSET, NSET=X",
     r"\*NSET is a model definition keyword"),
    ("dload label", ("*END STEP", "*DLOAD\n1, BX, 9.81\n*END STEP"), "1, BX",
     r"\*DLOAD, BX is not supported yet"),
    ("gravity line", ("*END STEP", "*DLOAD\n1, GRAV, 9.81, 0., -1.\n*END STEP"), "1, GRAV",
     r"GRAV data line: element or element set, GRAV, magnitude, x, y, z"),
    ("gravity direction", ("*END STEP", "*DLOAD\n1, GRAV, 9.81, 0., 0., 0.\n*END STEP"),
     "1, GRAV", r"GRAV: the direction is the zero vector"),
    ("dload face", ("*END STEP", "*DLOAD\nEALL, P7, 1.\n*END STEP"), "EALL, P7",
     r"\*DLOAD, P7 is not supported yet"),
    ("tied behavior", ("PRESSURE-OVERCLOSURE=LINEAR", "PRESSURE-OVERCLOSURE=TIED"),
     "PRESSURE-OVERCLOSURE=TIED", r"TIED is for face-to-face contact"),
    ("exponential data", ("1.0e7, 1.0, 1.0e-3", "1.0e7, 1.0, 1.0e-3\n*SURFACE INTERACTION, NAME=E\n"
                          "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=EXPONENTIAL\n-1., 2."),
     "-1., 2.", r"EXPONENTIAL needs c0 > 0"),
    ("friction", ("1.0e7, 1.0, 1.0e-3", "1.0e7, 1.0, 1.0e-3\n*FRICTION\n0., 100."), "0., 100.",
     r"friction coefficient > 0"),
    ("unknown parameter", ("*STEP", "*STEP, PERTURBATION"), "*STEP",
     r"parameter PERTURBATION of \*STEP is not supported"),
    ("time points", ("*CONTACT PRINT\n", "*CONTACT PRINT, TIME POINTS=T1\n"),
     "*CONTACT PRINT, TIME",
     r"time points T1 are not defined \(before this line\)"),
    ("time points order", ("*STEP\n", "*TIME POINTS, NAME=T1\n0.5, 0.2\n*STEP\n"),
     "*TIME POINTS", r"\*TIME POINTS must increase"),
    ("time points total", ("*STEP\n", "*TIME POINTS, NAME=T1, TIME=TOTAL TIME\n0.5\n*STEP\n"),
     "*TIME POINTS", r"TIME=TOTAL TIME is not supported yet"),
    ("duplicate node", ("12, 0.75, 0.25, 1.0", "12, 0.75, 0.25, 1.0\n11, 0., 0., 0."),
     "11, 0., 0., 0.",
     r"node 11 is defined twice"),
    ("no section", ("*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL", "*ELSET, ELSET=E1\n1\n"
                    "*SOLID SECTION, ELSET=E1, MATERIAL=STEEL"), "2, 11, 12, 13, 14",
     r"element 2 has no \*SOLID SECTION"),
    ("model change element", ("*END STEP", "*MODEL CHANGE, TYPE=ELEMENT, REMOVE\n2\n*END STEP"),
     "*MODEL CHANGE", r"TYPE=ELEMENT is not supported yet"),
    ("change friction without friction",
     ("*END STEP", "*CHANGE FRICTION, INTERACTION=SI\n*END STEP"),
     "*CHANGE FRICTION", r"\*CHANGE FRICTION without a following \*FRICTION"),
    ("amplitude", ("TOP, 3, 3, -0.001", "*BOUNDARY, AMPLITUDE=A9\nTOP, 3, 3, -0.001"),
     "AMPLITUDE=A9", r"amplitude A9 is not defined"),
    ("duplicate element", ("2, 11, 12, 13, 14, 15, 16, 17, 18",
                           "2, 11, 12, 13, 14, 15, 16, 17, 18\n1, 11, 12, 13, 14, 15, 16, 17, 18"),
     "1, 11, 12, 13, 14", r"element 1 is defined twice \(first at .*:\d+\)"),
    ("repeated node", ("1, 1, 2, 3, 4, 5, 6, 7, 8", "1, 1, 2, 3, 4, 5, 6, 7, 1"),
     "1, 1, 2, 3, 4, 5, 6, 7, 1", r"element 1 repeats a node"),
    ("unknown node in nset", ("*NSET, NSET=TOP\n15, 16, 17, 18", "*NSET, NSET=TOP\n15, 16, 17, 19"),
     "15, 16, 17, 19",
     r"\*NSET refers to node 19, which is not defined"),
    ("generate", ("*NSET, NSET=TOP", "*NSET, NSET=G, GENERATE\n8, 1\n*NSET, NSET=TOP"), "8, 1",
     r"GENERATE: need first <= last"),
]  # fmt: skip


@pytest.mark.parametrize("case", BAD_DECKS, ids=[c[0] for c in BAD_DECKS])
def test_bad_deck_errors_name_keyword_and_line(tmp_path, case):
    _, (old, new), marker, pattern = case
    assert old in _BASE, f"test case does not apply: {old!r}"
    path = tmp_path / "bad.inp"
    path.write_text(_BASE.replace(old, new, 1))
    with pytest.raises(DeckError) as info:
        read_deck(path)
    message = str(info.value)
    assert re.search(pattern, message), message
    expected_line = _line_of(path, marker.rstrip("\n")) if "\n" not in marker.rstrip("\n") else None
    if marker.endswith("\n"):  # marker is a whole line
        lines = path.read_text().splitlines()
        expected_line = lines.index(marker.rstrip("\n")) + 1
    assert message.startswith(f"{path}:{expected_line}: "), message
    assert info.value.location.line == expected_line


def test_error_in_included_file_names_that_file(tmp_path):
    (tmp_path / "mesh.inp").write_text("*NODE\n1, 0, 0, 0\n2, 1, 0, zero\n")
    (tmp_path / "main.inp").write_text("** main\n*INCLUDE, INPUT=mesh.inp\n")
    with pytest.raises(DeckError, match=r"mesh\.inp:3: bad number 'ZERO'"):
        read_deck(tmp_path / "main.inp")


def test_missing_include_file(tmp_path):
    (tmp_path / "main.inp").write_text("*HEADING\nx\n*INCLUDE, INPUT=nowhere.inp\n")
    with pytest.raises(DeckError, match=r"main\.inp:3: cannot read \*INCLUDE file .*nowhere\.inp"):
        read_deck(tmp_path / "main.inp")


def test_recursive_include(tmp_path):
    (tmp_path / "a.inp").write_text("*INCLUDE, INPUT=b.inp\n")
    (tmp_path / "b.inp").write_text("*INCLUDE, INPUT=a.inp\n")
    with pytest.raises(DeckError, match=r"b\.inp:1: \*INCLUDE of .*a\.inp is recursive"):
        read_deck(tmp_path / "a.inp")


def test_missing_deck(tmp_path):
    with pytest.raises(ValueError, match="cannot read deck"):
        read_deck(tmp_path / "none.inp")


def test_deck_error_is_value_error():
    assert issubclass(DeckError, ValueError)


def test_node_index_unknown_node():
    deck = read_deck(DATA / "two_cubes.inp")
    with pytest.raises(ValueError, match="node 9 is not defined"):
        deck.node_index([1, 9])
    with pytest.raises(ValueError, match="element 3 is not defined"):
        deck.element_location([3])


def _features_variant(tmp_path: Path, name: str, old: str, new: str) -> Path:
    """features.inp with ``old`` replaced by ``new``, written with its include files."""
    (tmp_path / "include").mkdir(exist_ok=True)
    for include in ("mesh.inp", "tets.inp"):
        (tmp_path / "include" / include).write_text((DATA / "include" / include).read_text())
    path = tmp_path / name
    path.write_text((DATA / "features.inp").read_text().replace(old, new))
    return path


def test_mixed_face_sizes_rejected(tmp_path):
    slave = "*Surface, name=Slave Faces\n10, s1"
    deck = read_deck(_features_variant(tmp_path, "mixed.inp", slave, slave + "\n1, S1"))
    with pytest.raises(ValueError, match=r"mixes faces with \[4, 6\] nodes"):
        face_nodes(deck, "SLAVEFACES")


def test_face_number_beyond_element_faces(tmp_path):
    path = _features_variant(tmp_path, "f.inp", "10, p1, 2.0", "10, P5, 2.0")
    with pytest.raises(DeckError) as info:
        read_deck(path)
    line = _line_of(tmp_path / "f.inp", "10, P5, 2.0")
    assert str(info.value) == (
        f"{tmp_path / 'f.inp'}:{line}: face 5 of element 10: C3D10 has faces 1..4"
    )
    path = _features_variant(tmp_path, "g.inp", "10, s1", "11, S6")
    with pytest.raises(DeckError, match=r"g\.inp:\d+: face 6 of element 11: C3D4 has faces 1\.\.4"):
        read_deck(path)


def test_calculix_file_formats_are_pure_python_numpy():
    """File formats, element table, ccx runner: no dolfinx (model, job, writer are the glue); of
    the package only its numpy kernels (the deck reader's wedges use kernels.collapsed_wedges)."""
    import ast

    import dolfinx_ntf.calculix as package

    here = Path(package.__file__).parent
    names = ["elements.py", "frd.py", "dat.py", "cel.py", "ccx.py", "compare.py"]
    for path in [here / name for name in names] + sorted((here / "deck").glob("*.py")):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            names = []
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0:
                names = [node.module or ""]
            for name in names:
                root = name.split(".")[0]
                pure_kernel = name.startswith("dolfinx_ntf.kernels.")  # numpy only (check_layers)
                assert pure_kernel or root not in (
                    "dolfinx",
                    "ufl",
                    "petsc4py",
                    "mpi4py",
                    "dolfinx_ntf",
                ), f"{path.name} imports {name}"


def test_contact_file_keys_read_as_ccx_reads_them(tmp_path, caplog):
    """ccx reads the first four characters of *CONTACT FILE keys, as of *CONTACT PRINT's: its
    own decks spell them CDISP and CSTRESS (cubespring), and the CONTACT block is written."""
    from dolfinx_ntf.calculix.job_files import check_requests

    text = (DATA / "two_cubes.inp").read_text()
    text = text.replace("*END STEP", "*CONTACT FILE\nCDISP,CSTRESS\n*END STEP")
    (tmp_path / "long_keys.inp").write_text(text)
    deck = read_deck(tmp_path / "long_keys.inp")
    (request,) = [r for r in deck.steps[0].file_requests if r.kind == "CONTACT"]
    assert request.keys == ("CDIS", "CSTR")
    with caplog.at_level("WARNING", logger="dolfinx_ntf"):
        check_requests(deck)
    assert "not written to the .frd" not in caplog.text


def test_empty_deck_file_is_named_empty(tmp_path):
    from dolfinx_ntf.calculix.job import run_job

    (tmp_path / "empty.inp").write_text("\n  \n")
    with pytest.raises(ValueError, match=r"empty\.inp: the deck file is empty"):
        run_job("empty", tmp_path, progress=False)
    (tmp_path / "nostep.inp").write_text("*HEADING\nno step here\n")
    with pytest.raises(ValueError, match=r"nostep\.inp: the deck has no \*STEP"):
        run_job("nostep", tmp_path, progress=False)


def _same(a: object, b: object) -> bool:
    """Equal values of the same types, arrays by dtype, shape and content."""
    if isinstance(a, np.ndarray):
        return a.dtype == b.dtype and a.shape == b.shape and np.array_equal(a, b)
    if dataclasses.is_dataclass(a):
        return type(a) is type(b) and all(
            _same(getattr(a, f.name), getattr(b, f.name)) for f in dataclasses.fields(a)
        )
    if isinstance(a, dict):
        return list(a) == list(b) and all(_same(a[k], b[k]) for k in a)
    if isinstance(a, (list, tuple)) and not hasattr(a, "_fields"):
        return type(a) is type(b) and len(a) == len(b) and all(map(_same, a, b))
    return type(a) is type(b) and a == b


def test_mesh_cards_read_card_wide_as_line_by_line(tmp_path, monkeypatch):
    """Plain *NODE and *ELEMENT cards are read card-wide; the deck is the line-by-line one.

    C3D20 elements span two lines; a D exponent, a blank field and an element split after its
    first node are not plain: their cards are read line by line.
    """
    nodes = "\n".join(f"{n}, {n % 3}., {n // 3 % 3}.0, {n // 9}" for n in range(1, 28))
    c3d20 = [1, 3, 9, 7, 19, 21, 27, 25, 2, 6, 8, 4, 20, 24, 26, 22, 10, 12, 18, 16]
    deck = (
        f"*NODE, NSET=ALL\n{nodes}\n*NODE\n28, 1.0D0, , 3.\n"
        f"*ELEMENT, TYPE=C3D20, ELSET=E1\n1, {', '.join(map(str, c3d20[:15]))},\n"
        f"{', '.join(map(str, c3d20[15:]))}\n"
        f"*ELEMENT, TYPE=C3D20, ELSET=E2\n2,\n{', '.join(map(str, c3d20))}\n"
        "*MATERIAL, NAME=STEEL\n*ELASTIC\n210000., 0.3\n*SOLID SECTION, ELSET=E1, MATERIAL=STEEL\n"
        "*SOLID SECTION, ELSET=E2, MATERIAL=STEEL\n*STEP\n*STATIC\n*END STEP\n"
    )
    path = tmp_path / "mesh.inp"
    path.write_text(deck)
    card_wide = read_deck(path)
    monkeypatch.setattr(mesh_cards, "_plain_nodes", lambda lines: None)
    monkeypatch.setattr(mesh_cards, "_plain_elements", lambda lines, needed: None)
    line_by_line = read_deck(path)
    assert card_wide.node_ids.size == 28 and card_wide.node_coords[-1].tolist() == [1.0, 0.0, 3.0]
    assert _same(card_wide, line_by_line)


_GRAVITY_DECK = """*NODE, NSET=NALL
1, 0., 0., 0.
2, 1., 0., 0.
3, 1., 1., 0.
4, 0., 1., 0.
5, 0., 0., 1.
6, 1., 0., 1.
7, 1., 1., 1.
8, 0., 1., 1.
*ELEMENT, TYPE=C3D8, ELSET=EALL
1, 1, 2, 3, 4, 5, 6, 7, 8
*MATERIAL, NAME=M
*ELASTIC
1000., 0.3
*DENSITY
2.
*SOLID SECTION, ELSET=EALL, MATERIAL=M
*TIME POINTS, NAME=T, GENERATE
0.0, 0.3, 0.1
*TIME POINTS, NAME=LIST
0.05, 0.25
*STEP
*DYNAMIC
0.03, 0.3
*DLOAD
EALL, GRAV, 9.81, 0., 3., -4.
*NODE PRINT, NSET=NALL, TIME POINTS=T
U
*END STEP
"""


def test_gravity_and_time_points_are_read(tmp_path):
    """GRAV lines keep magnitude and normed direction; GENERATE includes the end point."""
    path = tmp_path / "gravity.inp"
    path.write_text(_GRAVITY_DECK)
    deck = read_deck(path)
    np.testing.assert_allclose(deck.time_points["T"].times, [0.0, 0.1, 0.2, 0.3], atol=1e-15)
    np.testing.assert_array_equal(deck.time_points["LIST"].times, [0.05, 0.25])
    (step,) = deck.steps
    (gravity,) = step.gravity
    assert gravity.value == 9.81 and gravity.target == "EALL"
    np.testing.assert_allclose(gravity.direction, [0.0, 0.6, -0.8])
    np.testing.assert_array_equal(gravity.elements, [1])
    assert step.dloads == () and step.dload_op == "MOD"
    (request,) = step.node_prints
    assert request.time_points == "T"


def test_velocity_print_needs_a_dynamic_step(tmp_path):
    """``*NODE PRINT V`` is read; outside ``*DYNAMIC`` steps the runner refuses it at its line."""
    from dolfinx_ntf.calculix.job_files import check_requests

    text = (DATA / "two_cubes.inp").read_text()
    text = text.replace("*END STEP", "*NODE PRINT, NSET=NALL\nV\n*END STEP")
    (tmp_path / "velocities.inp").write_text(text)
    deck = read_deck(tmp_path / "velocities.inp")
    assert any(r.keys == ("V",) for r in deck.steps[0].prints)
    with pytest.raises(NotImplementedError, match=r"velocities.inp:\d+: \*NODE PRINT V"):
        check_requests(deck)
