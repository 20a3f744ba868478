"""Write the generated reference pages: the command-line reference (from torus-cad's own parser)
into docs/reference/cli.md and the configuration table (from the parameter schema) into
docs/reference/parameters.md.

    python scripts/reference_pages.py          # rewrite both pages in place
    python scripts/reference_pages.py --check  # exit 1 if a page is stale
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Callable
from pathlib import Path

from torus_cad.cli.reference import replace_reference
from torus_cad.parameters.parameter_reference import replace_table

REFERENCE = Path(__file__).resolve().parent.parent / "docs" / "reference"
#: page -> the function that returns its text with the generated part made anew.
PAGES: dict[Path, Callable[[str], str]] = {
    REFERENCE / "cli.md": replace_reference,
    REFERENCE / "parameters.md": replace_table,
}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--check", action="store_true", help="only check that the pages are up to date"
    )
    args = parser.parse_args()
    stale = []
    for page, regenerate in PAGES.items():
        text = page.read_text()
        updated = regenerate(text)
        if updated == text:
            continue
        stale.append(page)
        if not args.check:
            page.write_text(updated)
            print(f"wrote {page}")
    if args.check and stale:
        print(
            f"stale: {', '.join(str(page) for page in stale)}: "
            "run python scripts/reference_pages.py",
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
