"""Make the README's pictures by running the README's own examples.

    python docs/make_pictures.py      # from a clone, with blueprint importable (./run sets it up)

The README is the source: every ``### `` section under ``## Examples`` holds code blocks and
pictures ``![...](docs/pictures/NAME)``. Each section's blocks run in a fresh folder that looks
like a clone (``src`` and ``examples`` linked, the shipped ``gearbox.glb`` copied in, and
``models/`` holding it and a pillow block made with ``blueprint.examples``): a ``sh`` block line
by line, each line a ``blueprint`` command run through ``python -m blueprint.cli``; a
``python`` block as one script. A picture is the file of its name that the section wrote, or,
where it wrote none of that name, a contact sheet of every PNG it wrote. The picture at the top
of the README is what ``./run example`` draws, its command read from ``run``. Only the shipped
and generated models are drawn (the licences of others would have to travel with the pictures).
"""

from __future__ import annotations

import math
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
README = ROOT / "README.md"
PICTURES = "docs/pictures/"
MAX_BYTES = 300_000

_BLOCK = re.compile(r"^```(\w+)\n(.*?)^```\n", re.M | re.S)
_PICTURE = re.compile(r"!\[[^\]]*\]\((" + re.escape(PICTURES) + r"[^)\s]+)\)")
_RUN_EXAMPLE = re.compile(r'\.venv/bin/blueprint (render .*?) "\$@"')


@dataclass
class Example:
    """One README section: its title, code blocks (language, text) and picture paths."""

    title: str
    blocks: list[tuple[str, str]] = field(default_factory=list)
    pictures: list[str] = field(default_factory=list)


def examples(text: str) -> list[Example]:
    """The examples of the README's ``## Examples`` section, in order."""
    part = text.split("\n## Examples\n", 1)
    if len(part) < 2:
        raise SystemExit("README.md has no '## Examples' section")
    body = re.split(r"^## ", part[1], maxsplit=1, flags=re.M)[0]
    found = []
    for chunk in re.split(r"^### ", body, flags=re.M)[1:]:
        title, _, rest = chunk.partition("\n")
        found.append(
            Example(
                title.strip(),
                [(lang, code) for lang, code in _BLOCK.findall(rest)],
                _PICTURE.findall(rest),
            )
        )
    return found


def command_lines(code: str) -> list[list[str]]:
    """The commands of a ``sh`` block: backslash-continued lines joined, comments dropped."""
    commands = []
    for line in code.replace("\\\n", " ").splitlines():
        words = shlex.split(line, comments=True)
        if words:
            commands.append(words)
    return commands


def hero_command() -> list[str]:
    """The arguments ``./run example`` gives ``blueprint``."""
    found = _RUN_EXAMPLE.search((ROOT / "run").read_text())
    if not found:
        raise SystemExit("run: no example command found")
    return shlex.split(found.group(1))


def _environment() -> dict[str, str]:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (str(ROOT / "src"), env.get("PYTHONPATH")) if p)
    return env


def _blueprint(words: list[str], cwd: Path) -> None:
    if words[0] != "blueprint":
        raise SystemExit(f"README: only blueprint commands run in a sh block, not {words[0]!r}")
    print("$", shlex.join(words), flush=True)
    subprocess.run(
        [sys.executable, "-m", "blueprint.cli", *words[1:]], cwd=cwd, env=_environment(), check=True
    )


def _workspace(folder: Path) -> None:
    """A folder that looks like a clone, with the models the examples draw."""
    (folder / "src").symlink_to(ROOT / "src")
    (folder / "examples").symlink_to(ROOT / "examples")
    shutil.copy(ROOT / "src/blueprint/data/gearbox.glb", folder / "gearbox.glb")
    models = folder / "models"
    models.mkdir()
    shutil.copy(ROOT / "src/blueprint/data/gearbox.glb", models / "gearbox.glb")
    script = (
        "from blueprint import examples as e\n"
        "parts = {'block': e.box((-30, 0, -20), (30, 30, 20)),\n"
        "         'bearing': e.tube(8, 14, 40, 48, axis=2, center=(0, 44, 0)),\n"
        "         'bolt': e.prism([4.0], 50, 24, axis=1, center=(20, 20, 0))}\n"
        "e.write_glb(e.assemble(parts), 'models/pillow_block.glb')\n"
    )
    subprocess.run([sys.executable, "-c", script], cwd=folder, env=_environment(), check=True)


def _contact_sheet(images: list[Path], out: Path) -> None:
    """The images side by side in a square-ish grid, on white."""
    from PIL import Image

    columns = math.ceil(math.sqrt(len(images)))
    tiles = [Image.open(p).convert("RGBA") for p in images]
    w = max(t.width for t in tiles)
    h = max(t.height for t in tiles)
    rows = -(-len(tiles) // columns)
    sheet = Image.new("RGBA", (w * min(columns, len(tiles)), h * rows), (255, 255, 255, 255))
    for i, tile in enumerate(tiles):
        sheet.paste(tile, ((i % columns) * w, (i // columns) * h), tile)
    sheet.save(out, optimize=True)


def _written(folder: Path, before: set[Path]) -> list[Path]:
    return sorted(p for p in folder.rglob("*") if p.is_file() and not p.is_symlink() and p not in before)


def make_example(example: Example, target: Path) -> list[Path]:
    """Run one example in a fresh folder and copy its pictures to ``target`` (the repo root)."""
    made = []
    with tempfile.TemporaryDirectory(prefix="blueprint-docs-") as tmp:
        folder = Path(tmp)
        _workspace(folder)
        before = set(_written(folder, set()))
        for lang, code in example.blocks:
            if lang == "sh":
                for words in command_lines(code):
                    _blueprint(words, folder)
            elif lang == "python":
                (folder / "cell.py").write_text(code)
                print("$ python <<", example.title, flush=True)
                subprocess.run([sys.executable, "cell.py"], cwd=folder, env=_environment(), check=True)
                (folder / "cell.py").unlink()
            else:
                raise SystemExit(f"README: {example.title}: a {lang!r} block does not run")
        written = _written(folder, before)
        for picture in example.pictures:
            out = target / picture
            out.parent.mkdir(parents=True, exist_ok=True)
            same = [p for p in written if p.name == out.name]
            if len(same) == 1:
                shutil.copy(same[0], out)
            elif not same and any(p.suffix == ".png" for p in written):
                _contact_sheet([p for p in written if p.suffix == ".png"], out)
            else:
                raise SystemExit(f"README: {example.title}: cannot tell which file is {picture}")
            made.append(out)
    return made


def make_hero(target: Path) -> Path:
    """Draw what ``./run example`` draws into docs/pictures/<its output's name>."""
    words = ["blueprint", *hero_command()]
    with tempfile.TemporaryDirectory(prefix="blueprint-docs-") as tmp:
        folder = Path(tmp)
        _workspace(folder)
        _blueprint(words, folder)
        name = words[words.index("-o") + 1]
        out = target / PICTURES / name
        out.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy(folder / name, out)
    return out


def main() -> int:
    text = README.read_text()
    made = [make_hero(ROOT)]
    for example in examples(text):
        if not example.blocks or not example.pictures:
            raise SystemExit(f"README: {example.title}: an example needs a code block and a picture")
        made += make_example(example, ROOT)
    for path in made:
        size = path.stat().st_size
        print(f"{path.relative_to(ROOT)}: {size} bytes")
        if size > MAX_BYTES:
            raise SystemExit(f"{path}: {size} bytes, over {MAX_BYTES}: draw it smaller")
    return 0


if __name__ == "__main__":
    sys.exit(main())
