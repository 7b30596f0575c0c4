"""The program around the commands, kept light so that ``blueprint --help`` imports nothing
of the renderer: one-line warnings, and ``run``, which makes a click command a program whose
user errors are one line on stderr and exit code 2."""

from __future__ import annotations

import logging
import sys
import warnings

import click

from blueprint.errors import BlueprintError, printable


class _OneLine(logging.Handler):
    def emit(self, record: logging.LogRecord) -> None:
        click.echo(f"blueprint: warning: {printable(record.getMessage())}", err=True)


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    # Python's form is two lines with the source line (NumPy's "overflow encountered in matmul"
    # on coordinates near the float limits); ours is one, once per message
    text = " ".join(str(message).split())
    if text not in _WARNED:
        _WARNED.add(text)
        kind = "numeric trouble: " if issubclass(category, RuntimeWarning) else ""
        logging.getLogger("blueprint").warning("%s%s", kind, text)


_WARNED: set[str] = set()


def setup_logging() -> None:
    log = logging.getLogger("blueprint")
    if not any(isinstance(h, _OneLine) for h in log.handlers):
        log.addHandler(_OneLine())
    log.setLevel(logging.WARNING)
    log.propagate = False
    warnings.showwarning = _one_line_warning


def run(command: click.Command, argv: list[str] | None, prog_name: str) -> None:
    """Run a click command as a program: user errors become one line on stderr and exit code 2."""
    setup_logging()
    try:
        command.main(args=argv, prog_name=prog_name, standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("blueprint: interrupted", err=True)
        sys.exit(130)
    except click.ClickException as exc:
        click.echo(f"blueprint: error: {printable(exc.format_message())}", err=True)
        sys.exit(2)
    except BlueprintError as exc:
        # the API names its arguments, the command line its flags; loaded only for an error
        from blueprint.cli.options import with_flags

        # file names in messages may hold newlines and bytes that are not UTF-8
        click.echo(f"blueprint: error: {printable(with_flags(str(exc)))}", err=True)
        sys.exit(2)
    except MemoryError:
        click.echo("blueprint: error: out of memory (try a smaller --size)", err=True)
        sys.exit(2)
    except ModuleNotFoundError as exc:
        # a module of the package, or a package it requires, is not there (the optional ones
        # are asked for by name where they are used): a broken install, not a fault to trace
        click.echo(
            f"blueprint: error: no module named {exc.name!r}: the installation is incomplete "
            "(reinstall blueprint-drawings)",
            err=True,
        )
        sys.exit(2)
    except KeyboardInterrupt:
        click.echo("blueprint: interrupted", err=True)
        sys.exit(130)
    sys.exit(0)
