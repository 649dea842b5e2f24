"""The deck's contact pairs with their pressure-overclosure laws, friction and ADJUST."""

from __future__ import annotations

import logging

import numpy as np

from dolfinx_ntf.contact.problem import ContactPair
from dolfinx_ntf.fem.surfaces import FaceNodesSurface, FacetSurface, NodeSurface
from dolfinx_ntf.kernels.laws import (
    ContactDamping,
    ExponentialLaw,
    Friction,
    LinearLaw,
    PressureOverclosureLaw,
    SurfaceInteraction,
    TabularLaw,
)

from ..deck import ContactPair as ContactPairCard
from ..deck import Deck, Location, not_supported
from ..deck import Friction as FrictionCard
from .c3d15 import c3d15_exterior
from .mesh import MeshMaps

__all__ = [
    "adjust_of",
    "contact_pairs",
    "damping_of",
    "first_youngs_modulus",
    "friction_of",
    "pressure_overclosure_law",
    "surface_section",
]


def pressure_overclosure_law(deck: Deck, interaction_name: str) -> PressureOverclosureLaw:
    """The ``*SURFACE BEHAVIOR`` of an interaction as a pressure-overclosure law."""
    behavior = deck.interactions[interaction_name].behavior
    kind = behavior.pressure_overclosure
    if kind == "EXPONENTIAL":
        c0, p0 = behavior.values
        return ExponentialLaw(c0=c0, p0=p0)
    if kind in ("LINEAR", "HARD"):
        elastic = next((m.elastic for m in deck.materials.values() if m.elastic is not None), None)
        if elastic is None:
            raise ValueError(
                f"{behavior.location}: {kind} contact needs an *ELASTIC material for its defaults"
            )
        values = tuple(behavior.values) + (None,) * (3 - len(behavior.values))
        return LinearLaw.with_ccx_defaults(elastic[0], *values[:3])
    if kind == "TABULAR":
        table = behavior.table
        if table.shape[1] != 2:
            raise not_supported(
                "temperature-dependent *SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=TABULAR",
                behavior.location,
            )
        return TabularLaw(pressures=table[:, 0], overclosures=table[:, 1])
    raise not_supported(f"*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE={kind}", behavior.location)


def first_youngs_modulus(deck: Deck, location: Location) -> float:
    """E of the first ``*ELASTIC`` material: ccx's reference for contact defaults."""
    elastic = next((m.elastic for m in deck.materials.values() if m.elastic is not None), None)
    if elastic is None:
        raise ValueError(f"{location}: contact defaults need an *ELASTIC material")
    return elastic[0]


def friction_of(deck: Deck, data: FrictionCard) -> Friction:
    """A ``*FRICTION`` data line as ccx reads it: a missing or non-positive lambda is ``E/2``.

    The default is announced with a warning, as ccx does (docs/method.md §11.5).
    """
    e = first_youngs_modulus(deck, data.location)
    if data.stick_slope is None or data.stick_slope <= 0.0:
        logging.getLogger("dolfinx_ntf").warning(
            " *WARNING in frictions: stick slope (lambda) missing or not positive at %s; "
            "using E/2 = %g",
            data.location,
            0.5 * e,
        )
        return Friction(data.mu, 0.5 * e)
    return Friction(data.mu, data.stick_slope)


def damping_of(deck: Deck, interaction_name: str) -> ContactDamping | None:
    """The ``*CONTACT DAMPING`` of an interaction (it acts in ``*DYNAMIC`` steps only, §29)."""
    data = deck.interactions[interaction_name].damping
    return None if data is None else ContactDamping(data.coefficient, data.tangent_fraction)


def adjust_of(deck: Deck, pair: ContactPairCard, maps: MeshMaps) -> float | NodeSurface | None:
    """The ADJUST of a pair: a distance, the vertices of a node set, or None."""
    if pair.adjust is None or isinstance(pair.adjust, float):
        return pair.adjust
    ids = deck.nsets[pair.adjust]
    vertices = maps.node_vertex[deck.node_index(ids)]
    corner = maps.corner[deck.node_index(ids)]
    if not np.all(corner):
        node = int(ids[np.argmax(~corner)])
        raise not_supported(
            f"ADJUST={pair.adjust} with node {node}, which is not an element corner",
            pair.location,
        )
    # C3D15: the exterior faces by their nodes, a prism mesh has no facets (§38)
    outer = c3d15_exterior(deck, maps, pair.adjust) if maps.block.type.name == "C3D15" else None
    return NodeSurface(
        np.unique(vertices[vertices >= 0]).astype(np.int32), pair.adjust, exterior=outer
    )


def surface_section(
    deck: Deck, maps: MeshMaps, name: str, models: np.ndarray, thickness: np.ndarray
) -> tuple[str, float]:
    """The 2D model and thickness of an element-face surface's elements (one of each).

    Raises:
        NotImplementedError: the surface's elements mix models or thicknesses (its springs
            would need them per node).
    """
    surface = deck.surfaces[name]
    block = maps.block
    order = np.argsort(block.ids)
    rows = order[np.searchsorted(block.ids, np.unique(surface.elements), sorter=order)]
    kinds, widths = np.unique(models[rows]), np.unique(thickness[rows])
    if kinds.size != 1 or widths.size != 1:
        raise not_supported(
            f"*SURFACE {name} on elements of different 2D models or thicknesses "
            f"({', '.join(map(str, kinds))}; {', '.join(f'{t:g}' for t in widths)})",
            surface.location,
        )
    return str(kinds[0]), float(widths[0])


def contact_pairs(
    deck: Deck,
    surfaces: dict[str, FacetSurface | NodeSurface | FaceNodesSurface],
    maps: MeshMaps,
    *,
    thickness: np.ndarray | None = None,
    models: np.ndarray | None = None,
    area_weights: str = "consistent",
) -> list[ContactPair]:
    """The deck's ``*CONTACT PAIR`` cards as contact pairs, in deck order.

    On CPE/CPS elements the spring areas are the edge shares times the slave elements'
    thickness, on CAX elements the ring areas of the whole circumference, consistent or with the
    shares of ccx's expanded faces (``area_weights``, docs/method.md §23). Node-based slave
    surfaces of 2D elements are faceless, as in ccx: every spring gets ccx's fallback area of
    the master face, a plane layer's or an axisymmetric sector's (docs/method.md §26.3).

    Args:
        deck: The deck.
        surfaces: Its dolfinx surfaces.
        maps: The mesh maps.
        thickness: The thickness of each element of the block (2D decks; default 1).
        models: The 2D model of each element of the block (default: the block type's).
        area_weights: ``"ccx"`` or ``"consistent"`` (2D decks).
    """
    block = maps.block
    two_d_deck = block.type.tdim == 2
    if models is None:
        models = np.full(block.ids.size, block.type.model, dtype=object)
    if thickness is None:
        thickness = np.ones(block.ids.size)
    pairs = []
    for pair in deck.contact_pairs:
        law = pressure_overclosure_law(deck, pair.interaction)
        data = deck.interactions[pair.interaction].friction
        friction = None if data is None else friction_of(deck, data)
        two_d: dict = {}
        if two_d_deck:
            master_model, master_t = surface_section(deck, maps, pair.master, models, thickness)
            two_d["area_weights"] = area_weights
            if isinstance(surfaces[pair.slave], NodeSurface):  # faceless: the master's area
                if master_model == "axisymmetric":
                    two_d["fallback_area"] = "ccx_ring"
                else:
                    two_d.update(fallback_area="ccx_plane", thickness=master_t)
            else:
                model, t = surface_section(deck, maps, pair.slave, models, thickness)
                two_d.update(
                    {"axisymmetric": True} if model == "axisymmetric" else {"thickness": t}
                )
        pairs.append(
            ContactPair(
                surfaces[pair.slave],
                surfaces[pair.master],
                SurfaceInteraction(law, friction, damping_of(deck, pair.interaction)),
                small_sliding=pair.small_sliding,
                name=f"{pair.slave}-{pair.master}",
                adjust=adjust_of(deck, pair, maps),
                hold_fallback_area=not two_d_deck,  # ccx's, docs/method.md §38.5
                **two_d,
            )
        )
    return pairs
