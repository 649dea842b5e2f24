"""``*ORIENTATION`` on isotropic sections and ``*ELASTIC`` variants against CalculiX 2.20.

docs/method.md §41. Two skewed C3D8 on a clamped base under uneven nodal forces: with a
rectangular (turned, and turned again about a local axis) or cylindrical ``*ORIENTATION`` on the
section and the element outputs in global axes, ccx's ``.dat`` and ``.frd`` are those of the deck
without it, and ours too; ``*ELASTIC, TYPE=ISOTROPIC``; ``*ELASTIC`` tables with a temperature
column: the first line without temperatures, interpolated at one initial temperature, held beyond
the table; ``*DENSITY`` tables the same (the eigenvalues of a ``*FREQUENCY`` step). The
refusals (outputs in the orientation's axes, anisotropic and unknown types, temperatures that
vary) are tested without ccx.
"""

from __future__ import annotations

import shutil
from pathlib import Path

from mpi4py import MPI

import numpy as np
import pytest
from helpers.ccx_runs import largest_differences, run_ccx_and_ours

from dolfinx_ntf.calculix.dat import read_dat
from dolfinx_ntf.calculix.deck import DeckError, read_deck
from dolfinx_ntf.calculix.deck.materials import table_at_temperature
from dolfinx_ntf.calculix.frd import read_frd

needs_ccx = pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX ccx is not installed")

ELASTIC = "*ELASTIC\n210000., 0.3\n"
GLOBAL_PRINT = "*EL PRINT, ELSET=EALL, GLOBAL=YES\nS, E\n"

ORIENTATIONS = {
    "none": None,
    "rectangular": "*ORIENTATION, NAME=OR1, SYSTEM=RECTANGULAR\n0.8, 0.6, 0., -0.6, 0.8, 0.3\n",
    "turned": "*ORIENTATION, NAME=OR1\n0.8, 0.6, 0., -0.6, 0.8, 0.3\n3, 25.\n",
    "cylindrical": "*ORIENTATION, NAME=OR1, SYSTEM=CYLINDRICAL\n-1., -2., 0., -1., -2., 1.\n",
    "identity": (
        "*ORIENTATION, NAME=OR1, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR\n"
        "1., 0., 0., 0., 1., 0.\n"
    ),
}

TABLE = "*ELASTIC\n100000., 0.25, -100.\n210000., 0.3, 300.\n"


def block(
    orientation: str | None = None,
    elastic: str = ELASTIC,
    el_print: str = GLOBAL_PRINT,
    el_file: str = "*EL FILE\nS, E\n",
    model: str = "",
    nlgeom: bool = False,
) -> str:
    """Two skewed C3D8 (12 nodes), the base clamped, four uneven nodal forces on the top."""
    ids, nodes = {}, []
    for k in range(2):
        for j in range(2):
            for i in range(3):
                ids[i, j, k] = len(ids) + 1
                xyz = (i + 0.1 * j * k, j + 0.05 * i, k + 0.02 * i * j)
                nodes.append(f"{ids[i, j, k]}, " + ", ".join(f"{x:.17g}" for x in xyz))
    rows = []
    for e in range(2):
        corners = [(e, 0), (e + 1, 0), (e + 1, 1), (e, 1)]
        c = [ids[i, j, k] for k in range(2) for i, j in corners]
        rows.append(f"{e + 1}, " + ", ".join(map(str, c)))
    bottom = ", ".join(str(ids[i, j, 0]) for i in range(3) for j in range(2))
    section = "*SOLID SECTION, ELSET=EALL, MATERIAL=M1" + (
        ", ORIENTATION=OR1" if orientation else ""
    )
    return (
        "*HEADING\norientation and elastic variants\n*NODE, NSET=NALL\n"
        + "\n".join(nodes)
        + "\n*ELEMENT, TYPE=C3D8, ELSET=EALL\n"
        + "\n".join(rows)
        + f"\n*NSET, NSET=BOT\n{bottom}\n{model}{orientation or ''}*MATERIAL, NAME=M1\n{elastic}"
        + f"{section}\n*STEP{', NLGEOM' if nlgeom else ''}\n*STATIC\n*BOUNDARY\nBOT, 1, 3\n"
        + f"*CLOAD\n{ids[2, 1, 1]}, 1, 100.\n{ids[2, 0, 1]}, 2, -50.\n{ids[1, 1, 1]}, 3, 80.\n"
        + f"{ids[0, 0, 1]}, 1, -30.\n*NODE PRINT, NSET=NALL\nU, RF\n{el_print}"
        + f"*NODE FILE\nU\n{el_file}*END STEP\n"
    )


def _run(directory: Path, deck: str) -> tuple[Path, Path]:
    """``run_ccx_and_ours`` of job ``b`` in a new ``directory``."""
    directory.mkdir()
    return run_ccx_and_ours(directory, "b", deck)


def _frd_blocks(path: Path) -> dict[str, np.ndarray]:
    """The ``.frd`` blocks by name (increments stacked), less ccx's ``ERROR`` block (not
    written, method §13.2)."""
    blocks: dict[str, list[np.ndarray]] = {}
    for b in read_frd(path).blocks:  # every increment's, one after the other
        if b.name != "ERROR":
            blocks.setdefault(b.name, []).append(b.values)
    return {name: np.concatenate(values) for name, values in blocks.items()}


def _check_against(ccx_dir: Path, ntf_dir: Path, job: str) -> dict[str, float]:
    """Our ``.dat`` against ccx's (blocks, labels, times), worst difference per block."""
    return largest_differences(read_dat(ccx_dir / f"{job}.dat"), read_dat(ntf_dir / f"{job}.dat"))


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("nlgeom", [False, True])
@pytest.mark.parametrize("case", ["rectangular", "turned", "cylindrical", "identity"])
def test_orientation_of_isotropic_section_changes_nothing(
    tmp_path: Path, case: str, nlgeom: bool
) -> None:
    """ccx 2.20's files with the orientation equal its files without it (every byte after the
    ``.frd`` header), and ours equal ccx's: U, RF, S, E within 1e-9 of the largest value."""
    deck = block(ORIENTATIONS[case], nlgeom=nlgeom)
    ccx_dir, ntf_dir = _run(tmp_path / "with", deck)
    bare_dir, _ = _run(tmp_path / "without", block(nlgeom=nlgeom))
    assert (ccx_dir / "b.dat").read_text() == (bare_dir / "b.dat").read_text()
    theirs, bare = _frd_blocks(ccx_dir / "b.frd"), _frd_blocks(bare_dir / "b.frd")
    assert list(theirs) == list(bare) == ["DISP", "STRESS", "TOSTRAIN"]
    for name in theirs:
        np.testing.assert_array_equal(theirs[name], bare[name])
    worst = _check_against(ccx_dir, ntf_dir, "b")
    assert set(worst) == {"U", "RF", "S", "E"}
    tolerance = 1e-6 if nlgeom else 1e-9  # NLGEOM: both codes' last Newton residual
    for name, difference in worst.items():
        assert difference <= tolerance, (name, difference)
    ours = _frd_blocks(ntf_dir / "b.frd")
    for name in theirs:
        scale = np.abs(theirs[name]).max()
        assert np.abs(ours[name] - theirs[name]).max() <= 1e-5 * scale, name


PLASTIC = "*ELASTIC\n210000., 0.3\n*PLASTIC\n150., 0.\n1000., 0.1\n"
ALL_KEYS = "S, E, PEEQ, SDV, ENER, ME\n"


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("nlgeom", [False, True])
@pytest.mark.parametrize("case", ["turned", "cylindrical"])
def test_orientation_of_plastic_section_changes_nothing(
    tmp_path: Path, case: str, nlgeom: bool
) -> None:
    """A plastic section (isotropic hardening) past yield in 4 increments: ccx 2.20's ``.dat``
    (S, E, PEEQ, SDV, ENER, ME in global axes) and ``.frd`` with the orientation equal its files
    without it, and ours equal ccx's."""

    def deck(orientation: str | None) -> str:
        text = block(
            orientation,
            elastic=PLASTIC,
            el_print="*EL PRINT, ELSET=EALL, GLOBAL=YES\n" + ALL_KEYS,
            el_file="*EL FILE\nS, E, PE, SDV, ENER, ME\n",
            nlgeom=nlgeom,
        )
        return text.replace("*STATIC\n", "*STATIC\n0.25, 1.\n")

    ccx_dir, ntf_dir = _run(tmp_path / "with", deck(ORIENTATIONS[case]))
    bare_dir, _ = _run(tmp_path / "without", deck(None))
    assert (ccx_dir / "b.dat").read_text() == (bare_dir / "b.dat").read_text()
    theirs, bare = _frd_blocks(ccx_dir / "b.frd"), _frd_blocks(bare_dir / "b.frd")
    assert set(theirs) == {"DISP", "STRESS", "TOSTRAIN", "MESTRAIN", "PE", "ENER", "SDV"}
    for name in theirs:
        np.testing.assert_array_equal(theirs[name], bare[name])
    ccx_peeq = [b for b in read_dat(ccx_dir / "b.dat") if b.name == "PEEQ"]
    assert np.abs(ccx_peeq[-1].values).max() > 1e-3  # yielded
    worst = _check_against(ccx_dir, ntf_dir, "b")
    assert set(worst) == {"U", "RF", "S", "E", "PEEQ", "SDV", "ENER", "ME"}
    for name, difference in worst.items():
        assert difference <= 1e-5, (name, difference)


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
def test_scalar_outputs_in_local_axes(tmp_path: Path) -> None:
    """PEEQ, ENER and SDV requested in the orientation's axes (``*EL PRINT`` without GLOBAL,
    ``*EL FILE, GLOBAL=NO``): ccx 2.20 writes them as without the orientation, SDV's plastic
    strain in global axes too (measured), and the runner takes them: ours equal ccx's."""

    def deck(orientation: str | None) -> str:
        text = block(
            orientation,
            elastic=PLASTIC,
            el_print="*EL PRINT, ELSET=EALL\nPEEQ, ENER, SDV\n",
            el_file="*EL FILE, GLOBAL=NO\nPE, ENER, SDV\n",
        )
        return text.replace("*STATIC\n", "*STATIC\n0.25, 1.\n")

    ccx_dir, ntf_dir = _run(tmp_path / "with", deck(ORIENTATIONS["rectangular"]))
    bare_dir, _ = _run(tmp_path / "without", deck(None))
    assert (ccx_dir / "b.dat").read_text() == (bare_dir / "b.dat").read_text()
    theirs, bare = _frd_blocks(ccx_dir / "b.frd"), _frd_blocks(bare_dir / "b.frd")
    for name in theirs:
        np.testing.assert_array_equal(theirs[name], bare[name])
    worst = _check_against(ccx_dir, ntf_dir, "b")
    assert set(worst) == {"U", "RF", "PEEQ", "ENER", "SDV"}
    for name, difference in worst.items():
        assert difference <= 1e-5, (name, difference)
    ours = _frd_blocks(ntf_dir / "b.frd")
    assert set(ours) == set(theirs) == {"DISP", "PE", "ENER", "SDV"}
    for name in theirs:
        scale = np.abs(theirs[name]).max()
        assert np.abs(ours[name] - theirs[name]).max() <= 1e-5 * scale, name


#: c3d15.inp's material and orientation cards on the C3D8 block (method §34.3, §41).
C3D15_CARDS = (
    "*ELASTIC, TYPE=ISOTROPIC\n 29000000.,      0.32,       70.\n"
    "*EXPANSION, TYPE=ISO\n    6.6E-6,       70.\n*DENSITY\n0.00073315\n"
)


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("case", ["identity", "turned"])
def test_c3d15_cards_on_c3d8(tmp_path: Path, case: str) -> None:
    """``c3d15.inp``'s cards (an orientation, ``TYPE=ISOTROPIC``, temperature columns) on the two
    C3D8: ccx's ``.dat`` is that of plain ``E, nu`` without the orientation, ours is ccx's, and
    the section keeps its orientation's name."""
    ccx_dir, ntf_dir = _run(tmp_path / "cards", block(ORIENTATIONS[case], elastic=C3D15_CARDS))
    plain = block(elastic="*ELASTIC\n29000000., 0.32\n")
    plain_dir, _ = _run(tmp_path / "plain", plain)
    assert (ccx_dir / "b.dat").read_text() == (plain_dir / "b.dat").read_text()
    for name, difference in _check_against(ccx_dir, ntf_dir, "b").items():
        assert difference <= 1e-9, (name, difference)
    deck = read_deck(ntf_dir / "b.inp")
    assert [section.orientation for section in deck.sections] == ["OR1"]
    assert deck.materials["M1"].elastic == (29000000.0, 0.32)


@pytest.mark.mpi
@pytest.mark.ccx
@needs_ccx
def test_orientation_on_processes(tmp_path: Path) -> None:
    """The turned orientation on any number of processes: ccx's ``.dat`` digits."""
    ccx_dir, ntf_dir = run_ccx_and_ours(
        tmp_path, "b", block(ORIENTATIONS["turned"]), comm=MPI.COMM_WORLD
    )
    if MPI.COMM_WORLD.rank == 0:
        for name, difference in _check_against(ccx_dir, ntf_dir, "b").items():
            assert difference <= 1e-9, (name, difference)


ELASTIC_CASES = {
    # case: (elastic card, model cards, (E, nu) it equals in ccx)
    "isotropic": ("*ELASTIC, TYPE=ISOTROPIC\n210000., 0.3\n", "", (210000.0, 0.3)),
    "one-line": ("*ELASTIC\n210000., 0.3, 70.\n", "", (210000.0, 0.3)),
    "one-line-hot": (
        "*ELASTIC\n210000., 0.3, 70.\n",
        "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 185.\n",
        (210000.0, 0.3),
    ),
    "no-temperature": (TABLE, "", (100000.0, 0.25)),
    "between": (
        TABLE + "150000., 0.2, 400.\n",
        "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 350.\n",
        (180000.0, 0.25),
    ),
    "at-zero": (TABLE, "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 0.\n", (127500.0, 0.2625)),
    "above": (TABLE, "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 500.\n", (210000.0, 0.3)),
    "below": (TABLE, "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, -500.\n", (100000.0, 0.25)),
}


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("case", list(ELASTIC_CASES))
def test_elastic_variants_against_ccx(tmp_path: Path, case: str) -> None:
    """Each ``*ELASTIC`` variant gives ccx's ``.dat`` of the plain ``(E, nu)`` it stands for
    (ccx's own file, every byte), and ours is ccx's to 1e-9 of the largest value."""
    elastic, model, (young, nu) = ELASTIC_CASES[case]
    ccx_dir, ntf_dir = _run(tmp_path / "table", block(elastic=elastic, model=model))
    plain = block(elastic=f"*ELASTIC\n{young!r}, {nu!r}\n", model=model)
    plain_dir, _ = _run(tmp_path / "plain", plain)
    assert (ccx_dir / "b.dat").read_text() == (plain_dir / "b.dat").read_text()
    for name, difference in _check_against(ccx_dir, ntf_dir, "b").items():
        assert difference <= 1e-9, (name, difference)
    assert read_deck(ntf_dir / "b.inp").materials["M1"].elastic == pytest.approx((young, nu))


def test_table_at_temperature() -> None:
    """Each value linear between lines, the end lines' values beyond the table."""
    rows = ((100.0, 0.2, 0.0), (200.0, 0.3, 10.0), (300.0, 0.1, 20.0))
    assert table_at_temperature(rows, 5.0) == pytest.approx((150.0, 0.25))
    assert table_at_temperature(rows, 15.0) == pytest.approx((250.0, 0.2))
    assert table_at_temperature(rows, -5.0) == (100.0, 0.2)
    assert table_at_temperature(rows, 25.0) == (300.0, 0.1)
    assert table_at_temperature(((1.0, 0.0), (3.0, 1.0)), 0.25) == (1.5,)


def _frequency_block(density: str, model: str = "") -> str:
    """The two C3D8 with ``density`` in a ``*FREQUENCY`` step of 3 modes."""
    text = block(elastic="*ELASTIC\n210000., 0.3\n" + density, model=model)
    return text[: text.index("*STEP")] + "*STEP\n*FREQUENCY\n3\n*BOUNDARY\nBOT, 1, 3\n*END STEP\n"


def _eigenvalues(path: Path) -> np.ndarray:
    """The eigenvalues of a ``.dat``'s ``E I G E N V A L U E   O U T P U T`` table."""
    lines = path.read_text().split("E I G E N V A L U E   O U T P U T")[1].splitlines()
    values = []
    for line in lines:
        fields = line.split()
        if len(fields) == 5 and fields[0].isdigit():
            values.append(float(fields[1]))
        elif values:
            break
    return np.array(values)


DENSITY_TABLE = "*DENSITY\n7.8e-9, -100.\n3.9e-9, 100.\n"
DENSITY_CASES = {
    # case: (model cards, the density ccx's eigenvalues are those of)
    "no-temperature": ("", 7.8e-9),  # the first line, not the table at 0
    "between": ("*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 0.\n", 5.85e-9),
    "above": ("*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 500.\n", 3.9e-9),
}


@pytest.mark.serial
@pytest.mark.ccx
@needs_ccx
@pytest.mark.parametrize("case", list(DENSITY_CASES))
def test_density_table_against_ccx(tmp_path: Path, case: str) -> None:
    """A ``*DENSITY`` table follows the ``*ELASTIC`` rule: ccx's eigenvalue output equals that of
    the plain density it stands for (every byte), and ours is ccx's to 1e-9."""
    model, density = DENSITY_CASES[case]
    ccx_dir, ntf_dir = _run(tmp_path / "table", _frequency_block(DENSITY_TABLE, model))
    plain_dir, _ = _run(tmp_path / "plain", _frequency_block(f"*DENSITY\n{density!r}\n", model))
    assert (ccx_dir / "b.dat").read_text() == (plain_dir / "b.dat").read_text()
    theirs, ours = _eigenvalues(ccx_dir / "b.dat"), _eigenvalues(ntf_dir / "b.dat")
    assert theirs.size == 3
    np.testing.assert_allclose(ours, theirs, rtol=1e-6)  # 7 printed digits
    deck = read_deck(ntf_dir / "b.inp")
    assert deck.materials["M1"].extra["*DENSITY"] == ((pytest.approx(density),),)


REFUSED = {
    "print-local": (
        block(ORIENTATIONS["rectangular"], el_print="*EL PRINT, ELSET=EALL\nS, PEEQ\n"),
        "*EL PRINT S with GLOBAL=NO (the default of *EL PRINT)",
    ),
    "file-local": (
        block(ORIENTATIONS["rectangular"], el_file="*EL FILE, GLOBAL=NO\nENER, E, ME\n"),
        "*EL FILE E, ME with GLOBAL=NO over elements",
    ),
    "undefined": (
        block(ORIENTATIONS["rectangular"]).replace("ORIENTATION=OR1", "ORIENTATION=OR2"),
        "orientation OR2 is not defined",
    ),
    "degenerate": (
        block("*ORIENTATION, NAME=OR1\n1., 0., 0., 2., 0., 0.\n"),
        "point b not on the axis",
    ),
    "distribution": (block("*ORIENTATION, NAME=OR1\nDIST1\n"), "*DISTRIBUTION names"),
    "ortho": (
        block(elastic="*ELASTIC, TYPE=ORTHOTROPIC\n1., 1., 1., 1., 1., 1., 1., 1.\n1.\n"),
        "TYPE=ORTHOTROPIC is not supported yet",
    ),
    "engineering": (
        block(elastic="*ELASTIC, TYPE=ENGINEERING CONSTANTS\n1., 1., 1., .3, .3, .3, 1., 1.\n1.\n"),
        "TYPE=ENGINEERINGCONSTANTS is not supported yet",
    ),
    "unknown": (block(elastic="*ELASTIC, TYPE=FOO\n1., 0.3\n"), "TYPE=FOO: ISO (ISOTROPIC)"),
    "no-temperature-column": (
        block(elastic="*ELASTIC\n1., 0.3\n2., 0.3\n"),
        "needs a temperature on each line",
    ),
    "decreasing": (
        block(elastic="*ELASTIC\n1., 0.3, 10.\n2., 0.3, 5.\n"),
        "the temperatures must increase",
    ),
    "varying": (
        block(
            elastic=TABLE,
            model="*INITIAL CONDITIONS, TYPE=TEMPERATURE\n1, 20.\nNALL, 30.\n",
        ),
        "needs one initial temperature at every node",
    ),
    "partial": (
        block(elastic=TABLE, model="*INITIAL CONDITIONS, TYPE=TEMPERATURE\n1, 20.\n"),
        "needs one initial temperature at every node",
    ),
    "changing": (
        block(elastic=TABLE).replace("*CLOAD", "*TEMPERATURE\nNALL, 50.\n*CLOAD"),
        "in a deck whose temperatures change",
    ),
    "density-varying": (
        _frequency_block(
            "*DENSITY\n1., 0.\n2., 300.\n",
            "*INITIAL CONDITIONS, TYPE=TEMPERATURE\n1, 20.\nNALL, 30.\n",
        ),
        "*DENSITY of material M1 (several data lines) needs one initial temperature",
    ),
    "conductivity-coupled": (
        block(elastic=ELASTIC + "*CONDUCTIVITY\n50., 0.\n60., 300.\n").replace(
            "*STATIC\n", "*COUPLED TEMPERATURE-DISPLACEMENT, STEADY STATE\n1., 1.\n"
        ),
        "temperature-dependent *CONDUCTIVITY of material M1 (several data lines) in a deck "
        "whose temperatures change",
    ),
}


@pytest.mark.serial
@pytest.mark.parametrize("case", list(REFUSED))
def test_refused(tmp_path: Path, case: str) -> None:
    """What would change the outputs or cannot be read is refused with the deck line."""
    text, message = REFUSED[case]
    (tmp_path / "b.inp").write_text(text)
    with pytest.raises(DeckError, match=r"b\.inp:\d+") as error:
        read_deck(tmp_path / "b.inp")
    assert message in str(error.value)
    line = int(str(error.value).split("b.inp:")[1].split(":")[0])
    card = text.splitlines()[line - 1]
    data_lines = {
        "varying": "210000., 0.3, 300.",  # the table's second line
        "density-varying": "2., 300.",
        "conductivity-coupled": "60., 300.",
        "partial": "210000., 0.3, 300.",
        "changing": "210000., 0.3, 300.",
        "degenerate": "1., 0., 0., 2., 0., 0.",
        "distribution": "DIST1",
        "no-temperature-column": "1., 0.3",
        "decreasing": "2., 0.3, 5.",
    }
    if case in data_lines:
        assert card == data_lines[case]
    else:
        assert card.startswith("*")
