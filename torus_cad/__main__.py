"""``python -m torus_cad ...`` runs the torus-cad command."""

import sys

from torus_cad.cli import main

sys.exit(main())
