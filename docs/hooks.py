"""MkDocs hook: the command-line reference is generated from torus_cad's own argument parser at build time."""

from __future__ import annotations

import argparse
from typing import Any

MARKER = "<!-- cli reference: generated from the parser -->"


def _help_of(parser: argparse.ArgumentParser, title: str) -> list[str]:
    parser.formatter_class = lambda prog: argparse.HelpFormatter(prog, width=100)
    return [f"## `{title}`", "", "```text", parser.format_help().rstrip(), "```", ""]


def cli_reference() -> str:
    """Markdown of ``torus-cad --help`` and every subcommand's ``--help``."""
    from torus_cad.cli.parser import build_parser

    parser = build_parser()
    lines = _help_of(parser, "torus-cad")
    for action in parser._actions:  # argparse keeps its subcommands here and nowhere public
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                lines += _help_of(sub, f"torus-cad {name}")
    return "\n".join(lines)


def on_page_markdown(markdown: str, **_: Any) -> str:
    return markdown.replace(MARKER, cli_reference()) if MARKER in markdown else markdown
