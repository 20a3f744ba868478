"""The design's front door: from the validated parameters (:mod:`torus_cad.parameters`) to the
kernel-free geometry they describe and everything the kernel is handed.

``described_geometry`` makes the propeller the parameters describe (either kind),
``design_targets`` fits ``airfoil.naca``, ``diameter`` and ``pitch``, ``prepared_design`` runs every
step of the build before the kernel, ``design_checks`` is ``torus-cad check``, ``stl_budget``
refuses an STL too large.
"""
