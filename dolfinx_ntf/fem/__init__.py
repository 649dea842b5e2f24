"""dolfinx glue: contact surfaces, linear constraints, elasticity and continuum forms in UFL.

Thin layer between the numpy kernels and dolfinx: it turns meshes, tags and function spaces into
the arrays the kernels take. Nothing here communicates beyond what dolfinx itself does.
"""
