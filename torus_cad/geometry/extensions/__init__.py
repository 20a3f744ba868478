"""Design extensions beside the spec's chapters (the modules one level up): coordinate-file airfoils,
blunt trailing edges, blade elements and the diameter / pitch fits, feasibility, mounting features,
printability, handedness and the STL's size estimate."""
