"""One blade in space: centerline, moving frames, section laws, the sampled surface, the trailing
edge, handedness, the conventional (station-table) blade and the propeller's kernel-free objects.
Imports the section and hub layers, never the analysis layer."""
