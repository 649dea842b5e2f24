"""Contact pairs, their pairing, the springs' assembly and the nonlinear problem."""
