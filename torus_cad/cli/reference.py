"""The command-line reference page (docs/reference/cli.md): ``torus-cad --help`` and every
subcommand's, generated from the program's own parser and written into the page by
``scripts/reference_pages.py``, so the page reads the same in the repository and on the site; a test
checks that it is current."""

from __future__ import annotations

import argparse

BEGIN = (
    "<!-- BEGIN cli reference: generated from the parser "
    "by scripts/reference_pages.py; do not edit -->"
)
END = "<!-- END cli reference -->"

#: Help is wrapped at this width, whatever the terminal, so the page does not depend on who
#: generated it.
HELP_WIDTH = 100


def _help_of(parser: argparse.ArgumentParser, title: str) -> list[str]:
    parser.formatter_class = lambda prog: (
        argparse.RawDescriptionHelpFormatter(prog, width=HELP_WIDTH)
        if parser.epilog
        else argparse.HelpFormatter(prog, width=HELP_WIDTH)
    )
    return [f"## `{title}`", "", "```text", parser.format_help().rstrip(), "```", ""]


def cli_reference() -> str:
    """Markdown of ``torus-cad --help`` and every subcommand's ``--help`` (options loaded from the
    schema included), between the page's markers."""
    from torus_cad.cli.parser import build_parser_and_commands

    parser, commands = build_parser_and_commands()
    lines = [BEGIN, ""] + _help_of(parser, "torus-cad")
    for name, sub in commands.items():  # format_help adds a subcommand's schema options
        lines += _help_of(sub, f"torus-cad {name}")
    return "\n".join([*lines, END])


def replace_reference(page: str) -> str:
    """``page`` with the text between the markers replaced by the current reference."""
    start, end = page.index(BEGIN), page.index(END) + len(END)
    return page[:start] + cli_reference() + page[end:]
