"""The slave surface's set-up distribution on several processes: allgather against exchange.

docs/method.md §14.1, §14.2. Each process needs its owned slave nodes and every slave face (of any
process) holding one of them. The former way allgathered the whole slave surface (the node numbers
of every slave node and every face's node numbers and coordinates) on every process and kept what
it needed; ``distribute_slave`` now sends each face only to the owners of its nodes. This
script times both on the plates of ``benchmarks/contact_phases.py`` (slowest process, median of
``--repeat`` runs after a warm-up, each on a fresh halo), checks that they give the same surface,
and counts the bytes of slave surface each process holds after it and receives from the others
(largest over the processes; faces as node numbers and coordinates, 8 bytes each).
Run::

    mpirun -n 2 .venv/bin/python benchmarks/slave_distribution.py --sizes 1e4 1e5
"""

from __future__ import annotations

import argparse
import statistics
import time
import typing

from mpi4py import MPI

import numpy as np
from contact_phases import SLAVE, build_plates

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.fem.surfaces import SlaveSurface, SurfaceFaces, resolve_slave
from dolfinx_ntf.parallel import collectives, surface_distribution
from dolfinx_ntf.parallel.halo import NodeHalo

COMM = MPI.COMM_WORLD


def allgathered(halo: NodeHalo, slave: SlaveSurface) -> SlaveSurface:
    """The former way (before the exchange): the whole slave surface on every process."""
    slave_global = np.unique(
        np.concatenate(COMM.allgather(halo.local_global[slave.nodes])).astype(np.int64)
    )
    g, x, facets = surface_distribution._gather_faces(halo, slave.faces, "slave")
    mine = np.intersect1d(slave_global, halo.local_global[: halo.num_owned])
    keep = np.isin(g, mine).any(axis=1)
    faces = SurfaceFaces(
        slave.faces.face_type, halo.local(g[keep], x[keep]).astype(np.int32), facets[keep]
    )
    return SlaveSurface(np.sort(halo.find(mine)), faces, None)


def received_bytes(halo: NodeHalo, slave: SlaveSurface) -> tuple[int, ...]:
    """Bytes of slave surface this process holds after the distribution and receives from other
    processes: allgather, then exchange (node numbers and coordinates of faces, node numbers)."""
    n = slave.faces.faces.shape[1]
    per_face = 8 * (n + 3 * n)
    own = slave.faces.faces.shape[0]
    gathered = COMM.allreduce(own) * per_face + 8 * COMM.allreduce(slave.nodes.size)
    ghosts = halo.local_global[slave.nodes[slave.nodes >= halo.num_owned]]
    keys = collectives.send_to_owners(COMM, ghosts, halo.owner(ghosts)).size
    got, _ = surface_distribution._send_faces_to_owners(halo, slave.faces)
    exchanged = 8 * keys + got.shape[0] * per_face + 16 * COMM.size
    return (
        gathered,
        gathered - own * per_face - 8 * slave.nodes.size,
        exchanged + own * per_face,
        exchanged,
    )


def timed(function: typing.Callable[[NodeHalo], typing.Any], V, repeat: int) -> float:
    """Median (over runs) of the slowest process's time, each run on a fresh halo."""
    times = []
    for run in range(repeat + 1):
        node_halo = NodeHalo(V)
        COMM.barrier()
        start = time.perf_counter()
        function(node_halo)
        if run:
            times.append(COMM.allreduce(time.perf_counter() - start, op=MPI.MAX))
    return statistics.median(times)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--sizes", type=float, nargs="+", default=[1e4, 1e5])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args(argv)
    rows = []
    for size in args.sizes:
        plates = build_plates(int(size))
        V = compat.vector_space(plates.mesh, "Lagrange", 1)
        surface = ntf.FacetSurface(plates.facet_tags, SLAVE)
        slave = resolve_slave(V, surface, what="slave")
        a = allgathered(NodeHalo(V), slave)
        b = surface_distribution.distribute_slave(V, NodeHalo(V), surface, slave, "slave")
        same = all(
            np.array_equal(p, q)
            for p, q in [
                (a.nodes, b.nodes),
                (a.faces.faces, b.faces.faces),
                (a.faces.facets, b.faces.facets),
            ]
        )
        same = COMM.allreduce(same, op=MPI.LAND)
        received = [max(v) for v in zip(*COMM.allgather(received_bytes(NodeHalo(V), slave)))]
        rows.append(
            (
                COMM.allreduce(slave.nodes.size if COMM.size == 1 else b.nodes.size),
                COMM.allreduce(slave.faces.faces.shape[0]),
                timed(lambda halo: allgathered(halo, slave), V, args.repeat),
                timed(
                    lambda halo: surface_distribution.distribute_slave(
                        V, halo, surface, slave, "slave"
                    ),
                    V,
                    args.repeat,
                ),
                received,
                same,
            )
        )
    if COMM.rank == 0:
        print(f"{COMM.size} processes; slowest process, median of {args.repeat} runs")
        print(
            "| slave nodes | slave faces | allgather | exchange |"
            " held, allgather (received) | held, exchange (received) | same |"
        )
        print("|---|---|---|---|---|---|---|")
        for nodes, faces, t0, t1, (b0, o0, b1, o1), same in rows:
            print(
                f"| {nodes} | {faces} | {t0:.4f} s | {t1:.4f} s | {b0 / 1e6:.2f} MB"
                f" ({o0 / 1e6:.2f} MB) | {b1 / 1e6:.2f} MB ({o1 / 1e6:.2f} MB) | {same} |"
            )


if __name__ == "__main__":
    main()
