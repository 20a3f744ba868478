"""The preview picture (``picture``: VTK, off-screen), of ``build --preview`` and ``torus-cad
preview``."""
