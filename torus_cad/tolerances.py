"""Every numerical tolerance of the package, in one place (lengths in mm)."""

#: Curvature |T'(s)| / |C'(s)| below which the Frenet normal counts as undefined (1/mm).
FRENET_MIN_CURVATURE = 1e-6

#: Number of samples used to scan a quartic or a curve for sign changes / vanishing curvature.
SCAN_SAMPLES = 2001

#: Fine grid of the arc-length table (spec §5.2: n_fine, default 1000).
ARC_LENGTH_FINE_SAMPLES = 1000

#: Absolute tolerance of the adaptive quadrature of |f'(t)| (chord units).
ARC_LENGTH_QUAD_ABS = 1e-10

#: Tolerance (mm) for fitting B-spline wires through section points.
WIRE_FIT_TOLERANCE = 1e-4

#: Tolerance (mm) of the STEP / B-rep validity and read-back comparisons.
MODEL_TOLERANCE = 1e-6

#: Default STL linear deflection (mm) and angular deflection (rad).
STL_LINEAR_DEFLECTION = 0.05
STL_ANGULAR_DEFLECTION = 0.2
