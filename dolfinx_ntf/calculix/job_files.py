"""The ccx files of a deck run: ``.dat``, ``.frd``, ``.cel``, ``.sta`` and ``.cvg``.

:class:`JobFiles` opens them as ccx does at program start and writes, in ccx 2.20's formats:

    - ``JOB.dat``: the ``*NODE PRINT`` (U, RF), ``*EL PRINT`` (S, E, PEEQ, ENER, SDV, ME) and
      ``*CONTACT PRINT`` (CDIS, CSTR, CELS, CNUM) blocks of each printed increment
      (docs/method.md §8.5, §36).
    - ``JOB.frd``: the mesh, then the ``*NODE FILE`` (U, RF), ``*EL FILE`` (S, E as
      ``TOSTRAIN``, ME as ``MESTRAIN``, PEEQ as ``PE``, ENER, SDV) and ``*CONTACT FILE`` (CDIS,
      CSTR) blocks (§13.2).
    - ``JOB.cel``: the contact elements of every pairing when ``CONTACT ELEMENTS`` is requested.
    - ``JOB.sta`` and ``JOB.cvg``: one row per attempt and per Newton iteration (§13.3).

The values come from :class:`~dolfinx_ntf.calculix.output_values.OutputValues` (collective); only
rank 0 writes (docs/method.md §14.5), the other processes hold writers that discard.
"""

from __future__ import annotations

import logging
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .cel import ContactElementsFile
from .dat import (
    DatBlock,
    contact_print_blocks,
    el_print_blocks,
    increment_heading,
    node_print_blocks,
    step_heading,
    write_dat,
)
from .deck import Deck, FileRequest, PrintRequest, Step
from .elements import ELEMENT_TYPES
from .frd import FrdBlock, FrdWriter
from .gather import Discard
from .model import CalculixModel
from .output_values import ContactRows, OutputValues
from .progress import CvgFile, StaFile
from .roundoff import (
    FieldAccuracy,
    clean_contact,
    clean_dat_blocks,
    clean_frd_block,
    clean_totals,
    zero_below,
)

__all__ = ["JobFiles", "check_requests"]

logger = logging.getLogger("dolfinx_ntf")

#: ccx numbers contact element sets with at most three digits per counter.
MAX_SET_NUMBER = 999


class JobFiles:
    """The ``.dat``, ``.frd``, ``.cel``, ``.sta`` and ``.cvg`` files of one job.

    Opening them empties ``.dat``, starts ``.frd`` with the mesh and deletes a ``.cel`` left from
    an earlier run when the deck asks for no contact elements, as ccx does.

    Args:
        jobname: Deck name without ``.inp``.
        directory: Where the files are written.
        deck: The deck.
        model: Its dolfinx model.
        root: True on the process that writes (rank 0).
        ccx: The ccx version whose ``.dat`` and ``.frd`` formats are written (docs/method.md
            §13.6): ``"2.23"`` adds its step and increment lines, its CELS title and its CONTACT
            component records.
    """

    def __init__(
        self,
        jobname: str,
        directory: Path,
        deck: Deck,
        model: CalculixModel,
        *,
        root: bool,
        ccx: str = "2.20",
    ) -> None:
        self.deck, self.model, self.root, self.ccx = deck, model, root, ccx
        self._printed_step: Step | None = None
        self.dat = directory / f"{jobname}.dat"
        if root:
            write_dat(self.dat, [])
        self.cel: Path | None = None
        self._cel: ContactElementsFile | Discard | None = None
        cel = directory / f"{jobname}.cel"
        if any(step.contact_elements for step in deck.steps):
            self.cel = cel
            self._cel = ContactElementsFile(cel, deck.num_elements) if root else Discard()
        elif cel.exists() and root:  # ccx deletes the file at program start
            cel.unlink()
        self._cel_overflow = False
        self.frd = directory / f"{jobname}.frd"
        self._frd = _frd_writer(self.frd, deck, model, ccx) if root else Discard()
        self._sta = StaFile(directory / f"{jobname}.sta") if root else Discard()
        self._cvg = CvgFile(directory / f"{jobname}.cvg") if root else Discard()

    def write_dat_text(self, text: str) -> None:
        """Append ``text`` to the ``.dat`` file (rank 0), e.g. a frequency step's blocks."""
        if self.root:
            with open(self.dat, "a", encoding="ascii", newline="\n") as handle:
                handle.write(text)

    def write_mode(self, step: Step, number: int, total: float, displacement: np.ndarray) -> None:
        """The print blocks of mode ``number`` of a ``*FREQUENCY`` step (rank 0 writes).

        ``displacement`` (N, 3) is the mode at every deck node. As ccx 2.20, which has no contact
        elements in the step, the contact prints are empty (docs/method.md §16.2).
        """
        blocks: list[DatBlock] = []
        for request in step.prints:
            if request.kind == "NODE":
                ids = self.deck.nsets[request.set]
                values = displacement[self.deck.node_index(ids)]
                blocks += node_print_blocks("U", request.set, total, ids, values)
            else:  # CONTACT (check_requests refuses the others)
                blocks += _contact_blocks(request, total, [])
        if self.root:
            heading = f"{' ' * 20}E I G E N V A L U E    N U M B E R{number:6d}\n\n"
            write_dat(self.dat, clean_dat_blocks(blocks), append=True, ccx=self.ccx,
                      heading=heading)  # fmt: skip

    def write_modal_increment(
        self, step: Step, total: float, displacement: np.ndarray, velocity: np.ndarray
    ) -> None:
        """The ``*NODE PRINT`` U and V blocks of a ``*MODAL DYNAMIC`` increment (rank 0 writes).

        ``displacement`` and ``velocity`` (N, 3) are at every deck node (docs/method.md §25).
        """
        blocks: list[DatBlock] = []
        for request in step.node_prints:
            ids = self.deck.nsets[request.set]
            rows = self.deck.node_index(ids)
            for key in request.keys:
                values = (displacement if key == "U" else velocity)[rows]
                blocks += node_print_blocks(key, request.set, total, ids, values)
        if self.root and blocks:
            write_dat(self.dat, clean_dat_blocks(blocks), append=True, ccx=self.ccx)

    def close(self) -> None:
        """Close the ``.frd`` file (the others are appended to row by row)."""
        self._frd.close()

    # -- .sta, .cvg --------------------------------------------------------------------------------

    def attempt(
        self,
        numbers: tuple[int, int, int],
        converged: bool,
        iterations: int,
        total_time: float,
        step_time: float,
        size: float,
        history: Sequence,
    ) -> None:
        """The ``.sta`` row and ``.cvg`` rows of an attempt ``(step, increment, attempt)``."""
        step, increment, attempt = numbers
        self._sta.row(step, increment, attempt, converged, iterations, total_time, step_time, size)
        self._cvg.rows(step, increment, attempt, history)

    # -- .cel --------------------------------------------------------------------------------------

    def wants_contact_elements(self, step: Step, numbers: tuple[int, int, int, int]) -> bool:
        """True if the pairing ``(step, increment, attempt, iteration)`` goes to the ``.cel`` file.

        Set numbers above 999 (ccx's limit) end the ``.cel`` output with a warning.
        """
        if self._cel is None or not step.contact_elements or self._cel_overflow:
            return False
        if max(numbers) > MAX_SET_NUMBER:
            logger.warning(
                " *WARNING: contact element set numbers above 999 (ccx limit): no more .cel output"
            )
            self._cel_overflow = True
            return False
        return True

    def write_contact_elements(
        self,
        numbers: tuple[int, int, int, int],
        elements: list[tuple[np.ndarray, np.ndarray]],
    ) -> None:
        """Write one pairing's ``(master faces, slave nodes)`` per pair (docs/method.md §8.5)."""
        step, increment, attempt, iteration = numbers
        for faces, slaves in elements:
            self._cel.write(
                faces,
                slaves,
                step=step,
                increment=increment,
                attempt=attempt,
                iteration=iteration,
            )

    # -- .dat, .frd --------------------------------------------------------------------------------

    def write_increment(
        self,
        step: Step,
        increment: int,
        total: float,
        contact: list[ContactRows],
        values: OutputValues,
        *,
        load_time: tuple[int, float],
        largest_residual: float,
        prints: Sequence[PrintRequest] | None = None,
        files: bool = True,
    ) -> None:
        """The ``.dat`` and ``.frd`` blocks of a printed increment at total time ``total``.

        ``contact`` are the increment's contact rows, ``load_time`` its ``(step index, step
        time)``, ``largest_residual`` that of its converged iterate; ``prints`` the print
        requests to write (default: the step's), ``files`` whether the ``.frd`` blocks are
        written too. Collective.
        """
        contact = [clean_contact(rows) for rows in contact]  # printed values (§14.5)
        results = _Increment(self.deck, values, load_time, largest_residual)
        blocks = results.dat_blocks(step, total, contact, step.prints if prints is None else prints)
        if self.root:
            heading = ""
            if self.ccx == "2.23" and blocks:
                if step is not self._printed_step:
                    self._printed_step = step
                    number = next(k for k, s in enumerate(self.deck.steps, 1) if s is step)
                    heading = step_heading(number)
                heading += increment_heading(increment)
            write_dat(self.dat, clean_dat_blocks(blocks), append=True, ccx=self.ccx,
                      heading=heading)  # fmt: skip
        for block in results.frd_blocks(step, increment, total, contact) if files else ():
            self._frd.write(clean_frd_block(block))


class _Increment:
    """The ``.dat`` and ``.frd`` blocks of one printed increment."""

    def __init__(
        self,
        deck: Deck,
        values: OutputValues,
        load_time: tuple[int, float],
        largest_residual: float,
    ) -> None:
        self.deck, self.values = deck, values
        self.load_time, self.largest_residual = load_time, largest_residual

    def frd_blocks(
        self, step: Step, increment: int, total: float, contact: list[ContactRows]
    ) -> list[FrdBlock]:
        """The ``.frd`` blocks in ccx's order.

        DISP, STRESS, TOSTRAIN, MESTRAIN, FORC, PE, ENER, SDV, CONTACT.
        """
        keys = {(r.kind, k): r for r in step.file_requests for k in r.keys}
        blocks = []

        def node_block(name: str, request: FileRequest, values: np.ndarray) -> None:
            ids = _frd_node_ids(self.deck)
            if request.set is not None:  # in set order, repeats kept, as ccx (docs/method.md §13.2)
                ids = self.deck.nsets[request.set]
            values = values[self.deck.node_index(ids)]
            if name == "DISP":
                values = self.values.with_reference(ids, values, self.load_time)
            blocks.append(FrdBlock(name, (), step.number, increment, total, ids, values))

        if ("NODE", "U") in keys:
            node_block("DISP", keys["NODE", "U"], self.values.displacements())
        if ("EL", "S") in keys:
            nodes, values = self.values.nodal_stresses()
            values = zero_below(values, self.values.field_accuracy().stress)
            nodes, values = _in_set(self.deck, keys["EL", "S"], nodes, values)
            blocks.append(FrdBlock("STRESS", (), step.number, increment, total, nodes, values))
        if ("EL", "E") in keys:
            nodes, values = self.values.nodal_strains()
            values = zero_below(values, self.values.field_accuracy().strain)
            nodes, values = _in_set(self.deck, keys["EL", "E"], nodes, values)
            blocks.append(FrdBlock("TOSTRAIN", (), step.number, increment, total, nodes, values))
        if ("EL", "ME") in keys:
            nodes, values = self.values.nodal_element_values("ME")
            values = zero_below(values, self.values.field_accuracy().strain)
            nodes, values = _in_set(self.deck, keys["EL", "ME"], nodes, values)
            blocks.append(FrdBlock("MESTRAIN", (), step.number, increment, total, nodes, values))
        if ("NODE", "RF") in keys:
            node_block(
                "FORC", keys["NODE", "RF"], self.values.printed_forces(self.largest_residual)[0]
            )
        if ("EL", "PEEQ") in keys and self.values.model.plasticity:  # else none, as ccx's
            nodes, values = self.values.nodal_equivalent_plastic_strains()
            nodes, values = _in_set(self.deck, keys["EL", "PEEQ"], nodes, values)
            blocks.append(FrdBlock("PE", (), step.number, increment, total, nodes, values))
        for key in ("ENER", "SDV"):  # SDV without plastic sections: no components, as ccx's
            if ("EL", key) in keys:
                nodes, values = self.values.nodal_element_values(key)
                values = _within_accuracy(key, values, self.values.field_accuracy())
                nodes, values = _in_set(self.deck, keys["EL", key], nodes, values)
                blocks.append(FrdBlock(key, (), step.number, increment, total, nodes, values))
        if ("CONTACT", "CDIS") in keys or ("CONTACT", "CSTR") in keys:
            nodes = np.concatenate([r.nodes for r in contact]) if contact else np.zeros(0, int)
            values = np.zeros((nodes.size, 6))
            if contact:
                values[:, 0] = np.concatenate([r.clearance for r in contact])
                values[:, 3] = np.concatenate([r.pressure for r in contact])
            # ccx writes the contact elements in reverse order here (ascending in the .dat file)
            blocks.append(
                FrdBlock("CONTACT", (), step.number, increment, total, nodes[::-1], values[::-1])
            )
        return blocks

    def dat_blocks(
        self,
        step: Step,
        total: float,
        contact: list[ContactRows],
        prints: Sequence[PrintRequest],
    ) -> list[DatBlock]:
        """The ``.dat`` blocks of the print requests ``prints`` of ``step``, in the deck's order."""
        blocks: list[DatBlock] = []
        forces, floor = None, 0.0
        displacement = self.values.displacements()
        for request in prints:
            if request.kind == "NODE":
                ids = self.deck.nsets[request.set]
                for key in request.keys:
                    if key == "RF" and forces is None:
                        forces, floor = self.values.printed_forces(self.largest_residual)
                    if key in ("NT", "V"):
                        nodal = self.values.temperatures() if key == "NT" else None
                        if key == "V":
                            nodal = self.values.velocities()
                        values = nodal[self.deck.node_index(ids)]
                        blocks += node_print_blocks(key, request.set, total, ids, values)
                        continue
                    values = (displacement if key == "U" else forces)[self.deck.node_index(ids)]
                    if key == "U":
                        values = self.values.with_reference(ids, values, self.load_time)
                    new = node_print_blocks(
                        key, request.set, total, ids, values, totals=request.totals
                    )
                    blocks += clean_totals(new, ids.size, floor) if key == "RF" else new
            elif request.kind == "EL":
                blocks += self._element_blocks(request, total)
            else:
                blocks += _contact_blocks(request, total, contact)
        return blocks

    def _element_blocks(self, request: PrintRequest, total: float) -> list[DatBlock]:
        ids = self.deck.elsets[request.set]
        blocks = []
        for key in request.keys:
            if key == "HFL":
                blocks += el_print_blocks(
                    "HFL", request.set, total, ids, self.values.heat_fluxes(ids)
                )
                continue
            if key == "E":
                strains = zero_below(self.values.strains(ids), self.values.field_accuracy().strain)
                counts = self.values.point_counts(ids, strains.shape[1])
                blocks += el_print_blocks("E", request.set, total, ids, strains, counts)
                continue
            if key in ("ME", "ENER", "SDV"):
                if key == "ME":
                    values = self.values.mechanical_strains(ids)
                    values = zero_below(values, self.values.field_accuracy().strain)
                else:
                    values = getattr(self.values, _ELEMENT_VALUES[key])(ids)
                    values = _within_accuracy(key, values, self.values.field_accuracy())
                counts = self.values.point_counts(ids, values.shape[1])
                blocks += el_print_blocks(key, request.set, total, ids, values, counts)
                continue
            if key == "PEEQ":
                if not self.values.model.plasticity:  # ccx 2.20 prints no block without one
                    continue
                values = self.values.equivalent_plastic_strains(ids)
                counts = self.values.point_counts(ids, values.shape[1])
                blocks += el_print_blocks("PEEQ", request.set, total, ids, values, counts)
                continue
            if key != "S":
                raise NotImplementedError(
                    f"{request.location}: *EL PRINT key {key} is not supported yet"
                )
            stresses = zero_below(self.values.stresses(ids), self.values.field_accuracy().stress)
            counts = self.values.point_counts(ids, stresses.shape[1])
            blocks += el_print_blocks("S", request.set, total, ids, stresses, counts)
        return blocks


#: The OutputValues method of the element keys printed from the laws' or the elastic values.
_ELEMENT_VALUES = {"ENER": "energy_densities", "SDV": "state_variables"}


def _within_accuracy(key: str, values: np.ndarray, accuracy: FieldAccuracy) -> np.ndarray:
    """ENER or SDV values (last axis: the components) with those within round-off as 0.

    ENER at the energy's accuracy; SDV's plastic strains (components 2-7) at the strain's, its
    equivalent plastic strain as PEEQ (the law's value) and its zeros unchanged.
    """
    if key == "ENER":
        return zero_below(values, accuracy.energy)
    values = np.array(values, dtype=np.float64)
    if values.shape[-1]:
        values[..., 1:7] = zero_below(values[..., 1:7], accuracy.strain)
    return values


def _in_set(
    deck: Deck, request: FileRequest, nodes: np.ndarray, values: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The rows of the request's node set that have values, in set order (all without a set)."""
    if request.set is None:
        return nodes, values
    members = deck.nsets[request.set]
    pos = np.minimum(np.searchsorted(nodes, members), nodes.size - 1)
    keep = nodes[pos] == members
    return members[keep], values[pos[keep]]


def _contact_blocks(
    request: PrintRequest, total: float, contact: list[ContactRows]
) -> list[DatBlock]:
    """The ``*CONTACT PRINT`` blocks of ``request``: rows of all pairs, pairs in deck order."""
    nodes = np.concatenate([r.nodes for r in contact]) if contact else np.zeros(0, np.int64)
    zeros = np.zeros(nodes.size)
    zeros2 = np.zeros((nodes.size, 2))

    def tangential(name: str) -> np.ndarray:
        return np.concatenate([getattr(r, name) for r in contact]) if contact else zeros2

    columns = {
        "CDIS": lambda: np.column_stack(
            [
                np.concatenate([r.clearance for r in contact]) if contact else zeros,
                tangential("slip"),
            ]
        ),
        "CSTR": lambda: np.column_stack(
            [
                np.concatenate([r.pressure for r in contact]) if contact else zeros,
                tangential("shear"),
            ]
        ),
        "CELS": lambda: np.concatenate([r.energy for r in contact]) if contact else zeros,
        "CNUM": lambda: None,
    }
    blocks = []
    for key in request.keys:
        if key not in columns:
            raise NotImplementedError(
                f"{request.location}: *CONTACT PRINT key {key} is not supported yet"
            )
        blocks += contact_print_blocks(key, total, nodes, columns[key](), totals=request.totals)
    return blocks


def _frd_node_ids(deck: Deck) -> np.ndarray:
    """The nodes ccx writes in the ``.frd``: without shell nodes and unused middle nodes (§24)."""
    if deck.shells is None:
        return deck.node_ids
    return deck.node_ids[~np.isin(deck.node_ids, deck.shells.hidden())]


def _frd_writer(path: Path, deck: Deck, model: CalculixModel, ccx: str) -> FrdWriter:
    """The ``.frd`` file with the deck's mesh (ccx writes it for every job)."""
    block = deck.elements[model.element_type.name]
    materials = list(deck.materials)
    index = dict(zip(materials, range(1, len(materials) + 1)))
    element_material = np.zeros(block.ids.size, dtype=np.int64)
    order = np.argsort(block.ids, kind="stable")
    for section in deck.sections:  # a later section's material wins, as ccx's
        members = np.asarray(deck.elsets[section.elset], dtype=np.int64)
        rows = order[np.minimum(np.searchsorted(block.ids, members, sorter=order), order.size - 1)]
        missing = block.ids[rows] != members
        if np.any(missing):
            raise KeyError(int(members[np.argmax(missing)]))
        element_material[rows] = index[section.material]
    ids = _frd_node_ids(deck)
    return FrdWriter(
        path,
        ids,
        deck.node_coords[deck.node_index(ids)],
        block.ids,
        model.element_type.name,
        block.connectivity,
        element_material,
        materials + list(deck.interactions),
        ccx=ccx,
        wedges=(deck.wedges, deck.wedge_nodes),
    )


def _check_transformed_outputs(deck: Deck) -> None:
    """Refuse node outputs of ``*TRANSFORM`` nodes: ccx prints them in the local directions."""
    if deck.transformed_nodes.size == 0:
        return
    for step in deck.steps:
        requests = [r for r in step.prints if r.kind == "NODE"]
        requests += [r for r in step.file_requests if r.kind == "NODE"]
        for request in requests:
            members = deck.nsets.get(request.set) if request.set is not None else None
            held = deck.node_ids if members is None else members
            if np.isin(held, deck.transformed_nodes).any():
                raise NotImplementedError(
                    f"{request.location}: node output of nodes with a *TRANSFORM is not "
                    "supported yet (ccx prints them in their local directions); request a set "
                    "without them"
                )


#: ``*EL PRINT`` keys printed at ccx's two C3D6 points of a wedge.
_WEDGE_PRINT_KEYS = {"S", "E", "PEEQ", "ENER", "SDV", "ME"}
#: ``*EL FILE`` keys extrapolated to a wedge's nodes by ccx's C3D6 weights (method §35, §41.4).
_WEDGE_FILE_KEYS = {"S", "E", "PEEQ", "ENER", "SDV", "ME"}


def _check_wedge_outputs(deck: Deck) -> None:
    """Refuse the wedges' element outputs that are not built (method §30.6, §35, §36).

    ``*EL PRINT`` S, E, PEEQ, ENER, SDV and ME of a wedge are printed at ccx's two C3D6 points;
    ``*EL FILE`` writes the same keys extrapolated to the nodes by ccx's C3D6 weights (§41.4).
    """
    if deck.wedges.size == 0:
        return
    for step in deck.steps:
        for request in [*step.prints, *step.file_requests]:
            if request.kind != "EL":
                continue
            allowed = _WEDGE_PRINT_KEYS if isinstance(request, PrintRequest) else _WEDGE_FILE_KEYS
            if set(request.keys) <= allowed:
                continue
            members = deck.elsets.get(request.set or "", None) if request.set else None
            hit = deck.wedges if members is None else deck.wedges[np.isin(deck.wedges, members)]
            if hit.size:
                keyword = request.keyword if isinstance(request, FileRequest) else "*EL PRINT"
                raise NotImplementedError(
                    f"{request.location}: {keyword} {'/'.join(request.keys)} of C3D6 element "
                    f"{int(hit[0])} is not supported (only S, E, PEEQ, ENER, SDV and ME of ccx's "
                    "two C3D6 points)"
                )


#: Element outputs built for 3D continuum elements only, and what each is in a refusal.
_CONTINUUM_KEYS = {
    "E": "E (strains)",
    "ME": "ME (mechanical strains)",
    "ENER": "ENER (strain energy densities)",
    "SDV": "SDV (internal state variables)",
}


def _check_strain_outputs(deck: Deck) -> None:
    """Refuse E, ME, ENER and SDV where ccx's values were not measured.

    2D elements, C3D8I, shells (docs/method.md §21.6, §36); the message names the element type
    and the deck line. Coupled steps print them (measured, §36).
    """
    names = [name for name in deck.elements if name in ELEMENT_TYPES]
    why = ""
    flat = [name for name in names if ELEMENT_TYPES[name].tdim == 2]
    if flat:
        why = f"2D elements ({', '.join(flat)})"
    elif "C3D8I" in deck.elements:
        why = "C3D8I elements (their incompatible modes)"
    elif deck.shells is not None:
        why = "shell elements"
    for step in deck.steps:
        for request in [*step.prints, *step.file_requests]:
            if request.kind != "EL":
                continue
            for key in (k for k in request.keys if k in _CONTINUUM_KEYS):
                if why:
                    keyword = request.keyword if isinstance(request, FileRequest) else "*EL PRINT"
                    raise NotImplementedError(
                        f"{request.location}: {keyword} {_CONTINUUM_KEYS[key]} of a deck with "
                        f"{why} is not supported yet"
                    )


def check_requests(deck: Deck) -> None:
    """Output keys this runner cannot produce: a clear error before anything runs."""
    supported = {
        "NODE": {"U", "RF", "V"},
        "EL": {"S", "E", "PEEQ", "ENER", "SDV", "ME"},
        "CONTACT": {"CDIS", "CSTR", "CELS", "CNUM"},
    }
    for step in deck.steps:
        if step.modal_dynamic is not None:
            _check_modal_requests(step)
            continue
        for request in step.prints:
            for key in request.keys:
                thermal = (request.kind, key) in (("NODE", "NT"), ("EL", "HFL"))
                if (request.kind, key) == ("NODE", "V") and step.dynamic is None:
                    raise NotImplementedError(
                        f"{request.location}: *NODE PRINT V (velocities) is supported in *DYNAMIC "
                        "and *MODAL DYNAMIC steps only"
                    )
                if thermal and step.coupled is None:
                    raise NotImplementedError(
                        f"{request.location}: *{request.kind} PRINT {key} needs a *COUPLED "
                        "TEMPERATURE-DISPLACEMENT step"
                    )
                if key not in supported[request.kind] and not thermal:
                    raise NotImplementedError(
                        f"{request.location}: *{request.kind} PRINT key {key} is not supported yet"
                    )
    for step in deck.steps:
        if step.frequency is None:
            continue
        for request in step.prints:
            if request.kind == "EL" or (request.kind == "NODE" and set(request.keys) != {"U"}):
                raise NotImplementedError(
                    f"{request.location}: *{request.kind} PRINT {', '.join(request.keys)} in the "
                    f"*FREQUENCY step at {step.location} is not supported yet (modes print U and "
                    "the contact keys only)"
                )
        if step.file_requests:
            logger.warning(
                " *WARNING: the modes of the *FREQUENCY step at %s are not written to the .frd "
                "file",
                step.location,
            )
    _check_transformed_outputs(deck)
    _check_wedge_outputs(deck)
    _check_strain_outputs(deck)
    written = {
        "NODE": {"U", "RF"},
        "EL": {"S", "E", "PEEQ", "ENER", "SDV", "ME"},
        "CONTACT": {"CDIS", "CSTR"},
    }
    for step in deck.steps:
        for request in step.file_requests:
            for key in request.keys:
                if key not in written[request.kind]:
                    logger.warning(
                        " *WARNING: %s key %s is not written to the .frd file (%s)",
                        request.keyword,
                        key,
                        request.location,
                    )


def _check_modal_requests(step: Step) -> None:
    """A ``*MODAL DYNAMIC`` step prints ``*NODE PRINT`` U and V (docs/method.md §25)."""
    for request in step.prints:
        if request.kind != "NODE" or not set(request.keys) <= {"U", "V"}:
            raise NotImplementedError(
                f"{request.location}: *{request.kind} PRINT {', '.join(request.keys)} in the "
                f"*MODAL DYNAMIC step at {step.location} is not supported yet (U and V only)"
            )
    if step.file_requests:
        logger.warning(
            " *WARNING: the *MODAL DYNAMIC step at %s writes nothing to the .frd file",
            step.location,
        )
