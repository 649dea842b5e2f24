"""CalculiX interoperability: deck reader, ``.dat``/``.cel`` writers and readers, ccx runner.

Pure Python/numpy (no dolfinx import), so decks and ccx results can be handled anywhere:
    - ``deck``: ``read_deck`` parses the node-to-face subset of a ``.inp`` deck into a ``Deck``;
    - ``dat``: ccx 2.20 ``.dat`` blocks, written byte for byte as ccx does, and read back;
    - ``cel``: the CONTACT ELEMENTS file ``jobname.cel``;
    - ``ccx``: ``run_ccx`` and helpers to read its results.
"""

from .ccx import CcxError, dat_block, dat_times, read_ccx_dat, read_sta, run_ccx
from .cel import ContactElementsFile, format_contact_elements, read_cel
from .dat import (
    DatBlock,
    contact_print_blocks,
    el_print_blocks,
    format_block,
    node_print_blocks,
    read_dat,
    write_dat,
)
from .deck import (
    ELEMENT_TYPES,
    Deck,
    DeckError,
    Step,
    external_faces,
    face_nodes,
    node_surface_faces,
    read_deck,
    surface_nodes,
)

__all__ = [
    "CcxError",
    "ContactElementsFile",
    "DatBlock",
    "Deck",
    "DeckError",
    "ELEMENT_TYPES",
    "Step",
    "contact_print_blocks",
    "dat_block",
    "dat_times",
    "el_print_blocks",
    "external_faces",
    "face_nodes",
    "format_block",
    "format_contact_elements",
    "node_print_blocks",
    "node_surface_faces",
    "read_ccx_dat",
    "read_cel",
    "read_dat",
    "read_deck",
    "read_sta",
    "run_ccx",
    "surface_nodes",
    "write_dat",
]
