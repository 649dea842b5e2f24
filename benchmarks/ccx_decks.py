"""CalculiX decks of the ccx benchmark (``benchmarks/vs_ccx.py``), written by ``write_inp``.

Each deck is built as a dolfinx problem (mesh, tags, contact pair, constraints, step: a
:class:`DeckModel`), so that a Python-API twin can reuse the same objects, and exported with
:func:`dolfinx_ntf.calculix.write_inp`. Units: mm, N, MPa.

- **Flat punch on hexahedra** (:func:`punch_model`): a 40 x 40 x 30 steel punch centred on a
  100 x 100 x 50 aluminium block, both structured (``cases.blocks`` of the cross-validation decks),
  touching at z = 0. The punch grid is finer than the block's and placed so that the slave nodes on
  every fifth punch grid line (x, y = 30, 50, 70 and more, see :data:`PUNCH_SIZES`) lie exactly
  above master nodes or edges: the ties of the pairing; the deck is symmetric about x = 50 and
  y = 50, so the ties persist under load. The block bottom is clamped; the punch top is held in x
  and y and pushed down by :data:`PUNCH_INDENTATION` in one increment. LINEAR law K = 1e7,
  sigma_inf = 3.
    - ``tie_punch``: the 6 x 6 punch (49 slave nodes) on a 10 x 10 block, with ``*CONTROLS,
      PARAMETERS=FIELD`` R_n = C_n = 1e-9.
    - ``punch_10``, ``punch_20``, ``punch_30``: the same punch with 10, 20 and 30 divisions (about
      5k, 29k and 81k dofs) and ccx's default controls. With R_n = C_n = 1e-9 ccx 2.20 stops on
      ``tie_punch``, ``punch_10`` and ``punch_20`` ("solution seems to diverge"): its own
      re-pairings move slave nodes above master vertices between diagonally opposite faces at
      every iteration, and its residual stalls (at 1.5e-6 of the average force on ``tie_punch``,
      1.4e-7 on ``punch_20``).
- **Fixed-increment quarter sphere** (:func:`quarter_sphere_model`): the lower half of a steel
  sphere of radius 10 (C3D4, ``dolfinx_ntf.meshes.hertz``: size 0.15 within 2.5 of the pole) on a
  steel block, its flat top pushed down by 0.12 in 4 fixed increments of 0.25 (``*STATIC, DIRECT``),
  LINEAR law K = 1e7, sigma_inf = 3, ccx's default controls. ccx 2.20 converges every increment;
  dolfinx_ntf at 926a3d5 diverges in increment 2 (the spring count runs away). The coarse version
  (size 0.3 at the pole, pushed down 0.14, about 4.5k dofs) runs in seconds and fails the same way
  (in increment 3), ccx converging. Whether either code converges here depends on the mesh
  itself: gmsh 4.13 (Debian 13) meshes the same sizes differently, and on its mesh ccx fails and
  dolfinx_ntf converges at 0.12 (and both converge at 0.11, both fail at 0.125). The decks
  therefore read meshes made once with gmsh 4.8 and kept in ``meshes/``
  (:func:`pin_sphere_mesh`; ``pinned=False`` meshes with this machine's gmsh).
- **Cross-validation decks**: ``tests/data/calculix/crossval/cases.py`` as they are.

Every deck prints U of all nodes and CDIS, CSTR, CELS per increment, so that both codes' results
can be compared with :mod:`dolfinx_ntf.calculix.compare`; the punch decks also ask for the
``.cel`` contact element sets, which ``vs_ccx.py`` compares pairing by pairing. Serial
(``MPI.COMM_SELF``).
"""

from __future__ import annotations

import argparse
import sys
import typing
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path

from mpi4py import MPI

import numpy as np

import dolfinx.fem
import dolfinx.mesh

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.calculix.writer import BoundarySpec, OutputSpec, StepSpec, write_inp
from dolfinx_ntf.meshes import hertz
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "data" / "calculix" / "crossval"))
import cases  # noqa: E402

__all__ = [
    "DECKS",
    "PUNCH_SIZES",
    "QUARTER_SPHERE",
    "QUARTER_SPHERE_COARSE",
    "TIE_PUNCH",
    "BenchDeck",
    "DeckModel",
    "PunchSpec",
    "SphereSpec",
    "pin_sphere_mesh",
    "punch_model",
    "quarter_sphere_model",
    "select_decks",
    "sphere_facet_tags",
    "write_model",
]

#: LINEAR law of the punch and sphere decks: K = 1e7, sigma_inf = 3 (ccx's defaults for E = 2e5).
LAW = ntf.LinearLaw(slope=1e7, tension=3.0)
#: ``*CONTROLS, PARAMETERS=FIELD`` of the tie punch.
TIE_CONTROLS: dict[str, float] = {"R_n": 1e-9, "C_n": 1e-9}
STEEL, ALUMINIUM = (210_000.0, 0.3), (70_000.0, 0.33)

BLOCK_BOX = ((0.0, 0.0, -50.0), (100.0, 100.0, 50.0))
PUNCH_BOX = ((30.0, 30.0, 0.0), (40.0, 40.0, 30.0))
#: Downward displacement of the punch top [mm].
PUNCH_INDENTATION = 0.03

_OUTPUT = OutputSpec(node_print=("U",), contact_print=("CDIS", "CSTR", "CELS"))


@dataclass(frozen=True)
class DeckModel:
    """A contact problem ready for ``write_inp`` (and for a Python-API twin).

    Attributes:
        V: Vector P1 displacement space (serial mesh).
        cell_tags, facet_tags: Tags of the bodies and of their surfaces.
        materials: ``(E, nu)`` per cell tag value.
        pair: The contact pair (slave, master, law).
        fixed: Constraints of the model definition.
        step: The static step (load, incrementation, controls, output).
        heading: One line describing the deck.
    """

    V: dolfinx.fem.FunctionSpace
    cell_tags: compat.MeshTags
    facet_tags: compat.MeshTags
    materials: dict[int, tuple[float, float]]
    pair: ntf.ContactPair
    fixed: tuple[BoundarySpec, ...]
    step: StepSpec
    heading: str

    @property
    def num_dofs(self) -> int:
        """Number of displacement dofs."""
        imap = self.V.dofmap.index_map
        return 3 * (imap.size_local + imap.num_ghosts)


def write_model(model: DeckModel, directory: Path, name: str) -> Path:
    """Write ``<directory>/<name>.inp`` for ``model``; returns the path."""
    path = Path(directory) / f"{name}.inp"
    write_inp(
        path,
        displacement_space=model.V,
        materials=model.materials,
        cell_tags=model.cell_tags,
        pairs=[model.pair],
        fixed=list(model.fixed),
        steps=[model.step],
        heading=model.heading,
    )
    return path


# ----------------------------------------------------------------------------- flat punch


@dataclass(frozen=True)
class PunchSpec:
    """Divisions of the punch deck: in-plane and vertical, for the punch and for the block."""

    punch: int
    punch_layers: int
    block: int
    block_layers: int


#: The 6 x 6 punch (49 slave nodes, spacing 20/3) on a 10 x 10 block (spacing 10): the slave nodes
#: on x, y = 30, 50, 70 lie on master nodes and edges.
TIE_PUNCH = PunchSpec(punch=6, punch_layers=4, block=10, block_layers=5)
#: The punch at three sizes (4.7k, 29k and 81k dofs). The punch spacing is 40/n and the block
#: spacing 100/n, so every fifth punch grid line lies exactly on a block grid line.
PUNCH_SIZES: dict[int, PunchSpec] = {
    10: PunchSpec(punch=10, punch_layers=8, block=10, block_layers=3),
    20: PunchSpec(punch=20, punch_layers=15, block=20, block_layers=5),
    30: PunchSpec(punch=30, punch_layers=20, block=30, block_layers=6),
}


def _snap_to_grid(x: np.ndarray, grid: np.ndarray) -> None:
    """Move x and y coordinates within round-off of a block grid line onto it, in place.

    Punch and block grid lines that coincide in exact arithmetic can differ by an ulp after
    ``linspace`` (30 + 5 (40/30) against 11 (100/30)); the ties must be exact.
    """
    for axis in (0, 1):
        nearest = grid[np.abs(x[:, axis, None] - grid[None, :]).argmin(axis=1)]
        close = np.abs(x[:, axis] - nearest) <= 1e-12 * np.abs(grid).max()
        x[close, axis] = nearest[close]


def punch_model(
    spec: PunchSpec,
    *,
    controls: Mapping[str, float] | None = None,
    contact_elements: bool = False,
) -> DeckModel:
    """The structured flat punch deck (module docstring) with the divisions of ``spec``.

    Args:
        spec: Divisions.
        controls: ``*CONTROLS, PARAMETERS=FIELD`` values by name (None: ccx's defaults).
        contact_elements: Ask both codes for the ``.cel`` contact element sets.

    Raises:
        ValueError: A division that is not a positive integer.
    """
    for what in ("punch", "punch_layers", "block", "block_layers"):
        value = getattr(spec, what)
        if not isinstance(value, int) or value < 1:
            raise ValueError(f"PunchSpec.{what} must be a positive integer, got {value!r}")
    (bo, bs), (po, ps) = BLOCK_BOX, PUNCH_BOX
    V, ct, ft = cases.blocks(
        [
            (bo, bs, (spec.block, spec.block, spec.block_layers)),
            (po, ps, (spec.punch, spec.punch, spec.punch_layers)),
        ]
    )
    _snap_to_grid(V.mesh.geometry.x, np.linspace(bo[0], bo[0] + bs[0], spec.block + 1))
    top = ntf.FacetSurface(ft, cases.facet_tag(1, cases.TOP))
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, cases.facet_tag(1, cases.BOTTOM)),
        ntf.FacetSurface(ft, cases.facet_tag(0, cases.TOP)),
        ntf.SurfaceInteraction(LAW),
    )
    output = OutputSpec(
        node_print=_OUTPUT.node_print,
        contact_print=_OUTPUT.contact_print,
        contact_elements=contact_elements,
    )
    step = StepSpec(
        boundaries=[BoundarySpec(top, (2,), -PUNCH_INDENTATION, name="PRESS")],
        increments=1,
        field_controls=None if controls is None else dict(controls),
        output=output,
    )
    fixed = (
        BoundarySpec(ntf.FacetSurface(ft, cases.facet_tag(0, cases.BOTTOM)), name="BASE"),
        BoundarySpec(top, (0, 1), name="GUIDE"),
    )
    heading = (
        f"Flat punch {spec.punch} x {spec.punch} x {spec.punch_layers} (C3D8) on a block "
        f"{spec.block} x {spec.block} x {spec.block_layers}, slave nodes on master nodes and "
        f"edges, LINEAR K = {LAW.slope:g}, sigma_inf = {LAW.tension:g}, top pushed down "
        f"{PUNCH_INDENTATION:g} in one increment"
    )
    return DeckModel(V, ct, ft, {1: ALUMINIUM, 2: STEEL}, pair, fixed, step, heading)


# ----------------------------------------------------------------------------- quarter sphere


@dataclass(frozen=True)
class SphereSpec:
    """Mesh sizes (``dolfinx_ntf.meshes.hertz``) and indentation of the quarter sphere deck.

    Attributes:
        name: Name of the pinned mesh ``meshes/<name>.npz``.
        size_fine: Edge length within ``refine_radius`` of the pole.
        size_coarse: Largest edge length.
        refine_radius: Radius of the fine zone.
        indentation: Downward displacement of the sphere's flat top.
    """

    name: str
    size_fine: float
    size_coarse: float
    refine_radius: float
    indentation: float

    def mesh_sizes(self) -> dict[str, float]:
        """Keyword arguments of ``build_hertz`` (besides the radius and block)."""
        return {"size_fine": self.size_fine, "size_coarse": self.size_coarse,
                "refine_radius": self.refine_radius}  # fmt: skip


SPHERE_RADIUS = 10.0
#: The block ``[0, 20] x [0, 20] x [-15, 0]`` under the quarter sphere (``build_hertz``'s default).
SPHERE_BLOCK = (2.0 * SPHERE_RADIUS, 2.0 * SPHERE_RADIUS, 1.5 * SPHERE_RADIUS)
SPHERE_INCREMENTS = 4
#: The benchmark deck (22k dofs).
QUARTER_SPHERE = SphereSpec(
    "quarter_sphere", size_fine=0.15, size_coarse=2.5, refine_radius=2.5, indentation=0.12
)
#: The coarse deck for tests (4.5k dofs).
QUARTER_SPHERE_COARSE = SphereSpec(
    "quarter_sphere_coarse", size_fine=0.3, size_coarse=3.0, refine_radius=2.0, indentation=0.14
)
#: Pinned meshes of the sphere decks (see :func:`pin_sphere_mesh` and meshes/README.md).
MESHES = ROOT / "meshes"


def _hertz_meshes() -> typing.Any:
    """The Hertz mesh builder (``dolfinx_ntf.meshes.hertz``)."""
    return hertz


def _gmsh_sphere(spec: SphereSpec) -> tuple[dolfinx.mesh.Mesh, compat.MeshTags, compat.MeshTags]:
    """Mesh the quarter sphere and block with gmsh (the result depends on the gmsh version)."""
    return mesh_from_gmsh(_hertz_meshes().build_hertz, MPI.COMM_SELF, radius=SPHERE_RADIUS,
                          block_size=SPHERE_BLOCK, **spec.mesh_sizes())  # fmt: skip


def sphere_facet_tags(mesh: dolfinx.mesh.Mesh, body_of_cell: np.ndarray) -> compat.MeshTags:
    """Facet tags of ``dolfinx_ntf.meshes.hertz`` (quarter model) from the geometry.

    The body of each cell and the planes of the block and of the sphere's flat top decide; the rest
    of the sphere is curved.
    """
    hz = _hertz_meshes()
    mesh.topology.create_connectivity(2, 3)
    exterior = dolfinx.mesh.exterior_facet_indices(mesh.topology)
    f_to_c = mesh.topology.connectivity(2, 3)
    body = body_of_cell[f_to_c.array[f_to_c.offsets[exterior]]]
    mid = dolfinx.mesh.compute_midpoints(mesh, 2, exterior)
    tolerance = 1e-9 * SPHERE_RADIUS

    def plane(axis: int, value: float) -> np.ndarray:
        return np.abs(mid[:, axis] - value) <= tolerance

    symmetry_x, symmetry_y = plane(0, 0.0), plane(1, 0.0)
    block, sphere = body == hz.BLOCK, body == hz.SPHERE
    values = np.zeros(exterior.size, dtype=np.int32)
    values[block & plane(2, -SPHERE_BLOCK[2])] = hz.BLOCK_BOTTOM
    values[block & plane(2, 0.0)] = hz.BLOCK_TOP
    values[sphere & plane(2, SPHERE_RADIUS)] = hz.SPHERE_TOP
    values[sphere & ~(symmetry_x | symmetry_y | plane(2, SPHERE_RADIUS))] = hz.SPHERE_CONTACT
    values[symmetry_x] = hz.SYMMETRY_X
    values[symmetry_y] = hz.SYMMETRY_Y
    keep = values > 0
    order = np.argsort(exterior[keep])
    return dolfinx.mesh.meshtags(mesh, 2, exterior[keep][order], values[keep][order])


def _pinned_sphere(spec: SphereSpec) -> tuple[dolfinx.mesh.Mesh, compat.MeshTags, compat.MeshTags]:
    """The mesh of ``meshes/<spec.name>.npz``, with its tags.

    Raises:
        ValueError: The file is missing or was made for other sizes.
    """
    path = MESHES / f"{spec.name}.npz"
    if not path.is_file():
        raise ValueError(f"pinned mesh {path} is missing: make it with "
                         "`python benchmarks/ccx_decks.py --pin`")  # fmt: skip
    data = np.load(path)
    made_for = {key: float(data[key]) for key in spec.mesh_sizes()}
    if made_for != spec.mesh_sizes():
        raise ValueError(f"pinned mesh {path} was made for {made_for}, not {spec.mesh_sizes()}: "
                         "remake it with `python benchmarks/ccx_decks.py --pin`")  # fmt: skip
    domain = compat.coordinate_element("tetrahedron", 1)
    mesh = compat.create_mesh(MPI.COMM_SELF, data["cells"].astype(np.int64), data["x"],
                              domain)  # fmt: skip
    body_of_cell = data["body"].astype(np.int32)[mesh.topology.original_cell_index]
    cell_tags = dolfinx.mesh.meshtags(
        mesh, 3, np.arange(body_of_cell.size, dtype=np.int32), body_of_cell
    )
    return mesh, cell_tags, sphere_facet_tags(mesh, body_of_cell)


def pin_sphere_mesh(spec: SphereSpec, directory: Path = MESHES) -> Path:
    """Mesh ``spec`` with gmsh and save nodes, cells and bodies to ``<directory>/<name>.npz``.

    gmsh's unstructured mesher gives different meshes in different versions (4.8 on Debian 12,
    4.13 on Debian 13), and whether a Newton iteration converges on this deck depends on the mesh;
    the decks read the pinned mesh so that every machine runs the same problem.
    """
    mesh, cell_tags, _ = _gmsh_sphere(spec)
    body = np.zeros(mesh.topology.index_map(3).size_local, dtype=np.int8)
    body[cell_tags.indices] = cell_tags.values
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{spec.name}.npz"
    np.savez_compressed(path, x=mesh.geometry.x, cells=compat.geometry_dofs(mesh).astype(np.int32),
                        body=body, **spec.mesh_sizes())  # fmt: skip
    return path


def quarter_sphere_model(
    spec: SphereSpec = QUARTER_SPHERE, *, increments: int = SPHERE_INCREMENTS, pinned: bool = True
) -> DeckModel:
    """The fixed-increment quarter sphere deck (module docstring).

    Args:
        spec: Mesh sizes and indentation.
        increments: Fixed increments of the step (``*STATIC, DIRECT``).
        pinned: Use the pinned mesh of ``meshes/`` (the same on every machine) instead of
            meshing with this machine's gmsh.
    """
    hz = _hertz_meshes()
    mesh, ct, ft = _pinned_sphere(spec) if pinned else _gmsh_sphere(spec)
    V = compat.vector_space(mesh, "Lagrange", 1)
    pair = ntf.ContactPair(
        ntf.FacetSurface(ft, hz.SPHERE_CONTACT),
        ntf.FacetSurface(ft, hz.BLOCK_TOP),
        ntf.SurfaceInteraction(LAW),
    )
    top = ntf.FacetSurface(ft, hz.SPHERE_TOP)
    step = StepSpec(
        boundaries=[BoundarySpec(top, (2,), -spec.indentation, name="PRESS")],
        increments=increments,
        output=_OUTPUT,
    )
    fixed = (
        BoundarySpec(ntf.FacetSurface(ft, hz.BLOCK_BOTTOM), name="BASE"),
        BoundarySpec(ntf.FacetSurface(ft, hz.SYMMETRY_X), (0,), name="XSYM"),
        BoundarySpec(ntf.FacetSurface(ft, hz.SYMMETRY_Y), (1,), name="YSYM"),
    )
    heading = (
        f"Quarter sphere R = {SPHERE_RADIUS:g} (C3D4, size {spec.size_fine:g} at the pole) on a "
        f"block, top pushed down {spec.indentation:g} in {increments} fixed increments, LINEAR "
        f"K = {LAW.slope:g}, sigma_inf = {LAW.tension:g}"
    )
    return DeckModel(V, ct, ft, {hz.BLOCK: STEEL, hz.SPHERE: STEEL}, pair, fixed, step, heading)


# ----------------------------------------------------------------------------- the deck list


@dataclass(frozen=True)
class BenchDeck:
    """A deck of the benchmark.

    Attributes:
        name: Job name (``<name>.inp``).
        description: One line for the report.
        write: ``write(directory)`` writes ``<directory>/<name>.inp``.
        quick: Part of the ``--quick`` selection (each code runs it in seconds).
    """

    name: str
    description: str
    write: Callable[[Path], None]
    quick: bool = False


def _model_deck(
    name: str, description: str, build: Callable[[], DeckModel], quick: bool
) -> BenchDeck:
    def write(directory: Path) -> None:
        write_model(build(), directory, name)

    return BenchDeck(name, description, write, quick)


def _punch_decks() -> list[BenchDeck]:
    decks = [
        _model_deck(
            "tie_punch",
            "C3D8 6 x 6 punch, slave nodes on master nodes/edges, R_n = C_n = 1e-9, 1 increment",
            lambda: punch_model(TIE_PUNCH, controls=TIE_CONTROLS, contact_elements=True),
            True,
        )
    ]
    for n, spec in PUNCH_SIZES.items():
        decks.append(
            _model_deck(
                f"punch_{n}",
                f"C3D8 {n} x {n} punch on a {spec.block} x {spec.block} block, 1 increment",
                lambda spec=spec: punch_model(spec, contact_elements=True),
                n == 10,
            )
        )
    return decks


def _sphere_decks() -> list[BenchDeck]:
    return [
        _model_deck(
            "quarter_sphere",
            "C3D4 quarter sphere, h = 0.15 at the pole, 4 fixed increments",
            quarter_sphere_model,
            False,
        ),
        _model_deck(
            "quarter_sphere_coarse",
            "C3D4 quarter sphere, h = 0.3 at the pole, 4 fixed increments",
            lambda: quarter_sphere_model(QUARTER_SPHERE_COARSE),
            True,
        ),
    ]


DECKS: tuple[BenchDeck, ...] = (
    *_punch_decks(),
    *_sphere_decks(),
    *(BenchDeck(c.name, f"cross-validation: {c.description}", c.write, True) for c in cases.CASES),
)
"""Every deck of the benchmark, in report order."""


def select_decks(names: Sequence[str] | None = None, *, quick: bool = False) -> list[BenchDeck]:
    """The decks called ``names`` (all if None), only the quick ones if ``quick``, in order.

    Raises:
        ValueError: An unknown name (the message lists the known ones).
    """
    known = [d.name for d in DECKS]
    unknown = [n for n in names or () if n not in known]
    if unknown:
        raise ValueError(f"unknown deck(s) {unknown}; known: {', '.join(known)}")
    return [d for d in DECKS if (names is None or d.name in names) and (d.quick or not quick)]


def main(argv: Sequence[str] | None = None) -> None:
    """Command line: ``--pin`` remakes the pinned sphere meshes, ``--write DIR`` writes decks."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--pin", action="store_true", help="remake meshes/*.npz (gmsh)")
    parser.add_argument("--write", type=Path, metavar="DIR", help="write the decks into DIR")
    parser.add_argument("--only", nargs="+", metavar="DECK", help="decks to write")
    args = parser.parse_args(argv)
    if args.pin:
        for spec in (QUARTER_SPHERE, QUARTER_SPHERE_COARSE):
            print(f"wrote {pin_sphere_mesh(spec)}")
    if args.write is not None:
        args.write.mkdir(parents=True, exist_ok=True)
        for deck in select_decks(args.only):
            deck.write(args.write)
            print(f"wrote {args.write / deck.name}.inp")


if __name__ == "__main__":
    main()
