"""Measurements and checks of a blade that is already described: feasibility, printability, blade
elements, pitch and diameter fits, the STL's size estimate. The top of the geometry layer."""
