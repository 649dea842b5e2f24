"""The reader's leniency (dolfinx_ntf.calculix.deck.LENIENCY) and ccx's own test decks."""

from __future__ import annotations

import gzip
import re
import shutil
from pathlib import Path

import pytest

from dolfinx_ntf.calculix.deck import LENIENCY, DeckError, read_deck

DATA = Path(__file__).parents[1] / "data" / "calculix"
_BASE = (DATA / "two_cubes.inp").read_text()
CCX_TESTS = Path("/usr/share/doc/calculix-ccx-test/examples/test")

# Where each keyword of LENIENCY goes in two_cubes.inp: (text to replace, replacement); "{p}" is
# ", PARAMETER=..." (empty for the whole keyword). The new card is on the first line of "{p}".
_PLACES = {
    "*HEADING": ("*HEADING\n", "*HEADING{p}\n"),
    "*NSET": ("*NSET, NSET=FIX\n", "*NSET, NSET=FIX{p}\n"),
    "*ELSET": ("*MATERIAL,", "*ELSET, ELSET=E1{p}\n1\n*MATERIAL,"),
    "*NODE FILE": ("*NODE FILE, CONTACT ELEMENTS", "*NODE FILE, CONTACT ELEMENTS{p}"),
    "*EL FILE": ("*END STEP", "*EL FILE{p}\nS\n*END STEP"),
    "*CONTACT FILE": ("*END STEP", "*CONTACT FILE{p}\nCDIS\n*END STEP"),
    "*NODE OUTPUT": ("*END STEP", "*NODE OUTPUT{p}\nU\n*END STEP"),
    "*ELEMENT OUTPUT": ("*END STEP", "*ELEMENT OUTPUT{p}\nS\n*END STEP"),
    "*CONTACT OUTPUT": ("*END STEP", "*CONTACT OUTPUT{p}\nCDIS\n*END STEP"),
    "*NODE PRINT": ("*NODE PRINT, NSET=NALL\n", "*NODE PRINT, NSET=NALL{p}\n"),
    "*EL PRINT": ("*EL PRINT, ELSET=EALL\n", "*EL PRINT, ELSET=EALL{p}\n"),
    "*CONTACT PRINT": ("*CONTACT PRINT\n", "*CONTACT PRINT{p}\n"),
    "*OUTPUT": ("*END STEP", "*OUTPUT, FIELD{p}\n*END STEP"),
    "*FACE PRINT": ("*END STEP", "*FACE PRINT{p}\nS1\n*END STEP"),
    "*SECTION PRINT": ("*END STEP", "*SECTION PRINT, NAME=SP1{p}\nSOF\n*END STEP"),
    "*TIME POINTS": ("*STEP\n", "*TIME POINTS, NAME=T1{p}\n0.5, 1.0\n*STEP\n"),
    "*PREPRINT": ("*STEP\n", "*PREPRINT, ECHO=NO{p}\n*STEP\n"),
    "*RESTART": ("*END STEP", "*RESTART, WRITE{p}\n*END STEP"),
    "*SOLID SECTION": ("MATERIAL=STEEL\n", "MATERIAL=STEEL{p}\n"),
    "*BOUNDARY": ("*BOUNDARY\n", "*BOUNDARY{p}\n"),
    "*STEP": ("*STEP\n", "*STEP{p}\n"),
}

_RULES = [
    (keyword, parameter, action)
    for keyword, rules in LENIENCY.items()
    for parameter, (action, _) in rules.items()
]


def _deck_with(tmp_path: Path, keyword: str, parameter: str) -> tuple[Path, int]:
    """two_cubes.inp with ``keyword`` carrying ``parameter``; returns the path and card line."""
    assert keyword in _PLACES, f"add a place for {keyword} to _PLACES"
    old, new = _PLACES[keyword]
    written = {"": "", "*": ", FOO=1"}.get(parameter, f", {parameter}=X1")
    text = _BASE.replace(old, new.format(p=written), 1)
    assert text != _BASE
    path = tmp_path / "lenient.inp"
    path.write_text(text)
    head = new.split("{p}")[0].rsplit("\n", 1)[-1]
    line = text[: text.index(head + written)].count("\n") + 1
    return path, line


@pytest.mark.parametrize(
    "rule", [r for r in _RULES if r[2] == "warn"], ids=lambda r: f"{r[0]} {r[1] or '(keyword)'}"
)
def test_warned_keyword_or_parameter_gives_one_warning_and_the_parse_goes_on(tmp_path, rule):
    keyword, parameter, _ = rule
    path, line = _deck_with(tmp_path, keyword, parameter)
    deck = read_deck(path)
    reference = read_deck(DATA / "two_cubes.inp")
    assert len(deck.warnings) == 1, [str(w) for w in deck.warnings]
    (warning,) = deck.warnings
    assert warning.keyword == keyword
    assert (warning.location.file, warning.location.line) == (str(path), line)
    text = str(warning)
    assert text.startswith(f" *WARNING reading {keyword}: ")
    assert text.endswith(f" at {path}:{line}")
    if parameter:
        written = "FOO=1" if parameter == "*" else f"{parameter}=X1"
        assert warning.parameter == written and f"parameter {written} ignored" in text
    else:
        assert warning.parameter is None and (keyword, str(path), line) in deck.ignored
    assert len(deck.steps) == len(reference.steps) == 1
    assert deck.node_ids.tolist() == reference.node_ids.tolist()
    assert [p.keys for p in deck.steps[0].prints] == [p.keys for p in reference.steps[0].prints]


@pytest.mark.parametrize(
    "rule", [r for r in _RULES if r[2] == "refuse"], ids=lambda r: f"{r[0]} {r[1]}"
)
def test_refused_parameter_names_keyword_parameter_and_line(tmp_path, rule):
    keyword, parameter, _ = rule
    path, line = _deck_with(tmp_path, keyword, parameter)
    with pytest.raises(DeckError) as info:
        read_deck(path)
    message = str(info.value)
    assert message.startswith(f"{path}:{line}: {keyword}, {parameter} is not supported yet ("), (
        message
    )


def test_every_table_action_is_warn_or_refuse():
    assert {action for _, _, action in _RULES} == {"warn", "refuse"}
    assert all(reason for rules in LENIENCY.values() for _, reason in rules.values())


def test_parameters_not_in_the_table_are_still_refused(tmp_path):
    path = tmp_path / "bad.inp"
    path.write_text(_BASE.replace("*NSET, NSET=FIX", "*NSET, NSET=FIX, FOO=1", 1))
    with pytest.raises(DeckError, match=r"parameter FOO of \*NSET is not supported"):
        read_deck(path)


# ----------------------------------------------------------------------------- ccx's test decks

# What may stop one of ccx's decks: an element type or a keyword with a mechanical meaning.
_MECHANICAL_REFUSAL = re.compile(
    r"^(element type (?P<element>\S+) is not supported"
    r"|(?P<keyword>\*[A-Z][A-Z -]*?)(, (?P<parameter>[A-Z ]+))? is not supported yet)"
)
_WARNED_KEYWORDS = {k for k, rules in LENIENCY.items() if rules.get("", ("",))[0] == "warn"}


def _node_to_surface_decks(directory: Path) -> list[Path]:
    decks = []
    for source in sorted(CCX_TESTS.glob("*.inp*")):
        opener = gzip.open if source.suffix == ".gz" else open
        with opener(source, "rt", encoding="latin-1") as stream:
            text = stream.read()
        if not re.search(r"TYPE\s*=\s*NODE\s*TO\s*SURFACE", text, re.IGNORECASE):
            continue
        target = directory / source.name.removesuffix(".gz")
        if source.suffix == ".gz":
            target.write_text(text, encoding="latin-1")
        else:
            shutil.copyfile(source, target)
        decks.append(target)
    return decks


@pytest.mark.skipif(not CCX_TESTS.is_dir(), reason="needs the package calculix-ccx-test")
def test_ccx_node_to_surface_decks_parse_or_name_a_mechanical_feature(tmp_path):
    decks = _node_to_surface_decks(tmp_path)
    assert len(decks) >= 17
    table = {}
    for path in decks:
        try:
            read_deck(path)
        except DeckError as error:
            message = str(error)
            assert message.startswith(f"{path}:"), message
            reason = message.split(": ", 1)[1]
            match = _MECHANICAL_REFUSAL.match(reason)
            assert match, f"{path.name}: not a mechanical refusal: {reason}"
            assert match["keyword"] not in _WARNED_KEYWORDS, reason
            table[path.stem] = reason
        else:
            table[path.stem] = "parses"
    print("\nccx test deck -> first refusal")
    for name, reason in table.items():
        print(f"  {name:14s} {reason}")
    assert {"cubespring", "friction1", "friction2"} <= {
        k for k, v in table.items() if v == "parses"
    }


@pytest.mark.skipif(not CCX_TESTS.is_dir(), reason="needs the package calculix-ccx-test")
def test_ccx_friction_decks_build(tmp_path):
    """ccx's frictional decks parse and build (friction and *CHANGE FRICTION are supported).

    ``tests/calculix/test_ccx_friction.py`` runs them against ccx.
    """
    from mpi4py import MPI

    from dolfinx_ntf.calculix.model import build_model

    decks = {p.stem: p for p in _node_to_surface_decks(tmp_path)}
    for name in ("friction1", "friction2"):
        model = build_model(read_deck(decks[name]), MPI.COMM_SELF)
        friction = model.pairs[0].interaction.friction
        assert friction is not None and friction.mu == pytest.approx(0.2)
    steps = read_deck(decks["friction2"]).steps
    assert [len(s.friction_changes) for s in steps] == [0, 0, 0, 1]
