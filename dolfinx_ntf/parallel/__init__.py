"""MPI: collective errors, the node halo, and surfaces and constraints across processes.

Every function here that is marked *Collective* must be called by all processes of the mesh's
communicator in the same order (docs/method.md §14).
"""
