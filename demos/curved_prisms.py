"""A curved bracket of 15-node prisms from gmsh (CalculiX C3D15 in the Python API, dolfinx 0.11).

A quarter ring (radii 40 and 60 mm, 20 mm thick, steel) is clamped at its end on the y axis and
loaded by a pressure on its other end face (on the x axis), which pushes that end along the
ring and bends it. gmsh triangulates the ring's quarter annulus, extrudes the triangles into
prisms and raises them to second order (``Mesh.SecondOrderIncomplete = 1``: 15-node prisms,
whose edges follow the arcs). :func:`~dolfinx_ntf.meshes.gmsh_io.mesh_from_gmsh` reads them
into a mesh of 18-node prisms, the face centres placed by the quad8 map as CalculiX's C3D15
(docs/method.md §40); since dolfinx has no facets on prism meshes the tagged faces come back as
node rows
(:class:`~dolfinx_ntf.fem.wedge_faces.PrismFaces`) and the pressure becomes nodal forces
(:func:`~dolfinx_ntf.fem.wedge_faces.prism_face_forces`). The displacement lives in C3D15's
space (:func:`~dolfinx_ntf.fem.serendipity_wedge.wedge15_space`: vector P2 with the
quadrilateral centres constrained), integrated at ccx's 9 points; the constraints are eliminated
(``dolfinx_ntf.fem.constraints.ConstraintElimination``) and the system solved by LU.

The demo checks the equilibrium (the clamp's reaction, with each constrained centre's force
handed to the nodes it depends on, equals the load), reads the same ring as 18-node prisms
(gmsh's face centres; on these extruded, ruled faces they coincide with the quad8 ones, so the
results agree to round-off), and compares the loaded end's displacement
with Castigliano's thin curved beam (bending, normal force and shear; the ring is thick, so
only roughly). dolfinx 0.5.2 and 0.9 cannot run degree-2 spaces on prisms: there the demo says
so and stops.

Run it with::

    .venv/bin/python demos/curved_prisms.py           # finer mesh
    .venv/bin/python demos/curved_prisms.py --coarse  # small mesh (tests)
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from mpi4py import MPI
from petsc4py import PETSc

import gmsh
import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

from dolfinx_ntf import compat
from dolfinx_ntf.fem.constraints import ConstraintElimination
from dolfinx_ntf.fem.serendipity_wedge import wedge15_metadata, wedge15_space
from dolfinx_ntf.fem.wedge_faces import prism_face_forces
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

__all__ = ["build_ring", "main"]

# %%
# Parameters
# ----------
# Units: mm, N, MPa.

INNER, OUTER, THICKNESS = 40.0, 60.0, 20.0
E, NU = 210_000.0, 0.3  # steel
PRESSURE = 50.0  # MPa on the loaded end face (outward normal -y): a force along +y
#: Physical groups: the ring, the clamped end (x = 0), the loaded end (y = 0).
RING, CLAMPED, LOADED = 1, 11, 12


# %%
# The gmsh model
# --------------
# A quarter annulus in the plane z = 0, triangulated and extruded with ``recombine=True``: prisms.
# Second order after meshing: 15-node prisms (``incomplete``) or 18-node ones.


def build_ring(*, size: float, layers: int, incomplete: bool = True) -> None:
    """The quarter ring of second-order prisms in the current gmsh session, ends tagged."""
    gmsh.model.add("curved_prisms")
    occ = gmsh.model.occ
    ring, _ = occ.cut(
        [(2, occ.addDisk(0, 0, 0, OUTER, OUTER))], [(2, occ.addDisk(0, 0, 0, INNER, INNER))]
    )
    quarter, _ = occ.intersect(ring, [(2, occ.addRectangle(0, 0, 0, 2 * OUTER, 2 * OUTER))])
    volume = occ.extrude(quarter, 0, 0, THICKNESS, numElements=[layers], recombine=True)
    occ.synchronize()
    gmsh.model.addPhysicalGroup(3, [t for d, t in volume if d == 3], RING)
    e = 1e-6 * OUTER
    for tag, box in (
        (CLAMPED, (-e, -e, -e, e, OUTER + e, THICKNESS + e)),
        (LOADED, (-e, -e, -e, OUTER + e, e, THICKNESS + e)),
    ):
        faces = occ.getEntitiesInBoundingBox(*box, dim=2)
        gmsh.model.addPhysicalGroup(2, [t for _, t in faces], tag)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", int(incomplete))
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)


# %%
# The solve
# ---------
# Small-strain elasticity at ccx's 9 points; the clamp leaves the constrained face centres free
# (their constraint fixes them), the face-centre rows are eliminated.


def _solve(mesh, faces) -> dict:
    """Displacement, reaction and load of the ring (serial)."""
    V, constraints = wedge15_space(mesh)
    centres = np.unique(np.concatenate([c.nodes[:, 0] for c in constraints]))
    clamped = dolfinx.fem.locate_dofs_geometrical(V, lambda x: np.isclose(x[0], 0.0))
    clamped = clamped[~np.isin(clamped, centres)]
    bcs = [dolfinx.fem.dirichletbc(np.zeros(3), clamped, V)]
    mu, lam = E / (2 * (1 + NU)), E * NU / ((1 + NU) * (1 - 2 * NU))
    u_, v = ufl.TrialFunction(V), ufl.TestFunction(V)
    eps = ufl.sym(ufl.grad(u_))
    sigma = lam * ufl.tr(eps) * ufl.Identity(3) + 2 * mu * eps
    dx = ufl.Measure("dx", domain=mesh, metadata=wedge15_metadata())
    a = dolfinx.fem.form(ufl.inner(sigma, ufl.sym(ufl.grad(v))) * dx)
    forces = prism_face_forces(V, faces, LOADED, PRESSURE)

    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=bcs)
    A.assemble()
    b = A.createVecLeft()
    b.array[:] = forces.x.array
    dolfinx.fem.petsc.set_bc(b, bcs)
    prescribed = bcs[0].dof_indices()[0].astype(np.int64)
    elimination = ConstraintElimination(b.getSize(), constraints, prescribed, mesh.comm)
    reduced = elimination.reduce_matrix(A, ("stiffness",))
    elimination.reduce_vector(b, lambda x: dolfinx.fem.petsc.set_bc(x, bcs))
    ksp = PETSc.KSP().create(mesh.comm)
    ksp.setOperators(reduced)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    x = reduced.createVecRight()
    ksp.solve(b, x)
    elimination.back_substitute(x)
    u = dolfinx.fem.Function(V)
    u.x.array[:] = x.array

    # reaction: the unconstrained stiffness times u minus the load, each dependent centre's
    # force handed to its 8 nodes (the transpose of the constraint), summed over the clamp
    K = dolfinx.fem.petsc.assemble_matrix(a)
    K.assemble()
    displacement, internal = K.createVecRight(), K.createVecLeft()
    displacement.array[:] = u.x.array
    K.mult(displacement, internal)
    residual = (internal.array - forces.x.array).reshape(-1, 3)
    for block in constraints:
        rows, weights = block.nodes, -np.asarray(block.coefficients)[:, 1:]
        comp = block.components[:, 0]
        np.add.at(
            residual, (rows[:, 1:], comp[:, None]), weights * residual[rows[:, 0], comp][:, None]
        )
        residual[rows[:, 0], comp] = 0.0
    reaction = residual[clamped].sum(axis=0)
    load = forces.x.array.reshape(-1, 3).sum(axis=0)
    free = np.setdiff1d(np.arange(residual.shape[0]), clamped)
    for obj in (ksp, x, b, A, K, displacement, internal):
        obj.destroy()
    elimination.destroy()
    return {
        "V": V,
        "u": u,
        "reaction": reaction,
        "load": load,
        "free_residual": np.abs(residual[free]).max(),
    }


def _loaded_end(V, u) -> np.ndarray:
    """Mean displacement of the dofs on the loaded end (y = 0)."""
    x = V.tabulate_dof_coordinates()
    on = np.isclose(x[:, 1], 0.0)
    return u.x.array.reshape(-1, 3)[on].mean(axis=0)


def castigliano() -> float:
    """The loaded end's displacement along the load by Castigliano's thin curved beam.

    A force ``F`` along the ring at its free end (angle 0) gives at angle ``phi`` the bending
    moment ``F R (1 - cos phi)``, the normal force ``F cos phi`` and the shear ``F sin phi``:
    ``delta = F R^3 (3 pi / 4 - 2) / (E I) + F R pi / 4 / (E A) + k F R pi / 4 / (G A)``.
    """
    R, h, t = (INNER + OUTER) / 2, OUTER - INNER, THICKNESS
    area, inertia = h * t, t * h**3 / 12
    force = PRESSURE * area
    shear = E / (2 * (1 + NU))
    return force * (
        R**3 * (3 * np.pi / 4 - 2) / (E * inertia)
        + R * np.pi / 4 / (E * area)
        + 1.2 * R * np.pi / 4 / (shear * area)
    )


def main(argv: list[str] | None = None) -> dict:
    """Run the demo; returns a summary (``skipped`` with the reason on dolfinx before 0.11)."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--coarse", action="store_true", help="small mesh (tests)")
    parser.add_argument("--quiet", action="store_true", help="no printout")
    parser.add_argument("--output", type=Path, default=Path("curved_prisms_output"))
    args = parser.parse_args(argv)
    say = (lambda *a: None) if args.quiet else print
    if compat.DOLFINX_VERSION < (0, 11):
        reason = (
            f"dolfinx {'.'.join(map(str, compat.DOLFINX_VERSION))} cannot run degree-2 spaces "
            "on prisms; this demo needs dolfinx 0.11 or later (docs/method.md §32.5, §40)"
        )
        say(reason)
        return {"passed": None, "skipped": reason}
    if MPI.COMM_WORLD.size > 1:
        raise SystemExit("curved_prisms.py runs on one process (its elimination is the serial one)")
    size, layers = (8.0, 2) if args.coarse else (4.0, 4)
    summary: dict = {"delta_castigliano": castigliano()}
    for incomplete, name in ((True, "15"), (False, "18")):
        start = time.perf_counter()
        mesh, _, faces = mesh_from_gmsh(
            build_ring, MPI.COMM_SELF, size=size, layers=layers, incomplete=incomplete
        )
        result = _solve(mesh, faces)
        end = _loaded_end(result["V"], result["u"])
        summary[f"cells_{name}"] = mesh.topology.index_map(3).size_local
        summary[f"dofs_{name}"] = result["u"].x.array.size
        summary[f"end_{name}"] = end
        summary[f"load_{name}"] = result["load"]
        summary[f"equilibrium_error_{name}"] = float(
            np.abs(result["reaction"] + result["load"]).max() / np.abs(result["load"]).max()
        )
        summary[f"seconds_{name}"] = time.perf_counter() - start
        if incomplete:
            u15, V15 = result["u"], result["V"]
    summary["delta"] = float(summary["end_15"][1])
    summary["ratio_castigliano"] = summary["delta"] / summary["delta_castigliano"]
    summary["difference_18"] = float(
        np.abs(summary["end_18"] - summary["end_15"]).max() / np.abs(summary["end_15"]).max()
    )
    summary["passed"] = bool(
        summary["equilibrium_error_15"] < 1e-9 and summary["equilibrium_error_18"] < 1e-9
    )
    say(
        f"{summary['cells_15']} prisms, {summary['dofs_15']} dofs: loaded end moves "
        f"{summary['delta']:.5g} mm along the load (Castigliano's thin beam "
        f"{summary['delta_castigliano']:.5g} mm, ratio {summary['ratio_castigliano']:.3f}); "
        f"18-node prisms differ by {summary['difference_18']:.2e}; reaction = load to "
        f"{summary['equilibrium_error_15']:.1e}"
    )

    # %%
    # The figure: the ring's mid-plane nodes before and after (displacement magnified).
    import matplotlib as mpl

    mpl.use("Agg")
    import matplotlib.pyplot as plt

    args.output.mkdir(parents=True, exist_ok=True)
    x = V15.tabulate_dof_coordinates()
    disp = u15.x.array.reshape(-1, 3)
    mid = np.isclose(x[:, 2], THICKNESS / 2) | np.isclose(x[:, 2], 0.0)
    scale = 0.1 * OUTER / np.abs(disp).max()
    fig, ax = plt.subplots(figsize=(5, 5))
    ax.plot(x[mid, 0], x[mid, 1], ".", color="0.7", markersize=3, label="undeformed")
    moved = x[mid, :2] + scale * disp[mid, :2]
    paint = ax.scatter(*moved.T, c=np.linalg.norm(disp[mid], axis=1), s=6, cmap="viridis")
    fig.colorbar(paint, ax=ax, label="|u| (mm)", shrink=0.8)
    ax.set_aspect("equal")
    ax.set_title(f"15-node prisms from gmsh, u x {scale:.0f}")
    ax.legend(loc="upper right")
    png = args.output / "curved_prisms.png"
    fig.savefig(png, dpi=120, bbox_inches="tight")
    plt.close(fig)
    summary["png"] = str(png)
    return summary


if __name__ == "__main__":
    summary = main()
    sys.exit(0 if summary["passed"] in (True, None) else 1)
