"""CalculiX interoperability: run ccx decks, write decks, read and write ccx results.

File formats (pure Python/numpy, no dolfinx):
    - ``deck``: ``read_deck`` parses the node-to-face subset of a ``.inp`` deck into a ``Deck``;
    - ``dat``: ccx 2.20 ``.dat`` blocks, written byte for byte as ccx does, and read back;
    - ``cel``: the CONTACT ELEMENTS file ``jobname.cel``;
    - ``ccx``: ``run_ccx`` and helpers to read its results; ``compare``: ccx results against a
      job's.
dolfinx glue:
    - ``model``: ``build_model`` turns a ``Deck`` into a mesh, UFL forms, loads and contact pairs;
    - ``job``: ``run_job`` runs a deck like ``ccx JOB`` (also ``python -m dolfinx_ntf run JOB``);
    - ``writer``: ``write_inp`` exports a problem built in Python as an equivalent ccx deck.
"""

from .ccx import CcxError, dat_block, dat_times, read_ccx_dat, read_sta, run_ccx
from .cel import ContactElementsFile, format_contact_elements, read_cel
from .compare import compare_job
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
from .job import JobError, JobResult, run_job
from .model import build_model
from .writer import write_inp

__all__ = [
    "ELEMENT_TYPES",
    "CcxError",
    "ContactElementsFile",
    "DatBlock",
    "Deck",
    "DeckError",
    "JobError",
    "JobResult",
    "Step",
    "build_model",
    "compare_job",
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
    "run_job",
    "surface_nodes",
    "write_dat",
    "write_inp",
]
