"""Tonal noise of a propeller from its steady blade loading: the Ffowcs Williams-Hawkings equation
in Farassat's formulation 1A on the rotating blade surface (:mod:`.fwh`), observers
(:mod:`.observers`), SPL per harmonic, overall and A-weighted levels (:mod:`.spectrum`), a finished
simulation's surface pressure (:mod:`.surface`) and the report and picture of ``torus-cad simulate``
(:mod:`.report`). Pure numpy apart from the VTK reader."""
