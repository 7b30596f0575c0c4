"""``python -m blueprint``: the ``blueprint`` command."""

from blueprint.cli import main

main()
