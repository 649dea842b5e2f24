"""Write ``c3d15_dload.inp`` and ``c3d15_cload.inp``: ccx's test deck c3d15.inp for the runner.

docs/method.md §34. From ``/usr/share/doc/calculix-ccx-test/examples/test/c3d15.inp.gz``, what
the deck runner refuses is taken out: its identity ``*ORIENTATION`` and the temperature column
of ``*ELASTIC`` and ``*EXPANSION`` (no temperatures are given) are removed, ``TYPE=ISOTROPIC``
becomes ``ISO`` (``c3d15_dload.inp``). ``c3d15_cload.inp`` also writes its ``*DLOAD`` pressures
P1/P2 on flat 6-node triangles as their consistent nodal forces (``A p / 3`` on each midside
node, 0 on the corners; ccx gives the same output to 1e-14 for both forms).
"""

from __future__ import annotations

import gzip
from pathlib import Path

import numpy as np

SOURCE = Path("/usr/share/doc/calculix-ccx-test/examples/test/c3d15.inp.gz")


def main() -> None:
    with gzip.open(SOURCE, "rt") as f:
        src = f.read().splitlines()
    drop = {"*ORIENTATION, NAME=S0, DEFINITION=COORDINATES, SYSTEM=RECTANGULAR"}
    text = []
    skip_next = False
    for line in src:
        if skip_next:
            skip_next = False
            continue
        if line in drop:
            skip_next = True
            continue
        line = line.replace(", ORIENTATION=S0", "").replace("TYPE=ISOTROPIC", "TYPE=ISO")
        line = line.replace(" 29000000.,      0.32,       70.", " 29000000.,      0.32")
        line = line.replace("    6.6E-6,       70.", "    6.6E-6")
        text.append(line)
    nodes, elems, buf, mode = {}, {}, [], None
    for line in text:
        if line.startswith("*"):
            mode = line.split(",")[0].strip().upper()
            continue
        f = [t.strip() for t in line.split(",") if t.strip()]
        if mode == "*NODE":
            nodes[int(f[0])] = np.array(list(map(float, f[1:4])))
        elif mode == "*ELEMENT":
            buf += [int(t) for t in f]
            if len(buf) == 16:
                elems[buf[0]] = buf[1:]
                buf = []
    loads: dict[int, np.ndarray] = {}
    out, in_dload = [], False
    for line in text:
        if line.upper().startswith("*DLOAD"):
            in_dload = True
            continue
        if in_dload and not line.startswith("*"):
            f = [t.strip() for t in line.split(",")]
            e, face, p = int(f[0]), f[1].upper(), float(f[2])
            n = elems[e]
            top = face == "P2"
            tri = (
                [n[3], n[4], n[5], n[9], n[10], n[11]]
                if top
                else [n[0], n[1], n[2], n[6], n[7], n[8]]
            )
            a, b, c = (nodes[k] for k in tri[:3])
            cross = np.cross(b - a, c - a)
            area = np.linalg.norm(cross) / 2
            outward = (cross if top else -cross) / (2 * area)  # S1 1-2-3 points inwards
            for m in tri[3:]:
                loads[m] = loads.get(m, np.zeros(3)) - p * area / 3 * outward
            continue
        if in_dload and line.startswith("*"):
            in_dload = False
            out.append("*CLOAD")
            for m in sorted(loads):
                out += [f"{m}, {d + 1}, {loads[m][d]:.17g}" for d in range(3) if loads[m][d]]
        out.append(line)
    here = Path(__file__).parent
    (here / "c3d15_dload.inp").write_text("\n".join(text) + "\n")
    (here / "c3d15_cload.inp").write_text("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
