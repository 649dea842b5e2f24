"""Node-to-face penalty contact for dolfinx, reproducing CalculiX 2.20 node-to-surface contact."""
