"""Pure numpy kernels: the mathematics of node-to-face contact, free of dolfinx, MPI and PETSc.

Laws, master faces, projections, spring areas, the pairing search, the springs' forces and
tangents, friction, tie frames and rigid master surfaces. Every function works on arrays of all
springs at once and is tested against closed forms and finite differences without a mesh. The
layer check (``scripts/check_layers.py``) keeps dolfinx, ufl, mpi4py and petsc4py out of it.
"""
