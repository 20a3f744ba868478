"""Write the command-line reference, generated from torus-cad's own parser, into docs/reference/cli.md.

    python scripts/cli_reference.py          # rewrite the reference in place
    python scripts/cli_reference.py --check  # exit 1 if the page is stale
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from torus_cad.cli.reference import replace_reference

PAGE = Path(__file__).resolve().parent.parent / "docs" / "reference" / "cli.md"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--check", action="store_true", help="only check that the page is up to date")
    args = parser.parse_args()
    text = PAGE.read_text()
    updated = replace_reference(text)
    if args.check:
        if updated != text:
            print("docs/reference/cli.md is stale: run python scripts/cli_reference.py", file=sys.stderr)
            return 1
        return 0
    PAGE.write_text(updated)
    print(f"wrote the command-line reference into {PAGE}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
