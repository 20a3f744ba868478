"""Fluid domain and tetrahedral mesh for CFD (gmsh, the ``cfd`` extra): ``torus-cad cfd``."""
