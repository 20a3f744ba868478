"""Write the configuration table, generated from the parameter schema, into docs/reference/parameters.md.

    python scripts/parameter_table.py          # rewrite the table in place
    python scripts/parameter_table.py --check  # exit 1 if the page is stale
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from torus_cad.parameters.reference import replace_table

README = Path(__file__).resolve().parent.parent / "docs" / "reference" / "parameters.md"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only check that the page is up to date")
    args = parser.parse_args()
    text = README.read_text()
    updated = replace_table(text)
    if args.check:
        if updated != text:
            print("docs/reference/parameters.md is stale: run python scripts/parameter_table.py", file=sys.stderr)
            return 1
        return 0
    README.write_text(updated)
    print(f"wrote the parameter table into {README}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
