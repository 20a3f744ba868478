"""The lifting-surface vortex solver (``torus-cad simulate --solver vortex``): the lattice on the
blade's camber surface and its helical wake, the steady solve, the section polars, the performance
report, the loading along the blade and the noise's surface (numpy / scipy, no kernel)."""
