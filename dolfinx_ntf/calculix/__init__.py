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

from dolfinx_ntf.lazy_names import lazy_dir, lazy_getattr

#: Where each public name lives: the submodules are imported on first use (PEP 562), so that
#: ``run_job`` does not pay for the deck writer, the ccx runner or the comparisons it never uses.
_LAZY = {
    "CcxError": "ccx",
    "ContactElementsFile": "cel",
    "DatBlock": "dat",
    "Deck": "deck",
    "DeckError": "deck",
    "ELEMENT_TYPES": "deck",
    "JobError": "job",
    "JobResult": "job",
    "Step": "deck",
    "build_model": "model",
    "compare_job": "compare",
    "contact_print_blocks": "dat",
    "dat_block": "ccx",
    "dat_times": "ccx",
    "el_print_blocks": "dat",
    "external_faces": "deck",
    "face_nodes": "deck",
    "format_block": "dat",
    "format_contact_elements": "cel",
    "node_print_blocks": "dat",
    "node_surface_faces": "deck",
    "read_ccx_dat": "ccx",
    "read_cel": "cel",
    "read_dat": "dat",
    "read_deck": "deck",
    "read_sta": "ccx",
    "run_ccx": "ccx",
    "run_job": "job",
    "surface_nodes": "deck",
    "write_dat": "dat",
    "write_inp": "writer",
}

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


__getattr__ = lazy_getattr(__name__, _LAZY)
__dir__ = lazy_dir(__name__, __all__)
