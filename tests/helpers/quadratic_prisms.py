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


#: Physical groups of the punch model: the two volumes and the contact and loaded faces.
BLOCK_VOLUME, PUNCH_VOLUME = 1, 2
BASE, MASTER, SLAVE, PUNCH_TOP = 11, 12, 21, 22


def _body(x0: float, y0: float, z0: float, dx: float, dy: float, dz: float, axis: str, n: int):
    """A box of prisms extruded along ``axis`` ("y" or "z") in ``n`` layers: its volume tag."""
    occ = gmsh.model.occ
    if axis == "z":
        surface = occ.addRectangle(x0, y0, z0, dx, dy)
        extruded = occ.extrude([(2, surface)], 0, 0, dz, numElements=[n], recombine=True)
    else:  # the rectangle in the x-z plane at y0 (rotated about x), extruded along y
        surface = occ.addRectangle(x0, z0, 0, dx, dz)
        occ.rotate([(2, surface)], 0, 0, 0, 1, 0, 0, np.pi / 2)
        occ.translate([(2, surface)], 0, y0, 0)
        extruded = occ.extrude([(2, surface)], 0, dy, 0, numElements=[n], recombine=True)
    return next(t for d, t in extruded if d == 3)


def build_prism_punch(
    *, incomplete: bool = True, axis: str = "y", punch: tuple = (0.6, 0.25, 0.85, 0.5)
) -> None:
    """A punch of second-order prisms on a block of them, in the current gmsh session.

    The block [0, 2] x [0, 1] x [0, 1] (mesh size 0.5, 3 layers along the axis), the punch
    ``[x0, x0 + dx] x [y0, y0 + dy] x [1, 1.5]`` (``punch = (x0, y0, dx, dy)``, size 0.3, 2
    layers) on its top, touching, the meshes not matching and no node shared. The prisms' axis
    is ``axis``: "y" puts quadrilaterals on the contact faces, "z" triangles. Groups: the
    volumes, the block's base and top (``MASTER``), the punch's bottom (``SLAVE``) and top.
    """
    gmsh.model.add("quadratic_prism_punch")
    x0, y0, dx, dy = punch
    block = _body(0, 0, 0, 2, 1, 1, axis, 3)
    punch_volume = _body(x0, y0, 1, dx, dy, 0.5, axis, 2)
    occ = gmsh.model.occ
    occ.synchronize()
    e = 1e-6
    for volume, size in ((block, 0.5), (punch_volume, 0.3)):
        points = gmsh.model.getBoundary([(3, volume)], recursive=True)
        gmsh.model.mesh.setSize(points, size)
    gmsh.model.addPhysicalGroup(3, [block], BLOCK_VOLUME)
    gmsh.model.addPhysicalGroup(3, [punch_volume], PUNCH_VOLUME)
    for volume, groups in (
        (
            block,
            {BASE: (-e, -e, -e, 2 + e, 1 + e, e), MASTER: (-e, -e, 1 - e, 2 + e, 1 + e, 1 + e)},
        ),
        (
            punch_volume,
            {
                SLAVE: (x0 - e, y0 - e, 1 - e, x0 + dx + e, y0 + dy + e, 1 + e),
                PUNCH_TOP: (x0 - e, y0 - e, 1.5 - e, x0 + dx + e, y0 + dy + e, 1.5 + e),
            },
        ),
    ):
        own = {t for _, t in gmsh.model.getBoundary([(3, volume)], oriented=False)}
        for tag, box in groups.items():
            found = [t for _, t in occ.getEntitiesInBoundingBox(*box, dim=2) if t in own]
            gmsh.model.addPhysicalGroup(2, found, tag)
    _second_order(incomplete)
    _snap_nodes()


def _snap_nodes(grid: float = 0.125) -> None:
    """Node coordinates within 1e-12 of a multiple of ``grid`` put on it (the rotation's 1e-16)."""
    tags, x, _ = gmsh.model.mesh.getNodes()
    x = x.reshape(-1, 3)
    snapped = np.round(x / grid) * grid
    near = np.abs(x - snapped) < 1e-12
    for k in np.flatnonzero(near.any(axis=1)):
        gmsh.model.mesh.setNode(int(tags[k]), np.where(near[k], snapped[k], x[k]).tolist(), [])
