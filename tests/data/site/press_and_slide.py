"""A block pressed onto another, then slid with Coulomb friction: written from the site alone.

The pages used: the quick start (the skeleton), guide/surfaces (the two-box gmsh builder), guide/
friction (``SurfaceInteraction(law, Friction(mu, stick_slope))``, the stick slope ``K/100``),
guide/steps (an analysis of two ``AnalysisStep``\\ s run by ``run_steps``, ``Load`` ramping a
pressure and a prescribed displacement; ``residual_floor`` for a stiff penalty) and guide/outputs
(``contact_force``, ``reaction``, ``contact_results`` with ``shear`` and ``sliding``).

A steel block (0.5 x 0.5 x 0.25 mm) stands on a larger one (1 x 1 x 0.5 mm), clamped at its
bottom. Step 1 presses the small block with a pressure of 100 MPa on its top (one increment); step 2
keeps the pressure and drags its top 0.002 mm along x in ten fixed increments. Checks that can fail:
the normal contact force equals the pressure times the top's area, the tangential contact force
equals the reaction of the dragged top, and at the end of the drag every spring slips with
``|F_T| = mu F_N`` and the total tangential over normal force is mu.
Run: ``.venv/bin/python tests/data/site/press_and_slide.py`` (or under ``mpirun``).
"""

from mpi4py import MPI

import gmsh
import numpy as np

import dolfinx.fem
import ufl

import dolfinx_ntf as ntf
from dolfinx_ntf import compat
from dolfinx_ntf.meshes.gmsh_io import mesh_from_gmsh

E, nu = 210e3, 0.3  # MPa
MU = 0.3
PRESSURE = 100.0  # MPa on the small block's top
DRAG = 0.002  # mm along x, of the small block's top
LOWER, UPPER = 1, 2  # cell tags
BASE, MASTER, SLAVE, TOP = 11, 12, 13, 14  # facet tags


def build_blocks(size: float = 0.1) -> None:
    """A 0.5 x 0.5 x 0.25 block standing on a 1 x 1 x 0.5 one (touching at z = 0.5)."""
    lower = gmsh.model.occ.addBox(0, 0, 0, 1, 1, 0.5)
    upper = gmsh.model.occ.addBox(0.25, 0.25, 0.5, 0.5, 0.5, 0.25)
    gmsh.model.occ.synchronize()
    gmsh.model.addPhysicalGroup(3, [lower], LOWER)
    gmsh.model.addPhysicalGroup(3, [upper], UPPER)

    def at_height(volume: int, z: float) -> list[int]:
        return [
            s
            for _, s in gmsh.model.getBoundary([(3, volume)], oriented=False)
            if abs(gmsh.model.occ.getCenterOfMass(2, s)[2] - z) < 1e-9
        ]

    gmsh.model.addPhysicalGroup(2, at_height(lower, 0.0), BASE)
    gmsh.model.addPhysicalGroup(2, at_height(lower, 0.5), MASTER)
    gmsh.model.addPhysicalGroup(2, at_height(upper, 0.5), SLAVE)
    gmsh.model.addPhysicalGroup(2, at_height(upper, 0.75), TOP)
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.model.mesh.generate(3)


mesh, cell_tags, facet_tags = mesh_from_gmsh(build_blocks, MPI.COMM_WORLD, size=0.1)
V = compat.vector_space(mesh, "Lagrange", 1)
u, v = dolfinx.fem.Function(V), ufl.TestFunction(V)
pressure = dolfinx.fem.Constant(mesh, 0.0)
ds = ufl.Measure("ds", domain=mesh, subdomain_data=facet_tags)
n = ufl.FacetNormal(mesh)
F = ufl.inner(ntf.small_strain_stress(u, E, nu), ufl.grad(v)) * ufl.dx
F += pressure * ufl.inner(n, v) * ds(TOP)

# Base clamped; the top of the small block: u_x prescribed (the drag, 0 while pressing), u_y = 0.
Vx, _ = V.sub(0).collapse()
drag = dolfinx.fem.Function(Vx)
top_x = dolfinx.fem.locate_dofs_topological((V.sub(0), Vx), 2, facet_tags.find(TOP))
drag_bc = dolfinx.fem.dirichletbc(drag, top_x, V.sub(0))
base = dolfinx.fem.locate_dofs_topological(V, 2, facet_tags.find(BASE))
bcs = [
    dolfinx.fem.dirichletbc(np.zeros(3), base, V),
    drag_bc,
    ntf.component_bc(V, 1, facet_tags.find(TOP)),
]

law = ntf.LinearLaw.with_ccx_defaults(youngs_modulus=E)
friction = ntf.SurfaceInteraction(law, ntf.Friction(mu=MU, stick_slope=law.slope / 100))
pair = ntf.ContactPair(
    slave=ntf.FacetSurface(facet_tags, SLAVE),
    master=ntf.FacetSurface(facet_tags, MASTER),
    interaction=friction,
    name="slide",
)
problem = ntf.ContactProblem(F, u, [pair], bcs)

history = []  # (drag, F_x, F_z, springs sliding) after each increment of the slide


def record(result: ntf.IncrementResult) -> None:
    force = ntf.contact_force(problem, "slide")
    sliding = sum(mesh.comm.allgather(int(ntf.contact_results(problem)[0].sliding.sum())))
    history.append((DRAG * result.time, force[0], force[2], sliding))


load = PRESSURE * 0.5 * 0.5
# K = 50 E: the round-off of a spring force (about 1e-16 K A |x|, 5e-12 N here) exceeds 1e-10 of the
# average element force (0.02 N): residuals below 1e-9 of the load count as zero (guide/steps).
with ntf.ContactNewtonSolver(mesh.comm, problem, residual_floor=1e-9 * load) as solver:
    steps = [
        ntf.AnalysisStep(loads=[ntf.Load(pressure, PRESSURE)]),
        ntf.AnalysisStep(
            ntf.StaticStep(lambda t: None, initial_increment=0.1, fixed=True, on_increment=record),
            loads=[ntf.Load(drag, DRAG)],
        ),
    ]
    ntf.run_steps(solver, steps)

force = ntf.contact_force(problem, "slide")
top_reaction = ntf.reaction(problem, dofs=drag_bc)
res = ntf.contact_results(problem)[0]
shear = np.linalg.norm(res.shear, axis=1)
slip_error = np.abs(shear - MU * res.pressure)[res.sliding].max(initial=0.0)
slip_error = mesh.comm.allreduce(float(slip_error), op=MPI.MAX) / (MU * PRESSURE)
springs = mesh.comm.allreduce(res.node.size)
sliding = mesh.comm.allreduce(int(res.sliding.sum()))

if mesh.comm.rank == 0:
    print(f"{V.dofmap.index_map.size_global * 3} dofs, {springs} springs")
    print(f"{'drag [mm]':>10} {'F_x [N]':>10} {'F_z [N]':>10} {'|F_x|/F_z':>9} {'sliding':>7}")
    for d, fx, fz, n_sliding in history:
        print(f"{d:>10.4f} {fx:>10.4f} {fz:>10.4f} {abs(fx) / fz:>9.5f} {n_sliding:>7}")
    print(f"load p A = {load:g} N; reaction of the dragged top in x {top_reaction[0]:.6g} N")
    print(f"max | |F_T|/A - mu p | over sliding springs: {slip_error:.1e} of mu p")

assert abs(force[2] / load - 1) < 1e-8  # the normal force carries the pressure
assert abs(top_reaction[0] + force[0]) < 1e-8 * load  # the top holds what the contact drags
assert sliding == springs and slip_error < 1e-10  # all slip, on the Coulomb cone
assert abs(abs(force[0]) / force[2] - MU) < 1e-3 * MU  # F_T / F_N = mu in slip
assert abs(history[0][1]) / history[0][2] < MU  # the first increment of the drag still sticks
if mesh.comm.rank == 0:
    print("checks passed")
