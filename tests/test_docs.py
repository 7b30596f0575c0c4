"""The README and docs/ stay true: the README short, its examples runnable as written and their
pictures present, every link resolving, docs/cli.md what the commands say."""

from __future__ import annotations

import importlib.util
import re
import sys
from pathlib import Path

import click
import pytest

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
DOCS = ROOT / "docs"
MARKDOWN = [README, *sorted(DOCS.glob("*.md"))]
_LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)\)")


def _script(name: str):
    """A script of docs/ as a module (registered, as its dataclasses need)."""
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, DOCS / f"{name}.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module
        spec.loader.exec_module(module)
    return sys.modules[name]


def _slug(heading: str) -> str:
    """GitHub's anchor of a Markdown heading."""
    return re.sub(r"[^\w\- ]", "", heading.strip().lower()).replace(" ", "-")


def _anchors(path: Path) -> set[str]:
    text = re.sub(r"^```.*?^```", "", path.read_text(encoding="utf-8"), flags=re.M | re.S)
    return {_slug(m.group(1)) for m in re.finditer(r"^#+ (.+)$", text, re.M)}


def _links(path: Path) -> list[str]:
    text = re.sub(r"^```.*?^```", "", path.read_text(encoding="utf-8"), flags=re.M | re.S)
    return _LINK.findall(text)


def test_readme_is_short():
    lines = README.read_text(encoding="utf-8").splitlines()
    assert len(lines) <= 150, f"README.md has {len(lines)} lines; the rest belongs in docs/"


def test_cli_reference_is_current():
    made = _script("make_cli").cli_reference()
    assert (DOCS / "cli.md").read_text(encoding="utf-8") == made, (
        "docs/cli.md is stale: run python docs/make_cli.py"
    )


def test_cli_reference_covers_every_command():
    from blueprint.cli import COMMANDS, cli

    text = (DOCS / "cli.md").read_text(encoding="utf-8")
    ctx = click.Context(cli, info_name="blueprint")
    for name in COMMANDS:
        assert f"## `blueprint {name}`" in text
        for param in cli.get_command(ctx, name).params:
            for opt in getattr(param, "opts", []):
                if opt.startswith("-") and opt not in ("-h", "--help"):
                    assert f"`{opt}`" in text, (name, opt)


@pytest.mark.parametrize("path", MARKDOWN, ids=lambda p: p.name)
def test_links_resolve(path):
    checked = 0
    for link in _links(path):
        if re.match(r"^[a-z]+:", link):
            continue
        target, _, anchor = link.partition("#")
        resolved = (path.parent / target).resolve() if target else path
        assert resolved.exists(), f"{path.name}: {link} does not exist"
        if anchor and resolved.suffix == ".md":
            assert anchor in _anchors(resolved), f"{path.name}: {link}: no such heading"
        checked += 1
    assert checked, f"{path.name} links nothing"


def test_readme_pictures_exist_and_are_small():
    pictures = [link for link in _links(README) if link.startswith("docs/pictures/")]
    assert len(pictures) >= 7
    for link in pictures:
        path = ROOT / link
        assert path.is_file(), link
        assert 0 < path.stat().st_size < _script("make_pictures").MAX_BYTES, link
    for path in (DOCS / "pictures").iterdir():
        assert f"docs/pictures/{path.name}" in pictures, f"{path.name} is shown nowhere"
    for alt in re.findall(r"!\[([^\]]*)\]", README.read_text(encoding="utf-8")):
        assert len(alt) > 20, f"a picture without a caption: {alt!r}"


def _command(words: list[str]) -> tuple[click.Command, list[str], click.Context]:
    """The click command a ``blueprint ...`` line runs, its arguments and parent context."""
    from blueprint.cli import cli

    command, args = cli, list(words[1:])
    ctx = click.Context(cli, info_name="blueprint")
    while isinstance(command, click.Group):
        name = args.pop(0)
        command = command.get_command(ctx, name)
        assert command is not None, f"no command {name!r}: {words}"
        if isinstance(command, click.Group):
            ctx = click.Context(command, info_name=name, parent=ctx)
    return command, args, ctx


def test_readme_examples_run_as_written():
    """Every example is a code block the picture script runs and a picture it made; every
    command line parses with the command's own options."""
    pictures = _script("make_pictures")
    text = README.read_text(encoding="utf-8")
    examples = pictures.examples(text)
    assert 6 <= len(examples) <= 8
    shown = {pictures.PICTURES + pictures.hero_command()[pictures.hero_command().index("-o") + 1]}
    commands = 0
    for example in examples:
        assert example.blocks and example.pictures, example.title
        shown.update(example.pictures)
        for lang, code in example.blocks:
            assert lang in ("sh", "python"), example.title
            if lang == "python":
                compile(code, example.title, "exec")
                continue
            for words in pictures.command_lines(code):
                assert words[0] == "blueprint", words
                command, args, parent = _command(words)
                command.make_context(words[1], args, parent=parent)
                commands += 1
    assert commands >= 6
    command, args, parent = _command(["blueprint", *pictures.hero_command()])
    command.make_context("render", args, parent=parent)
    linked = {link for link in _links(README) if link.startswith(pictures.PICTURES)}
    assert linked == shown, "every README picture is the hero or an example's"


def test_readme_keeps_the_install_facts_and_commands():
    text = README.read_text(encoding="utf-8")
    for fact in ("blueprint-drawings", "pip install .", "./run example", "./run tests", "gearbox.png"):
        assert fact in text, fact
    run = (ROOT / "run").read_text(encoding="utf-8")
    assert "example)" in run and "tests)" in run
