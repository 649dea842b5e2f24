"""``mesh_from_gmsh(..., MPI.COMM_SELF)`` on one process of several: no collective on COMM_WORLD.

A serial reference mesh built on rank 0 alone must neither hang nor wait for the other ranks
(docs/method.md §44). On 2 ranks, rank 1 waits in a non-blocking barrier that rank 0 joins only
after its call: a COMM_WORLD collective inside the call would mismatch it. ``faulthandler`` ends a
hung process with its traceback (the test run fails instead of spinning). The reported hang was
PETSc's initialization, which ``import dolfinx`` runs and which is collective on MPI_COMM_WORLD:
the subprocess test checks the documented way out (``petsc4py.init(comm=MPI.COMM_SELF)`` first).
"""

import faulthandler
import os
import shutil
import subprocess
import sys
import textwrap
import time
from pathlib import Path

from mpi4py import MPI

import pytest
from helpers.prism_blocks import BASE, PUNCH, build_prism_on_hex

import dolfinx.fem
import dolfinx.mesh
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.fem.serendipity_wedge import QUADRATIC_PRISMS_MIN_DOLFINX
from dolfinx_ntf.meshes import punch
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

WORLD = MPI.COMM_WORLD
#: Seconds after which a hung process is ended with its traceback.
GUARD = 120.0
#: The punch model: block [0, 1] x [0, 1] x [-0.5, 0] and punch 0.4 x 0.4 x 0.3 on top.
PUNCH_VOLUME = 0.5 + 0.4 * 0.4 * 0.3
COARSE = {"mesh_size_block": 0.25, "mesh_size_punch": 0.2}


def _volume(
    mesh: dolfinx.mesh.Mesh, dx: ufl.Measure | None = None, tag: int | None = None
) -> float:
    """Volume of ``mesh`` (of cells tagged ``tag``), summed over the mesh's own communicator."""
    measure = ufl.dx(domain=mesh) if dx is None else dx(tag)
    local = dolfinx.fem.assemble_scalar(dolfinx.fem.form(1.0 * measure))
    return mesh.comm.allreduce(local, op=MPI.SUM)


def _on_rank_zero(build_and_check) -> None:
    """Run ``build_and_check()`` on rank 0 of COMM_WORLD only, the others waiting without a
    collective that the call could complete; every process ends with its traceback on a hang."""
    faulthandler.dump_traceback_later(GUARD, exit=True)
    try:
        error = None
        if WORLD.rank == 0:
            try:
                build_and_check()
            except Exception as exc:  # reported on all ranks below
                error = exc
            request = WORLD.Ibarrier()
        else:
            request = WORLD.Ibarrier()  # completes only once rank 0 is through its call
        while not request.Test():
            time.sleep(0.01)
        errors = WORLD.allgather(None if error is None else repr(error))
        if error is not None:
            raise error
        assert errors[0] is None, f"rank 0: {errors[0]}"
    finally:
        faulthandler.cancel_dump_traceback_later()


@pytest.mark.mpi
@pytest.mark.parametrize("cell_type", ["tetrahedron", "hexahedron"])
def test_punch_on_comm_self_on_rank_zero_only(cell_type):
    def build_and_check():
        mesh, cell_tags, facet_tags = mesh_from_gmsh(
            punch.build_punch, MPI.COMM_SELF, cell_type=cell_type, **COARSE
        )
        assert mesh.comm.size == 1
        cells = mesh.topology.index_map(3)
        assert cells.num_ghosts == 0
        assert cell_tags.indices.size == cells.size_local
        assert facet_tags.indices.size > 0
        assert _volume(mesh) == pytest.approx(PUNCH_VOLUME, rel=1e-12)

    _on_rank_zero(build_and_check)


@pytest.mark.mpi
def test_prisms_beside_hexahedra_on_comm_self_on_rank_zero_only():
    def build_and_check():
        mesh, cell_tags, _ = mesh_from_gmsh(build_prism_on_hex, MPI.COMM_SELF)
        assert mesh.comm.size == 1
        assert mesh.topology.cell_type == dolfinx.mesh.CellType.hexahedron
        dx = ufl.Measure("dx", domain=mesh, subdomain_data=cell_tags)
        assert _volume(mesh, dx, BASE) == pytest.approx(1.0, rel=1e-12)
        assert _volume(mesh, dx, PUNCH) == pytest.approx(0.18, rel=1e-12)

    _on_rank_zero(build_and_check)


@pytest.mark.mpi
@pytest.mark.skipif(
    compat.DOLFINX_VERSION < QUADRATIC_PRISMS_MIN_DOLFINX,
    reason="15-node prisms need dolfinx 0.11 (docs/method.md §40)",
)
def test_quadratic_prisms_on_comm_self_on_rank_zero_only():
    from helpers.quadratic_prisms import VOLUME, build_prism_block

    def build_and_check():
        mesh, cell_tags, faces = mesh_from_gmsh(build_prism_block, MPI.COMM_SELF)
        assert mesh.comm.size == 1
        assert mesh.geometry.x.shape[0] > 0
        assert set(cell_tags.values.tolist()) == {VOLUME}
        assert faces.triangles.shape[0] > 0 and faces.quadrilaterals.shape[0] > 0

    _on_rank_zero(build_and_check)


_ONLY_RANK_ZERO_IMPORTS = textwrap.dedent(
    """
    from mpi4py import MPI

    if MPI.COMM_WORLD.rank == 0:
        import petsc4py

        petsc4py.init(comm=MPI.COMM_SELF)  # before anything imports dolfinx
        from dolfinx_ntf.meshes import punch
        from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

        mesh, _, _ = mesh_from_gmsh(
            punch.build_punch, MPI.COMM_SELF, cell_type="tetrahedron",
            mesh_size_block=0.25, mesh_size_punch=0.2,
        )
        print("cells", mesh.topology.index_map(3).size_local, flush=True)
    """
)


@pytest.mark.skipif(WORLD.size > 1, reason="starts its own 2-process mpirun")
@pytest.mark.skipif(shutil.which("mpirun") is None, reason="no mpirun")
def test_rank_zero_alone_imports_dolfinx_after_petsc_on_comm_self(tmp_path: Path):
    """The documented recipe for a rank that alone uses dolfinx: PETSc's world set to COMM_SELF."""
    script = tmp_path / "rank_zero.py"
    script.write_text(_ONLY_RANK_ZERO_IMPORTS)
    root = Path(__file__).resolve().parents[2]
    env = dict(
        os.environ, PYTHONPATH=os.pathsep.join([str(root), os.environ.get("PYTHONPATH", "")])
    )
    command = ["mpirun", "-n", "2", sys.executable, str(script)]
    if os.geteuid() == 0:
        command[1:1] = ["--allow-run-as-root", "--oversubscribe"]
    result = subprocess.run(
        ["timeout", "120", *command], capture_output=True, text=True, env=env, cwd=tmp_path
    )
    assert result.returncode == 0, (
        f"status {result.returncode} (124: hung)\n{result.stderr[-2000:]}"
    )
    assert "cells " in result.stdout
    assert int(result.stdout.split("cells ")[1].split()[0]) > 0
