"""Results of a contact solve: per-spring values, XDMF fields, reactions, contact force and area."""
