"""What a build leaves on disk: output sets that appear whole or not at all (``output_set``), the
JSON report (``report``), the blade-element table (``sections_table``) and the designer's targets
measured on the built solid (``measured_targets``). The files themselves are written by
``torus_cad.kernel.writers``."""
