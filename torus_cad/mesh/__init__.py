"""Surface meshes straight from the spec's math (§5, §6.2, §7): ``torus-cad mesh``."""
