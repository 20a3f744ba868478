"""The hub: where the blades meet its cylinder and where its seam may go, the bore, set screw and
chamfer (mounting). Imports nothing else from :mod:`torus_cad.geometry` but the section layer."""
