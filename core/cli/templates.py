"""``ease templates``: the design templates that ship with EASE, and where they are."""

from __future__ import annotations

from .common import subcommand


def _cmd(args) -> int:
    from ..design.templates import list_templates, template_path

    names = list_templates()
    width = max(len(n) for n in names)
    for name in names:
        print(f"{name:<{width}}  {template_path(name)}")
    return 0


def add_parser(sub) -> None:
    subcommand(
        sub,
        "templates",
        _cmd,
        help="list the shipped design templates and their files",
        description="List the design templates installed with EASE (name and JSON path); pass a "
        "path to `ease cut`, `ease pattern`, ... or copy the file to edit it.",
    )
