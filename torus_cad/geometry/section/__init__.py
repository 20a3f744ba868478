"""The 2-D section in chord units: NACA 4- and 5-digit airfoils, coordinate files, arc-length
resampling, the B-spline fit of a sampled section. Imports nothing else from
:mod:`torus_cad.geometry`."""
