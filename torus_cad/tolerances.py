"""The tolerances, time limits, input limits and option ranges that two or more places read: modules
of the package, or a module and the tests or scripts that hold it to them (lengths in mm).

A constant that one module alone reads lives beside it, at module level with its unit and why (for
example the Frenet frame's curvature floor in torus_cad.geometry.blade.frames, the STEP read-back's
tolerances in torus_cad.kernel.readable_edges, the station table's limits in
torus_cad.geometry.blade.station_table, the simulation's levels, fluid and layers in
torus_cad.simulate.settings). The measurements behind the limits: the docs' measurements page.
"""

#: Relative tolerance of read-back comparisons (a STEP file read back keeps its volume to this).
READ_BACK_RELATIVE_TOLERANCE = 1e-6

#: Default STL linear deflection (mm) and angular deflection (rad).
STL_LINEAR_DEFLECTION = 0.05
STL_ANGULAR_DEFLECTION = 0.2

#: Thinnest blunt trailing edge (mm). A thinner base is narrower than the STL's chordal deviation,
#: so the triangles of its faces and of the surfaces beside it pass through each other: a
#: blunt edge is 0 (sharp) or at least this, and a coordinate file's thinner open edge is closed.
MIN_BLUNT_TRAILING_EDGE_MM = 0.05

#: Relative precision of the volume sanity check after the fuse (hub < fused <= hub + n blades);
#: the blades' overlap with the hub keeps the bounds far apart, so a coarse, fast integral suffices.
VOLUME_CHECK_RELATIVE_PRECISION = 1e-3

#: Largest allowed y_t * kappa_c of a cambered section (1 = the lower surface folds over);
#: kept below 1 so the surface keeps a usable radius of curvature.
FOLD_RATIO_LIMIT = 0.9

#: Angular margin (degrees) added at each side of a blade's footprint on the hub before the
#: seam is placed beside it.
HUB_FOOTPRINT_MARGIN_DEG = 1.0


# -- limits: inputs and work refused before they start ---------------------------------------------

#: Largest configuration file read (bytes): a design is a few hundred bytes. Only regular files are
#: read.
CONFIG_FILE_MAX_BYTES = 1 << 20

#: Longest value an error message quotes (characters): a longer one (a name, a path, a list) is cut
#: in its middle with ``...`` (torus_cad.errors.shown), so that a 900 k-character value gives a
#: line, not a megabyte.
MESSAGE_VALUE_MAX_CHARS = 80

#: Longest word (a run without spaces: a quoted value, a path) and longest whole message any
#: torus_cad error, and any ``torus-cad`` error line, may hold (characters); longer ones are cut in
#: their middle with ``...`` (torus_cad.errors.bounded_message). A word this long is far beyond any
#: real path or key.
MESSAGE_WORD_MAX_CHARS = 240
MESSAGE_MAX_CHARS = 2000

#: Largest JSON report ``torus-cad verify`` reads (bytes): a build's report is a few kB.
REPORT_FILE_MAX_BYTES = 16 << 20

#: Deepest nesting of lists and inline tables a TOML value may have (a design's deepest is a list of
#: numbers, depth 1); Python's TOML reader recurses once per level and fails near 300.
TOML_NESTING_LIMIT = 16

#: Largest airfoil coordinate file read (bytes): the UIUC database's files are a few kB.
AIRFOIL_FILE_MAX_BYTES = 2_000_000

#: Most points an airfoil coordinate file may hold: the database's files have tens to a few hundred;
#: the parsing and crossing checks of this many take well under a second
#: (scripts/bench_airfoil_file.py).
AIRFOIL_FILE_MAX_POINTS = 20_000

#: Largest STEP file ``torus-cad simulate --step`` reads (bytes): the default design's is about 1
#: MB.
STEP_FILE_MAX_BYTES = 64 << 20

#: Most triangles an STL may have, by the estimate made before tessellating
#: (torus_cad.geometry.analysis.triangle_estimate). OpenCascade's mesher slows down faster than its
#: triangle count grows on the lofted blades (see the README's "Limits").
STL_TRIANGLE_LIMIT = 2_000_000

#: Most trials one optimisation study may ask for (``[study] trials``, ``--trials``): at ~2 trials/s
#: per machine, days of work; the sampler's own cost grows with the number of trials.
MAX_STUDY_TRIALS = 100_000


#: Where the constant-radius root fillet fails and a blade face bends concavely (seen from outside)
#: along a junction edge tighter than the fillet radius / this fraction, a last round of tries gives
#: that edge the radius this fraction x the bend's radius (the other edges keep the requested one):
#: the ball then fits the bend (the bends are the design's own sections, measured against
#: the analytic surface).
REDUCED_FILLET_FRACTION = 0.5

#: Relative precision of the integration for the balance report (static imbalance, products of
#: inertia): coarser than the mass properties', as it integrates the solid a second time.
BALANCE_RELATIVE_PRECISION = 1e-4


#: Simulations: largest airspeed, m/s (Mach 0.3 in air at 15 C: compressibility stays under ~2 %).
SIMULATE_AIRSPEED_LIMIT_M_S = 100.0

#: Simulations: the most further halvings of the propeller's surface and edge cells that
#: ``--surface-refinement`` takes (each about triples the cells near the blade).
SIMULATE_MAX_SURFACE_REFINEMENT = 4


#: gmsh threads that give the same CFD mesh, byte for byte, on every run of one design: with more,
#: gmsh's parallel meshing orders its work differently from run to run, so the tetrahedra (and the
#: forces simulated on them) differ slightly between runs of the same design.
GMSH_REPRODUCIBLE_THREADS = 1

#: Largest CFD mesh ``torus-cad cfd`` starts, in tetrahedra (estimated from the settings before any
#: meshing, torus_cad.cfd_domain.estimate): about 2.6 GB and 13 times the default design's work, 33
#: minutes of one core at torus_cad.cfd_domain.estimate.TETS_PER_SECOND (measured: the docs'
#: measurements page). The estimate is of the propeller as built (design targets met) and within
#: torus_cad.cfd_domain.estimate.REAL_OVER_ESTIMATE of the real count.
CFD_TETRAHEDRA_LIMIT = 3_000_000

# -- the strict validity check (torus_cad.kernel.strict)
# ---------------------------------------------

#: Seconds the self-interference test (BRepAlgoAPI_Check, in its child process) may take before the
#: build is refused: the shipped examples take seconds (a fuzz design that took far longer: the
#: docs' measurements page).
STRICT_CHECK_TIME_LIMIT_S = 300.0

#: Largest distance (mm) of an STL or 3MF tessellation from its mesh repaired free of crossing
#: triangles by meshlib (torus_cad.kernel.uncrossed); a repair that moves it further is refused
#: (under a 0.4 mm nozzle's line; what repairs moved: the docs' measurements page).
MESH_REPAIR_MAX_DEVIATION_MM = 0.5

# -- the conventional (open-tip) blade (torus_cad.geometry.blade.station_table, .conventional_blade)
# ------

#: Most stations a table may have (UIUC: 18, APC: ~ 40).
STATION_MAX_ROWS = 2000

# -- command-line options: the range of each numeric option of every command
# (torus_cad.cli.options), ----- -- shown in its --help; a value outside is refused with one line,
# exit 2, before any folder is made --------

#: ``cfd --threads``: gmsh threads, at most this many per CPU the process may use and never more
#: than CFD_THREADS_LIMIT. libgomp sets up every thread's state at once (what huge counts did: the
#: docs' measurements page); gmsh's meshing gains nothing past one thread per CPU.
CFD_THREADS_PER_CPU = 4
CFD_THREADS_LIMIT = 256

#: ``sweep --workers`` and ``optimize --workers`` (also the size of a ``--scheduler local``
#: cluster): worker processes, at most this many per CPU and never more than WORKERS_LIMIT; each
#: imports the kernel (about 0.3 GB), so more only thrash the machine (sweep caps them at the CPUs
#: unless --oversubscribe).
WORKERS_PER_CPU = 4
WORKERS_LIMIT = 256

#: ``simulate --iterations``: SIMPLE iterations of one run (the levels' defaults are 200 / 300 /
#: 400).
SIMULATE_MAX_ITERATIONS = 20000

#: ``simulate --rpm`` and a study's ``[simulate] rpm``: at most this (rpm); the design's own limit,
#: helical tip Mach SIMULATE_TIP_MACH_LIMIT, is checked once the design is read (smaller for any
#: real one).
SIMULATE_RPM_LIMIT = 1.0e6

#: ``simulate --thrust``: at most this (N); the design's own ceiling (CT 1 at its rpm limit) is
#: checked once the design is read.
SIMULATE_THRUST_LIMIT_N = 1.0e6

#: ``simulate --time-limit``: the budget of one run (of the whole search with --thrust), s: a week.
SIMULATE_TIME_LIMIT_MAX_S = 7 * 86400.0

#: ``simulate --thrust-tolerance`` (a fraction of the target) and ``--thrust-runs`` (solver runs).
THRUST_TOLERANCE_RANGE = (0.001, 0.2)
THRUST_RUNS_RANGE = (1, 10)

#: ``sweep --time-limit``, a sweep's ``time_limit_s`` and a study's ``time_limit_s``: per design, s
#: (a day).
DESIGN_TIME_LIMIT_MAX_S = 86400.0

#: ``build --density``, ``sweep --density`` and a sweep's ``density_g_cm3``: the material density,
#: g/cm^3, in (0, this] (osmium, the densest element, is 22.6).
DENSITY_LIMIT_G_CM3 = 25.0

#: ``preview --size`` and ``build --preview-size``: each side of the picture, pixels.
PREVIEW_EDGE_RANGE = (64, 8000)

# -- intersection edges rebuilt from exact points (torus_cad.kernel.edge_curves)
# ---------------------

#: Most observers one simulate run takes (each costs about a second of noise evaluation).
NOISE_MAX_OBSERVERS = 32

# -- the root fillet's edges made to read back from STEP (torus_cad.kernel.readable_edges) ---------

#: simulate --solver vortex: rings across the chord and strips along the blade a run may ask for
#: (--chordwise, --spanwise), and the defaults (torus_cad.vortex.rotor.Discretisation; here so that
#: the command line's help names them without importing the solver).
VORTEX_CHORDWISE_RANGE = (2, 24)
VORTEX_SPANWISE_RANGE = (6, 120)
VORTEX_CHORDWISE_DEFAULT = 8
VORTEX_SPANWISE_DEFAULT = 30
