"""gmsh models of second-order prisms and a linear elastic solve on C3D15's space (§40).

``build_prism_block`` meshes the block [0, 2] x [0, 1] x [0, 1] (a triangulated rectangle
extruded in 2 layers, 15- or 18-node prisms); ``build_prism_sector`` a quarter annulus
(radii 1 and 2, height 1) whose arcs make curved prisms. ``solve_wedge15`` solves small-strain
elasticity with ccx's 9 points, the face-centre constraints eliminated, nodal forces given.
"""

from __future__ import annotations

import gmsh
import numpy as np

import dolfinx.fem
import dolfinx.fem.petsc
import ufl

from dolfinx_ntf.fem.constraints import ConstraintElimination
from dolfinx_ntf.fem.serendipity_wedge import wedge15_metadata
from dolfinx_ntf.parallel.collectives import collectively
from dolfinx_ntf.parallel.global_constraints import distributed_elimination

#: Physical groups of the block: its volume and the faces z = 0, z = 1, x = 2, x = 0.
VOLUME, BOTTOM, TOP, END, START = 1, 11, 12, 13, 14
YOUNGS_MODULUS, POISSON = 210000.0, 0.3


def _second_order(incomplete: bool) -> None:
    """Second-order prisms: 15-node (``incomplete``) or 18-node."""
    gmsh.option.setNumber("Mesh.SecondOrderIncomplete", int(incomplete))
    gmsh.model.mesh.generate(3)
    gmsh.model.mesh.setOrder(2)


def _tag_faces(faces: dict[int, tuple[float, ...]]) -> None:
    """Physical groups of the surfaces inside each bounding box."""
    for tag, box in faces.items():
        found = gmsh.model.occ.getEntitiesInBoundingBox(*box, dim=2)
        gmsh.model.addPhysicalGroup(2, [t for _, t in found], tag)


def build_prism_block(*, incomplete: bool = True, size: float = 0.5) -> None:
    """The block [0, 2] x [0, 1] x [0, 1] of second-order prisms in the current gmsh session."""
    gmsh.model.add("quadratic_prism_block")
    occ = gmsh.model.occ
    surface = occ.addRectangle(0, 0, 0, 2, 1)
    volume = occ.extrude([(2, surface)], 0, 0, 1, numElements=[2], recombine=True)
    occ.synchronize()
    gmsh.model.addPhysicalGroup(3, [t for d, t in volume if d == 3], VOLUME)
    e = 1e-6
    _tag_faces(
        {
            BOTTOM: (-e, -e, -e, 2 + e, 1 + e, e),
            TOP: (-e, -e, 1 - e, 2 + e, 1 + e, 1 + e),
            END: (2 - e, -e, -e, 2 + e, 1 + e, 1 + e),
            START: (-e, -e, -e, e, 1 + e, 1 + e),
        }
    )
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    _second_order(incomplete)


def build_prism_sector(*, incomplete: bool = True, size: float = 0.35, layers: int = 2) -> None:
    """A quarter annulus (radii 1 and 2, height 1) of second-order prisms; faces tagged."""
    gmsh.model.add("quadratic_prism_sector")
    occ = gmsh.model.occ
    outer = occ.addDisk(0, 0, 0, 2, 2)
    inner = occ.addDisk(0, 0, 0, 1, 1)
    ring, _ = occ.cut([(2, outer)], [(2, inner)])
    quarter = occ.addRectangle(0, 0, 0, 3, 3)
    part, _ = occ.intersect(ring, [(2, quarter)])
    volume = occ.extrude(part, 0, 0, 1, numElements=[layers], recombine=True)
    occ.synchronize()
    gmsh.model.addPhysicalGroup(3, [t for d, t in volume if d == 3], VOLUME)
    e = 1e-6
    _tag_faces(
        {
            BOTTOM: (-e, -e, -e, 2 + e, 2 + e, e),
            TOP: (-e, -e, 1 - e, 2 + e, 2 + e, 1 + e),
            END: (-e, -e, -e, 2 + e, e, 1 + e),  # the cut face y = 0
            START: (-e, -e, -e, e, 2 + e, 1 + e),  # the cut face x = 0
        }
    )
    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    _second_order(incomplete)


def clamped_dofs(V: dolfinx.fem.FunctionSpace, where, constraints, component=None) -> np.ndarray:
    """Local block dofs where ``where(x)`` holds, without the constrained face centres."""
    if component is None:
        dofs = dolfinx.fem.locate_dofs_geometrical(V, where)
    else:
        sub, _ = V.sub(component).collapse()
        dofs = dolfinx.fem.locate_dofs_geometrical((V.sub(component), sub), where)[0]
    centres = np.unique(np.concatenate([c.nodes[:, 0] for c in constraints]))
    if component is None:
        return dofs[~np.isin(dofs, centres)]
    return dofs[~np.isin(dofs // 3, centres)]


def solve_wedge15(V, constraints, bcs, forces: dolfinx.fem.Function) -> dolfinx.fem.Function:
    """Small-strain elasticity on C3D15's space at ccx's 9 points under nodal ``forces``."""
    from petsc4py import PETSc

    mu = YOUNGS_MODULUS / (2 * (1 + POISSON))
    lam = YOUNGS_MODULUS * POISSON / ((1 + POISSON) * (1 - 2 * POISSON))
    u, v = ufl.TrialFunction(V), ufl.TestFunction(V)

    def eps(w):
        return ufl.sym(ufl.grad(w))

    sigma = lam * ufl.tr(eps(u)) * ufl.Identity(3) + 2 * mu * eps(u)
    dx = ufl.Measure("dx", domain=V.mesh, metadata=wedge15_metadata())
    a = dolfinx.fem.form(ufl.inner(sigma, eps(v)) * dx)
    A = dolfinx.fem.petsc.assemble_matrix(a, bcs=bcs)
    A.assemble()
    b = A.createVecLeft()
    owned = V.dofmap.index_map.size_local * 3
    b.array[:] = forces.x.array[:owned]
    dolfinx.fem.petsc.set_bc(b, bcs)
    prescribed = np.concatenate([bc.dof_indices()[0] for bc in bcs]).astype(np.int64)
    comm = V.mesh.comm
    if comm.size > 1:
        elimination = collectively(comm, distributed_elimination, V, constraints, prescribed)
    else:
        elimination = ConstraintElimination(b.getSize(), constraints, prescribed, comm)
    reduced = elimination.reduce_matrix(A, ("stiffness",))
    elimination.reduce_vector(b, lambda x: dolfinx.fem.petsc.set_bc(x, bcs))
    ksp = PETSc.KSP().create(comm)
    ksp.setOperators(reduced)
    ksp.setType("preonly")
    ksp.getPC().setType("lu")
    x = reduced.createVecRight()
    ksp.solve(b, x)
    elimination.back_substitute(x)
    out = dolfinx.fem.Function(V)
    out.x.array[:owned] = x.array
    out.x.scatter_forward()
    for obj in (ksp, x, b, A):
        obj.destroy()
    elimination.destroy()
    return out
