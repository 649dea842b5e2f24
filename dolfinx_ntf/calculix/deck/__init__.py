"""Reader of CalculiX ``.inp`` decks: the subset needed for node-to-face contact.

See docs/method.md §8.5.

``read_deck`` turns a deck (with its ``*INCLUDE`` files) into a ``Deck`` of frozen dataclasses
that keeps CalculiX's node and element numbers, so that results can be reported per ccx node. Only
the keywords that a static node-to-surface contact analysis needs are understood; everything else
is rejected with a ``DeckError`` (a ``ValueError``) naming the keyword and ``file:line``, except
the keywords and parameters that cannot change the solution (output-only ones, those ccx itself
ignores): ``LENIENCY`` lists them, the reader skips them with one ``DeckWarning`` each in
``Deck.warnings`` (skipped keywords are also in ``Deck.ignored``), as ccx warns and goes on.

Conventions shared by the whole module (they follow ccx, manual §"Input deck format"):
    - Keywords, parameters and names are case-insensitive and blanks are not significant: every
      name (sets, surfaces, materials, interactions, amplitudes) is stored upper-case without
      blanks, as ccx prints them. Only ``*HEADING`` text and ``*INCLUDE`` file names keep their
      case.
    - Node and element sets keep their members in definition order, duplicates included (ccx
      prints ``*NODE PRINT`` rows in that order). Set names must be defined before they are
      used; node and element *numbers* may be defined anywhere and are checked at the end.
    - Element types and their face tables are in ``calculix.elements`` (ccx's internal face
      order, outward normals).
    - Pure Python/numpy: no dolfinx import.
"""

from ..elements import ELEMENT_TYPES, ElementType
from .data import (
    FIELD_CONTROL_DEFAULTS,
    FIELD_CONTROL_NAMES,
    Amplitude,
    Boundary,
    CLoad,
    ContactPair,
    Coupled,
    CyclicSymmetry,
    Deck,
    DLoad,
    Dynamic,
    ElementBlock,
    Equation,
    FileRequest,
    Film,
    Frequency,
    Friction,
    FrictionChange,
    Gravity,
    InitialTemperature,
    InitialVelocity,
    Material,
    ModalDamping,
    ModalDynamic,
    ModelChange,
    PrintRequest,
    SolidSection,
    SpringElements,
    Static,
    Step,
    Surface,
    SurfaceBehavior,
    SurfaceInteraction,
    Tie,
    TimePoints,
)
from .errors import DeckError, DeckWarning, Location, not_supported
from .faces import external_faces, face_nodes, node_surface_faces, surface_nodes
from .leniency import LENIENCY
from .reader import read_deck

__all__ = [
    "ELEMENT_TYPES",
    "FIELD_CONTROL_DEFAULTS",
    "FIELD_CONTROL_NAMES",
    "LENIENCY",
    "Amplitude",
    "Boundary",
    "CLoad",
    "ContactPair",
    "Coupled",
    "CyclicSymmetry",
    "DLoad",
    "Deck",
    "DeckError",
    "DeckWarning",
    "Dynamic",
    "ElementBlock",
    "ElementType",
    "Equation",
    "FileRequest",
    "Film",
    "Frequency",
    "Friction",
    "FrictionChange",
    "Gravity",
    "InitialTemperature",
    "InitialVelocity",
    "Location",
    "Material",
    "ModalDamping",
    "ModalDynamic",
    "ModelChange",
    "PrintRequest",
    "SolidSection",
    "SpringElements",
    "Static",
    "Step",
    "Surface",
    "SurfaceBehavior",
    "SurfaceInteraction",
    "Tie",
    "TimePoints",
    "external_faces",
    "face_nodes",
    "node_surface_faces",
    "not_supported",
    "read_deck",
    "surface_nodes",
]
