"""The CONTACT ELEMENTS file ``jobname.cel`` of CalculiX 2.20 (docs/method.md §8.5).

With ``CONTACT ELEMENTS`` on a ``*NODE FILE``/``*EL FILE``/``*CONTACT FILE``/... card, ccx writes
every contact element of every pairing (every Newton iteration that re-pairs) as a cgx-readable
element, so the spring elements can be displayed over the mesh. Layout, verified against ccx 2.20:

    - one ``*ELEMENT,TYPE=...,ELSET=contactelements_st<step>_in<inc>_at<attempt>_it<iter>``
      line per element, followed by its data line;
    - quad master faces (4, 8 or 9 nodes) give a degenerate wedge ``C3D6`` with nodes
      ``(m2, s, m3, m1, s, m4)``, triangular faces (3 or 6 nodes) a ``C3D4`` ``(m1, m2, m3, s)``,
      where ``m1..m4`` are the face corners in ccx face order and ``s`` the slave node;
    - the data line is Fortran list-directed output: each integer right-aligned in 12 columns,
      separated by `` ,`` (element number first);
    - element numbers continue after the regular elements and never restart during the run;
    - ccx deletes the file at program start and appends at every pairing; set-name numbers
      (step, increment, attempt, iteration) must stay below 1000.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

__all__ = [
    "CelDifference",
    "CelElement",
    "ContactElementsFile",
    "cel_pairings",
    "compare_cel",
    "format_contact_elements",
    "read_cel",
]


def _set_name(step: int, increment: int, attempt: int, iteration: int) -> str:
    for what, value in (("step", step), ("increment", increment), ("attempt", attempt),
                        ("iteration", iteration)):  # fmt: skip
        if not 0 < int(value) < 1000:
            raise ValueError(
                f"{what} number {value} of a contact element set must be in 1..999 (ccx limit)"
            )
    return f"contactelements_st{step}_in{increment}_at{attempt}_it{iteration}"


def format_contact_elements(
    first_number: int,
    master_faces: np.ndarray,
    slave_nodes: np.ndarray,
    *,
    step: int,
    increment: int,
    attempt: int,
    iteration: int,
) -> str:
    """Text of one pairing's contact elements in ``.cel`` format.

    Args:
        first_number: element number of the first contact element.
        master_faces: ``(N, n)`` node numbers of each element's master face, ccx face order
            (n = 3, 4, 6, 8 or 9).
        slave_nodes: ``(N,)`` slave node number of each element.
        step: 1-based step number of the set name.
        increment: 1-based increment number of the set name.
        attempt: 1-based attempt number of the set name.
        iteration: 1-based iteration number of the set name.
    """
    faces = np.asarray(master_faces, dtype=np.int64)
    slaves = np.asarray(slave_nodes, dtype=np.int64).reshape(-1)
    if faces.ndim != 2 or faces.shape[0] != slaves.size:
        raise ValueError(f"master_faces must have shape ({slaves.size}, n), got {faces.shape}")
    if slaves.size == 0:
        return ""
    n = faces.shape[1]
    if n in (4, 8, 9):
        etype = "C3D6"
        nodes = np.stack([faces[:, 1], slaves, faces[:, 2], faces[:, 0], slaves, faces[:, 3]], 1)
    elif n in (3, 6):
        etype = "C3D4"
        nodes = np.column_stack([faces[:, :3], slaves])
    else:
        raise ValueError(f"master faces must have 3, 4, 6, 8 or 9 nodes, got {n}")
    header = f"*ELEMENT,TYPE={etype},ELSET={_set_name(step, increment, attempt, iteration)}\n"
    numbers = np.arange(first_number, first_number + slaves.size, dtype=np.int64)
    rows = np.column_stack([numbers, nodes])
    return "".join(header + " ,".join(f"{v:12d}" for v in row) + "\n" for row in rows.tolist())


class ContactElementsFile:
    """Writer of ``jobname.cel`` that numbers contact elements like ccx.

    Opening truncates the file (ccx deletes it at program start); every ``write`` appends one
    pairing and advances the element counter, which never restarts.

    Args:
        path: the ``.cel`` file.
        num_regular_elements: number of elements of the mesh; contact elements follow them.
    """

    def __init__(self, path: str | Path, num_regular_elements: int) -> None:
        if num_regular_elements < 0:
            raise ValueError(f"num_regular_elements must be >= 0, got {num_regular_elements}")
        self.path = Path(path)
        self.next_number = int(num_regular_elements) + 1
        self.path.write_text("")

    def write(
        self,
        master_faces: np.ndarray,
        slave_nodes: np.ndarray,
        *,
        step: int,
        increment: int,
        attempt: int,
        iteration: int,
    ) -> np.ndarray:
        """Append one pairing; return the ``(N,)`` element numbers given to its elements.

        ``master_faces``, ``slave_nodes``, ``step``, ``increment``, ``attempt`` and ``iteration``
        are those of :func:`format_contact_elements`.
        """
        text = format_contact_elements(
            self.next_number, master_faces, slave_nodes, step=step, increment=increment,
            attempt=attempt, iteration=iteration,
        )  # fmt: skip
        count = np.asarray(slave_nodes).size
        numbers = np.arange(self.next_number, self.next_number + count, dtype=np.int64)
        with open(self.path, "a", encoding="ascii", newline="\n") as handle:
            handle.write(text)
        self.next_number += count
        return numbers


@dataclass(frozen=True, eq=False)
class CelElement:
    """One element read from a ``.cel`` file."""

    set: str
    type: str
    number: int
    nodes: tuple[int, ...]


def read_cel(path: str | Path) -> list[CelElement]:
    """Read the ``.cel`` file at ``path`` (ccx's or ours) into its elements, in file order.

    Raises:
        ValueError: a line that is not an ``*ELEMENT`` line or an element data line.
    """
    path = Path(path)
    elements: list[CelElement] = []
    etype = elset = None
    for number, line in enumerate(path.read_text(encoding="latin-1").splitlines(), start=1):
        if not line.strip():
            continue
        if line.upper().startswith("*ELEMENT"):
            params = dict(p.split("=", 1) for p in line.split(",")[1:] if "=" in p)
            params = {k.strip().upper(): v.strip() for k, v in params.items()}
            etype, elset = params.get("TYPE"), params.get("ELSET")
            continue
        if etype is None:
            raise ValueError(f"{path}:{number}: element data before an *ELEMENT line")
        try:
            values = [int(v) for v in line.replace(",", " ").split()]
        except ValueError:
            raise ValueError(f"{path}:{number}: bad element data line {line.strip()!r}") from None
        elements.append(CelElement(elset or "", etype, values[0], tuple(values[1:])))
    return elements


def cel_pairings(elements: list[CelElement]) -> dict[str, dict[int, frozenset[int]]]:
    """Each pairing's master face per slave node: ``{set: {slave node: face corner nodes}}``.

    Sets keep their file order (one per pairing). A ``C3D6`` element ``(m2, s, m3, m1, s, m4)``
    gives its slave ``s`` and corners ``m1..m4``, a ``C3D4`` ``(m1, m2, m3, s)`` its slave ``s``
    and corners ``m1..m3``.

    Raises:
        ValueError: An element that is neither, or a slave node twice in one set.
    """
    sets: dict[str, dict[int, frozenset[int]]] = {}
    for element in elements:
        nodes = element.nodes
        if element.type == "C3D6" and len(nodes) == 6 and nodes[1] == nodes[4]:
            slave, corners = nodes[1], frozenset((nodes[0], nodes[2], nodes[3], nodes[5]))
        elif element.type == "C3D4" and len(nodes) == 4:
            slave, corners = nodes[3], frozenset(nodes[:3])
        else:
            raise ValueError(
                f"contact element {element.number} ({element.type}, nodes {list(nodes)}) of set "
                f"{element.set} is not a C3D6 (m2, s, m3, m1, s, m4) or C3D4 (m1, m2, m3, s)"
            )
        pairing = sets.setdefault(element.set, {})
        if slave in pairing:
            raise ValueError(f"slave node {slave} has two contact elements in set {element.set}")
        pairing[slave] = corners
    return sets


@dataclass(frozen=True)
class CelDifference:
    """One pairing of two ``.cel`` files compared (see :func:`compare_cel`).

    Attributes:
        set: The set name (``contactelements_st<s>_in<i>_at<a>_it<n>``).
        other_face: Slave nodes paired in both, to different master faces.
        only_first, only_second: Slave nodes with a contact element in one file only.
    """

    set: str
    other_face: tuple[int, ...]
    only_first: tuple[int, ...]
    only_second: tuple[int, ...]

    @property
    def count(self) -> int:
        """Slave nodes whose pairing differs (other face, or paired in one file only)."""
        return len(self.other_face) + len(self.only_first) + len(self.only_second)


def compare_cel(first: str | Path, second: str | Path) -> list[CelDifference]:
    """Compare two ``.cel`` files pairing by pairing.

    Only sets both files contain are compared, in the first file's order (e.g. ccx's, which stops
    at its failure, against ours).
    """
    a, b = cel_pairings(read_cel(first)), cel_pairings(read_cel(second))
    out = []
    for name, pa in a.items():
        if name not in b:
            continue
        pb = b[name]
        common = pa.keys() & pb.keys()
        out.append(
            CelDifference(
                name,
                tuple(sorted(s for s in common if pa[s] != pb[s])),
                tuple(sorted(pa.keys() - pb.keys())),
                tuple(sorted(pb.keys() - pa.keys())),
            )
        )
    return out
