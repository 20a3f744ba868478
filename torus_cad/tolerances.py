"""The tolerances, time limits, input limits and option ranges that several modules share or that a user
meets (lengths in mm).

A constant that belongs to one algorithm stays beside it, at module level with its unit: the geometry
checks' limits (torus_cad.geometry.analysis.feasibility), the parameters' ranges
(torus_cad.parameters.design), the STL budget's sampling (torus_cad.parameters.stl_budget), the surface
mesh's memory budget and crossing check (torus_cad.mesh.resolution, torus_cad.mesh.crossings), the CFD
domain's sizes and its estimate (torus_cad.cfd.sizes, torus_cad.cfd.estimate), the simulation's levels,
fluid and layers (torus_cad.simulate.settings), and the optimiser's storage timings
(torus_cad.optimize.storage). The measurements behind the limits: the docs' measurements page.
"""

#: Curvature |T'(s)| / |C'(s)| below which the Frenet normal counts as undefined (1/mm).
FRENET_MIN_CURVATURE = 1e-6

#: Samples on s in [0, 1] used to scan the centerline for vanishing curvature, flips of N,
#: and to step the rotation-minimising frame.
FRAME_SCAN_SAMPLES = 401

#: Fine grid of the arc-length table, both surfaces together (spec §5.2: n_fine, whose default
#: is 1000); 4000 keeps the spacing even for strongly cambered sections (cost and spacing measured:
#: the docs' measurements page).
ARC_LENGTH_FINE_SAMPLES = 4000

#: Gauss-Legendre nodes per interval of the arc-length table (torus_cad.geometry.section.arc_length): 10 keep
#: the table within 1.1e-11 chord of adaptive Gauss-Kronrod quadrature at ARC_LENGTH_QUAD_ABS on
#: coordinate files (2e-16 on NACA sections), where 5 leave 1.3e-10 (tests/test_arc_length.py).
ARC_LENGTH_GAUSS_POINTS = 10

#: Absolute tolerance of the arc-length quadrature of |f'(t)| (chord units): the table agrees within it
#: with QUADPACK's adaptive Gauss-Kronrod quadrature run to it (tests/test_arc_length.py).
ARC_LENGTH_QUAD_ABS = 1e-10


#: Relative tolerance of read-back comparisons (a STEP file read back keeps its volume to this).
READ_BACK_RELATIVE_TOLERANCE = 1e-6

#: Default STL linear deflection (mm) and angular deflection (rad).
STL_LINEAR_DEFLECTION = 0.05
STL_ANGULAR_DEFLECTION = 0.2

#: Thinnest blunt trailing edge (mm). A thinner base is narrower than the STL's chordal deviation,
#: so the triangles of its faces and of the surfaces beside it pass through each other: a
#: blunt edge is 0 (sharp) or at least this, and a coordinate file's thinner open edge is closed.
MIN_BLUNT_TRAILING_EDGE_MM = 0.05

#: Largest allowed deviation of a section's B-spline from its sampled points, as a fraction
#: of the section's chord. Interior knots are doubled until every section meets it.
WIRE_FIT_RELATIVE_TOLERANCE = 2e-4

#: Interior knots of the first section fit; doubled while the fit is too coarse (at most the maximum).
WIRE_FIT_INITIAL_KNOTS = 24
WIRE_FIT_MAXIMUM_KNOTS = 384

#: Precision of the loft (BRepOffsetAPI_ThruSections pres3d), mm.
LOFT_PRECISION = 1e-6

#: Relative precision of OpenCascade's adaptive volume / inertia integration (BRepGProp eps).
#: cadquery's Shape.Volume() integrates without it and is off by ~2 % on lofted blades.
MASS_PROPERTIES_RELATIVE_PRECISION = 1e-6

#: Relative precision of the volume sanity check after the fuse (hub < fused <= hub + n blades);
#: the blades' overlap with the hub keeps the bounds far apart, so a coarse, fast integral suffices.
VOLUME_CHECK_RELATIVE_PRECISION = 1e-3

#: Analytic surface points must lie on the B-rep within this fraction of the local chord.
SURFACE_ACCURACY_RELATIVE = 1e-3

#: Largest allowed y_t * kappa_c of a cambered section (1 = the lower surface folds over);
#: kept below 1 so the surface keeps a usable radius of curvature.
FOLD_RATIO_LIMIT = 0.9

#: Sections whose nearest point is within this fraction of the hub radius count as meeting
#: the hub when the kernel looks for a place for the hub's seam (geometry.hub).
HUB_FOOTPRINT_NEAR_RELATIVE = 0.02

#: Angular margin (degrees) added at each side of a blade's footprint on the hub before the
#: seam is placed beside it.
HUB_FOOTPRINT_MARGIN_DEG = 1.0


# -- limits: inputs and work refused before they start ---------------------------------------------

#: Largest configuration file read (bytes): a design is a few hundred bytes. Only regular files are read.
CONFIG_FILE_MAX_BYTES = 1 << 20

#: Longest value an error message quotes (characters): a longer one (a name, a path, a list) is cut in its
#: middle with ``...`` (torus_cad.errors.shown), so that a 900 k-character value gives a line, not a megabyte.
MESSAGE_VALUE_MAX_CHARS = 80

#: Longest word (a run without spaces: a quoted value, a path) and longest whole message any torus_cad
#: error, and any ``torus-cad`` error line, may hold (characters); longer ones are cut in their middle with
#: ``...`` (torus_cad.errors.bounded_message). A word this long is far beyond any real path or key.
MESSAGE_WORD_MAX_CHARS = 240
MESSAGE_MAX_CHARS = 2000

#: Largest JSON report ``torus-cad verify`` reads (bytes): a build's report is a few kB.
REPORT_FILE_MAX_BYTES = 16 << 20

#: Deepest nesting of lists and inline tables a TOML value may have (a design's deepest is a list of
#: numbers, depth 1); Python's TOML reader recurses once per level and fails near 300.
TOML_NESTING_LIMIT = 16

#: Most digits one number in a TOML file may have (Python refuses integers of more than 4300).
TOML_NUMBER_DIGITS_LIMIT = 400

#: Largest airfoil coordinate file read (bytes): the UIUC database's files are a few kB.
AIRFOIL_FILE_MAX_BYTES = 2_000_000

#: Most points an airfoil coordinate file may hold: the database's files have tens to a few hundred;
#: the parsing and crossing checks of this many take well under a second (scripts/bench_airfoil_file.py).
AIRFOIL_FILE_MAX_POINTS = 20_000

#: Largest STEP file ``torus-cad simulate --step`` reads (bytes): the default design's is about 1 MB.
STEP_FILE_MAX_BYTES = 64 << 20

#: Seconds the parsing and checks of one airfoil coordinate file may take before it is refused.
AIRFOIL_FILE_TIME_LIMIT_S = 10.0

#: Largest magnitude of a coordinate in an airfoil file (any length unit: the section is scaled to
#: chord units); larger values overflow the chord and area computations.
AIRFOIL_COORDINATE_LIMIT = 1e6

#: Most triangles an STL may have, by the estimate made before tessellating
#: (torus_cad.geometry.analysis.triangle_estimate). OpenCascade's mesher slows down faster than its
#: triangle count grows on the lofted blades (see the README's "Limits").
STL_TRIANGLE_LIMIT = 2_000_000

#: A writer that fails while its file system has less free space than this (bytes) failed for
#: lack of space: OpenCascade's writers report only that they could not write.
DISK_FULL_FREE_BYTES = 1 << 20

#: Most designs one sweep may hold (grid product or samples), checked from the axis sizes before
#: any design is generated. Beyond it the design list and table alone take gigabytes, and at
#: ~2 designs/s per machine the sweep would run for weeks.
MAX_SWEEP_DESIGNS = 1_000_000

#: Most trials one optimisation study may ask for (``[study] trials``, ``--trials``): at ~2 trials/s
#: per machine, days of work; the sampler's own cost grows with the number of trials.
MAX_STUDY_TRIALS = 100_000

#: Smallest gap (mm) the hub's mounting features (bore, chamfer, set-screw hole) must keep from
#: any sampled blade point; covers the blade surface between its samples.
MOUNTING_CLEARANCE_MM = 0.05

#: Pieces the blade's airfoil face is split into (in equal ranges of its section curves' parameter)
#: for the root fillet when the trailing edge is round (torus_cad.kernel.wires): the airfoil face is
#: then open, so the fillet's split of closed side faces does not apply. Fifths (split points at 20,
#: 40, 60, 80 % of the way from the lower to the upper end, none at the leading edge, near 50 %) fillet
#: round edges that fewer pieces do not (measured: the docs' measurements page).
ROUND_EDGE_FILLET_PIECES = 5

#: Seconds the root fillet may take (in its child process) before it counts as failed.
FILLET_TIME_LIMIT_S = 60.0

#: Seconds each of the root fillet's further tries (after the first, which has
#: FILLET_TIME_LIMIT_S) may take in its child: the tries that save a design take under a second,
#: the ones that fail either fail as fast or hang until their limit (``scripts/fillet_rate.py``).
FILLET_RETRY_TIME_LIMIT_S = 15.0

#: Seconds the root fillet's further tries together may take (counted from the end of the first);
#: when it runs out, the remaining tries are skipped and the fillet fails. With the first try and
#: the search for a smaller radius to suggest (up to 3 children of FILLET_TIME_LIMIT_S), a failing
#: fillet takes at most about 60 + 60 + 3 x 60 s.
FILLET_TRIES_TIME_LIMIT_S = 60.0

#: Where the constant-radius root fillet fails and a blade face bends concavely (seen from outside)
#: along a junction edge tighter than the fillet radius / this fraction, a last round of tries gives
#: that edge the radius this fraction x the bend's radius (the other edges keep the requested one):
#: the ball then fits the bend (the bends are the design's own sections, measured against
#: the analytic surface).
REDUCED_FILLET_FRACTION = 0.5

#: Points per junction edge at which the blade face's bend is measured for the reduced fillet.
REDUCED_FILLET_SAMPLES = 40

#: A root-fillet edge whose 3D curve leaves a face's p-curve by more than its tolerance (as
#: BOPAlgo_ArgumentAnalyzer measures; 1.4e-4 mm against 1e-4 mm on workshop_fillet) gets this many
#: times that deviation as tolerance (torus_cad.kernel.fillet_continuity).
FILLET_EDGE_TOLERANCE_MARGIN = 1.1

#: A repaired root fillet (ShapeFix) is accepted only if it adds at most this many r^2 of volume
#: per mm of junction: a rolling-ball fillet between faces meeting at 30 degrees adds 2.4 r^2,
#: at 90 degrees 0.21 r^2 (what repaired fillets add: the docs' measurements page).
REPAIRED_FILLET_MAX_AREA_RADII2 = 4.0

#: Relative precision of the integration for the balance report (static imbalance, products of
#: inertia): coarser than the mass properties', as it integrates the solid a second time.
BALANCE_RELATIVE_PRECISION = 1e-4

#: Surface meshes (torus_cad.mesh): largest sag of the flat faces from the analytic blade, as a
#: fraction of the local section thickness, above which a resolution is refused. The default design
#: needs 15 sections (any allowed points); a 6 % thick section needs 31 points (its leading edge).
MESH_SAG_LIMIT = 0.10


#: Surface meshes: triangles with every corner at least this fraction of the hub radius outside
#: the hub count as "away from the junctions" in the quality report.
MESH_JUNCTION_MARGIN_RELATIVE = 0.05

#: Surface meshes: at the blade-hub junctions, a triangle edge shorter than this fraction of its
#: triangle's longest edge is a needle the cleanup collapses (torus_cad.mesh.cleanup).
MESH_NEEDLE_EDGE_RATIO = 0.1

#: Simulations (torus_cad.simulate): the incompressible solver is trusted up to this helical tip
#: Mach number (tip speed with the airspeed, over the speed of sound); faster rpm are refused.
SIMULATE_TIP_MACH_LIMIT = 0.6

#: Simulations: largest airspeed, m/s (Mach 0.3 in air at 15 C: compressibility stays under ~2 %).
SIMULATE_AIRSPEED_LIMIT_M_S = 100.0

#: Simulations: the most further halvings of the propeller's surface and edge cells that
#: ``--surface-refinement`` takes (each about triples the cells near the blade).
SIMULATE_MAX_SURFACE_REFINEMENT = 4

#: Simulations: an initial residual above this, or any non-finite residual or force, is divergence.
SIMULATE_DIVERGENCE_RESIDUAL = 1e3

#: Simulations: a run counts as converged when thrust and torque vary by at most this fraction of
#: their mean over the last 10 % of its iterations.
SIMULATE_CONVERGED_VARIATION = 0.02

#: gmsh threads that give the same CFD mesh, byte for byte, on every run of one design: with more,
#: gmsh's parallel meshing orders its work differently from run to run, so the tetrahedra (and the
#: forces simulated on them) differ slightly between runs of the same design.
GMSH_REPRODUCIBLE_THREADS = 1

#: Largest CFD mesh ``torus-cad cfd`` starts, in tetrahedra (estimated from the settings before any
#: meshing, torus_cad.cfd.estimate): about 2.6 GB and 13 times the default design's work, 33 minutes of one
#: core at torus_cad.cfd.estimate.TETS_PER_SECOND (measured: the docs' measurements page). The estimate is of
#: the propeller as built (design targets met) and within torus_cad.cfd.estimate.REAL_OVER_ESTIMATE of the real count.
CFD_TETRAHEDRA_LIMIT = 3_000_000

# -- the strict validity check (torus_cad.kernel.strict) ---------------------------------------------

#: Two blade copies closer than this (mm) count as interfering (their faces' tolerances are ~1e-7 mm).
STRICT_BLADE_SEPARATION_MM = 1e-4
#: Seconds the self-interference test (BRepAlgoAPI_Check, in its child process) may take before the
#: build is refused: the shipped examples take seconds (a fuzz design that took far longer: the docs'
#: measurements page).
STRICT_CHECK_TIME_LIMIT_S = 300.0
#: Longest wait (s) for the B-rep that ``torus-cad mesh`` compares its mesh with (built in a child
#: beside the mesh): a build, its strict check (STRICT_CHECK_TIME_LIMIT_S) included, and one tessellation.
MESH_COMPARISON_TIME_LIMIT_S = 900.0
#: Longest wait (s) for the blade-element table (CSV and PNG), drawn in a child beside the build's files.
SECTIONS_TABLE_TIME_LIMIT_S = 120.0
#: Longest wait (s) for the STEP file, written and read back in a child beside the STL: the default's
#: takes under a second, and its read-back check leaves out the costly self-interference test.
STEP_WRITE_TIME_LIMIT_S = 900.0

#: Axis directions and positions within this of the z axis (unit vector components, mm) count as on it.
STRICT_AXIS_TOLERANCE = 1e-9

#: Largest distance (mm) of an STL or 3MF tessellation from its mesh repaired free of crossing
#: triangles by meshlib (torus_cad.kernel.uncrossed); a repair that moves it further is refused
#: (under a 0.4 mm nozzle's line; what repairs moved: the docs' measurements page).
MESH_REPAIR_MAX_DEVIATION_MM = 0.5
#: A repair that would move the tessellation further is tried again on a finer one: the linear
#: deflection halved, at most this many times (a user's coarse deflection crosses far: the docs'
#: measurements page).
MESH_REFINE_HALVINGS = 3
#: meshlib's SelfIntersections.fix passes tried in turn on a crossing tessellation, each on the last
#: one's result, until no triangle crosses.
MESH_REPAIR_PASSES = ("Relax", "Relax", "Relax", "CutAndFill", "Relax", "CutAndFill")
#: Tessellation nodes closer than this (mm) are one vertex of the written mesh (the faces store their
#: shared boundary nodes each in its own placement, equal to the last bits).
MESH_MERGE_DISTANCE_MM = 1e-6

# -- the conventional (open-tip) blade (torus_cad.geometry.blade.station_table, .conventional_blade) ------

#: Largest station file (a UIUC geometry file is < 1 kB, an APC PE0 file with its performance tables ~ 100 kB).
STATION_FILE_MAX_BYTES = 1_000_000
#: Most stations a table may have (UIUC: 18, APC: ~ 40).
STATION_MAX_ROWS = 2000
#: Allowed local pitch angle beta of a station (deg): a propeller blade's sections, not a feathered one.
STATION_BETA_LIMIT_DEG = 85.0
#: Largest chord of a station as a fraction of the tip radius (c/R; real propellers: < 0.4).
STATION_MAX_CHORD_OVER_R = 2.0
#: Largest propeller radius an APC PE0 file may give (inches; 100 in = 5 m across).
STATION_MAX_RADIUS_IN = 100.0
#: Largest |sweep| of a station's leading edge as a fraction of the tip radius.
STATION_MAX_SWEEP_OVER_R = 2.0
#: The root section of a conventional blade sits at this fraction of the hub's radius (well inside the
#: hub, so that the hub swallows the root's blend); the stations below the table's first one are blended
#: down to it.
CONVENTIONAL_ROOT_RADIUS_FRACTION = 0.5
#: The blended root section fits inside this fraction of the hub's half-width and half-length.
CONVENTIONAL_ROOT_FIT_MARGIN = 0.8
#: Share of sine clustering in the conventional blade's section radii (0: uniform in r; 1: a quarter
#: sine, sections densest at the tip).
CONVENTIONAL_TIP_CLUSTERING = 0.6

# -- command-line options: the range of each numeric option of every command (torus_cad.cli.options), -----
# -- shown in its --help; a value outside is refused with one line, exit 2, before any folder is made --------

#: ``cfd --threads``: gmsh threads, at most this many per CPU the process may use and never more than
#: CFD_THREADS_LIMIT. libgomp sets up every thread's state at once (what huge counts did: the docs'
#: measurements page); gmsh's meshing gains nothing past one thread per CPU.
CFD_THREADS_PER_CPU = 4
CFD_THREADS_LIMIT = 256

#: ``sweep --workers`` and ``optimize --workers`` (also the size of a ``--scheduler local`` cluster): worker
#: processes, at most this many per CPU and never more than WORKERS_LIMIT; each imports the kernel
#: (about 0.3 GB), so more only thrash the machine (sweep caps them at the CPUs unless --oversubscribe).
WORKERS_PER_CPU = 4
WORKERS_LIMIT = 256

#: ``simulate --iterations``: SIMPLE iterations of one run (the levels' defaults are 200 / 300 / 400).
SIMULATE_MAX_ITERATIONS = 20000

#: ``simulate --rpm`` and a study's ``[simulate] rpm``: at most this (rpm); the design's own limit,
#: helical tip Mach SIMULATE_TIP_MACH_LIMIT, is checked once the design is read (smaller for any real one).
SIMULATE_RPM_LIMIT = 1.0e6

#: ``simulate --thrust``: at most this (N); the design's own ceiling (CT 1 at its rpm limit) is checked
#: once the design is read.
SIMULATE_THRUST_LIMIT_N = 1.0e6

#: ``simulate --time-limit``: the budget of one run (of the whole search with --thrust), s: a week.
SIMULATE_TIME_LIMIT_MAX_S = 7 * 86400.0

#: ``simulate --thrust-tolerance`` (a fraction of the target) and ``--thrust-runs`` (solver runs).
THRUST_TOLERANCE_RANGE = (0.001, 0.2)
THRUST_RUNS_RANGE = (1, 10)

#: ``sweep --time-limit``, a sweep's ``time_limit_s`` and a study's ``time_limit_s``: per design, s (a day).
DESIGN_TIME_LIMIT_MAX_S = 86400.0

#: ``build --density``, ``sweep --density`` and a sweep's ``density_g_cm3``: the material density, g/cm^3,
#: in (0, this] (osmium, the densest element, is 22.6).
DENSITY_LIMIT_G_CM3 = 25.0

#: ``preview --size`` and ``build --preview-size``: each side of the picture, pixels.
PREVIEW_EDGE_RANGE = (64, 8000)

# -- intersection edges rebuilt from exact points (torus_cad.kernel.edge_curves) ---------------------

#: An intersection edge whose 3D curve and p-curves part by more than this (mm) is rebuilt: half of
#: what OpenCascade's STEP reader gives an edge at least (Precision::Confusion, 1e-7 mm), since a STEP
#: file carries no tolerance per edge (torus_cad.kernel.step_readback).
EDGE_CURVE_REFIT_ABOVE_MM = 5e-8
#: The rebuilt curves are refined until, half way between their points, they part by at most this (mm).
EDGE_CURVE_FIT_MM = 2e-8
#: ... and then until OpenCascade's own measure (GeomLib_CheckCurveOnSurface) finds them parting by at
#: most this (mm), below EDGE_CURVE_REFIT_ABOVE_MM and 2.5 times below the reader's 1e-7 mm.
EDGE_CURVE_ACCEPT_MM = 4e-8
#: Most points one rebuilt edge may need (the default's worst edge needs a few hundred); beyond, it is kept.
EDGE_CURVE_MAX_POINTS = 4000
#: Newton steps for one intersection point (it converges in 2-4 from the boolean's curves).
EDGE_CURVE_NEWTON_STEPS = 12
#: An exact intersection point farther than this many edge tolerances from the boolean's curve is
#: another branch of the intersection (or surfaces that touch): the edge keeps its curves.
EDGE_CURVE_REACH_TOLERANCES = 10.0
#: Times a point is added where OpenCascade's measure finds the rebuilt curves parting most, after the
#: half-way refinement (the interpolating spline can part between the half-way points).
EDGE_CURVE_WORST_POINT_ROUNDS = 20

#: simulate --observer: an observer's distance from the hub, m (open below, closed above). It must also lie
#: outside the blade tips' circle (torus_cad.acoustics.observers.check_observers).
NOISE_OBSERVER_DISTANCE_M = (0.0, 1.0e4)
#: Most observers one simulate run takes (each costs about a second of noise evaluation).
NOISE_MAX_OBSERVERS = 32

# -- the root fillet's edges made to read back from STEP (torus_cad.kernel.readable_edges) ---------

#: The least tolerance OpenCascade's STEP reader gives an edge (Precision::Confusion, mm): an edge whose
#: curves part by no more than this reads back valid whatever they do.
READBACK_MIN_TOLERANCE_MM = 1e-7
#: The reader samples an edge's curves at this many points at equal parameters, ends included
#: (ShapeAnalysis_Edge::CheckSameParameter's 23) ...
READBACK_SAMPLES = 23
#: ... and gives the edge the largest distance times this (BRepLib_ValidateEdge).
READBACK_TOLERANCE_FACTOR = 1.00001
#: A p-curve rebuilt from the feet of perpendiculars misses them, half way between its points, by at
#: most this (mm) or this fraction of the largest gap between the 3D curve and the surface, whichever
#: is larger: a miss along the curve of e moves the reader's projection of an end point, and the
#: largest distance it reads, by about e^2 / gap, well within its factor of 1.00001.
READBACK_PCURVE_FIT_MM = 1e-9
READBACK_PCURVE_FIT_GAP = 1e-3
#: Rounds of knots added where the rebuilt p-curve misses; beyond, the p-curve is kept.
READBACK_PCURVE_FIT_ROUNDS = 10
#: After those rounds, the closest fit is taken if it misses the feet by no more than this (mm): still
#: square to well within the reader's least tolerance (a 3D curve moved onto its vertices can leave
#: feet whose refinement stalls near 1e-9 mm).
READBACK_PCURVE_FIT_LOOSE_MM = 1e-8
#: An edge's 3D curve ending farther than this from its vertex (mm; the vertex's tolerance covers it in
#: memory) is moved to end on it: the reader closes the gap its p-curves then leave on a face by bending
#: them, its neighbour's too, whose edge may have no tolerance for it.
READBACK_VERTEX_GAP_MM = 1e-9
#: Points at equal parameters on which the largest distance between an edge's curves is looked for
#: before refining (GeomLib_CheckCurveOnSurface's own can be a fraction of a percent off next to an end).
READBACK_WORST_SAMPLES = 129
#: A split edge's pieces are moved this far (mm) from their face at the split, so that their largest
#: distance is there by more than the evaluation's rounding (about 1e-12 mm): a 1.1e-7 mm gap is within
#: the reader's factor of 1.00001 of it.
READBACK_SPLIT_MARGIN_MM = 1e-10

#: simulate --solver vortex: rings across the chord and strips along the blade a run may ask for (--chordwise,
#: --spanwise), and the defaults (torus_cad.vortex.rotor.Discretisation; here so that the command line's help
#: names them without importing the solver).
VORTEX_CHORDWISE_RANGE = (2, 24)
VORTEX_SPANWISE_RANGE = (6, 120)
VORTEX_CHORDWISE_DEFAULT = 8
VORTEX_SPANWISE_DEFAULT = 30
