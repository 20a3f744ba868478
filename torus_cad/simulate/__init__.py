"""Simulating the propeller in OpenFOAM (the ``simulate`` extra: foamlib): ``torus-cad simulate``.

``settings`` (levels, fluid, ranges), ``case`` (the case's dictionaries through foamlib),
``run`` (foamlib's asynchronous runner, watching the solver), ``history`` (what the function
objects write), ``performance`` (thrust, torque, coefficients, Richardson), ``plot``, and
``pipeline`` (one run as an output set; many at once; the convergence study).
"""
