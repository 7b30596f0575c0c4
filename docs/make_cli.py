"""Write docs/cli.md, the command-line reference, from the click commands themselves.

    python docs/make_cli.py           # rewrite docs/cli.md
    python docs/make_cli.py --check   # exit 1 if docs/cli.md differs from what the commands say

Every command of ``blueprint.cli.cli`` (subcommands of groups too) gets its usage, its help
and a table of its arguments and options with their help and defaults; tests/test_docs.py
fails when the file is stale.
"""

from __future__ import annotations

import inspect
import sys
from pathlib import Path

import click

CLI_MD = Path(__file__).resolve().parent / "cli.md"

HEADER = """\
# Command-line reference

Generated from the commands' own help by `python docs/make_cli.py`; `tests/test_docs.py` fails
when this file is stale. Every command takes `-h`/`--help`; `blueprint --version` prints the
version. In a clone, `./run blueprint ARGS...` runs the same commands inside the project's
environment. Bad input gets one line on stderr naming the file and the problem, exit code 2.
"""


def _cell(text: str) -> str:
    """Text fit for one cell of a Markdown table."""
    return " ".join(str(text).split()).replace("|", "\\|")


def _paragraphs(text: str) -> str:
    """A docstring's paragraphs, each on one line (the source's line breaks are its wrapping)."""
    blocks = inspect.cleandoc(text).replace("\b\n", "").split("\n\n")
    return "\n\n".join(" ".join(block.split()) for block in blocks if block.strip())


def _metavar(param: click.Parameter) -> str:
    if getattr(param, "is_flag", False) or getattr(param, "count", False):
        return ""
    if param.metavar:
        return param.metavar
    kind = param.type
    if isinstance(kind, click.Choice):
        return "[" + "\\|".join(map(str, kind.choices)) + "]"
    name = {"integer range": "INTEGER"}.get(kind.name, kind.name.upper())
    return " ".join([name] * max(param.nargs, 1))


def _default(param: click.Parameter) -> str:
    value = param.default
    if value is None or callable(value) or type(value).__name__ == "Sentinel":
        return ""
    if getattr(param, "is_flag", False) and value is False:
        return ""
    if isinstance(value, list | tuple):
        return " ".join(map(str, value))
    return str(value)


def _help(param: click.Option, ctx: click.Context) -> str:
    # an option may make its help when help is shown (render's -o lists the writers)
    param.get_help_record(ctx)
    return param.help or ""


def _command(lines: list[str], command: click.Command, ctx: click.Context) -> None:
    path = ctx.command_path
    lines += [f"## `{path}`", ""]
    pieces = " ".join(command.collect_usage_pieces(ctx))
    lines += ["```", f"{path} {pieces}".rstrip(), "```", ""]
    if command.help:
        lines += [_paragraphs(command.help), ""]
    arguments = [p for p in command.params if isinstance(p, click.Argument)]
    if arguments:
        lines += ["| argument | value | required |", "|---|---|---|"]
        for arg in arguments:
            many = " (one or more)" if arg.nargs == -1 else ""
            lines.append(
                f"| `{arg.human_readable_name}` | {_metavar(arg)}{many} | {'yes' if arg.required else 'no'} |"
            )
        lines.append("")
    options = [p for p in command.params if isinstance(p, click.Option) and "--help" not in p.opts]
    if options:
        lines += ["| option | value | default | help |", "|---|---|---|---|"]
        for opt in options:
            names = ", ".join(f"`{name}`" for name in [*opt.opts, *opt.secondary_opts])
            value = _metavar(opt)
            value = f"`{value}`" if value and not value.startswith("[") else value
            default = _default(opt)
            required = " (required)" if opt.required else ""
            repeat = " (repeatable)" if opt.multiple else ""
            lines.append(
                f"| {names} | {value} | {_cell(default)} | {_cell(_help(opt, ctx))}{required}{repeat} |"
            )
        lines.append("")
    if isinstance(command, click.Group):
        for name in command.list_commands(ctx):
            sub = command.get_command(ctx, name)
            _command(lines, sub, click.Context(sub, info_name=name, parent=ctx))


def cli_reference() -> str:
    """The text of docs/cli.md, made from the commands of ``blueprint.cli``."""
    from blueprint.cli import cli

    ctx = click.Context(cli, info_name="blueprint")
    lines = [HEADER, "## Commands", ""]
    for name in cli.list_commands(ctx):
        command = cli.get_command(ctx, name)
        short = command.get_short_help_str(limit=200)
        lines.append(f"- [`blueprint {name}`](#blueprint-{name}): {short}")
    lines.append("")
    for name in cli.list_commands(ctx):
        command = cli.get_command(ctx, name)
        _command(lines, command, click.Context(command, info_name=name, parent=ctx))
    return "\n".join(lines).rstrip() + "\n"


def main(argv: list[str]) -> int:
    text = cli_reference()
    if argv[1:] == ["--check"]:
        if CLI_MD.exists() and CLI_MD.read_text() == text:
            return 0
        print(f"{CLI_MD} is stale: run python docs/make_cli.py", file=sys.stderr)
        return 1
    CLI_MD.write_text(text)
    print(f"{CLI_MD}: {len(text.splitlines())} lines")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
