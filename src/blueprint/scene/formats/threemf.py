"""3MF: a zip of XML model parts, read by trimesh; Z-up as printing formats are, in the unit its
model states (millimetres where it states none, as trimesh reports it)."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

from blueprint import settings
from blueprint.errors import InputError
from blueprint.scene.archive import check_zip
from blueprint.scene.headers import walk_graph
from blueprint.scene.units import named_unit
from blueprint.settings import open_file

__all__ = ["check", "stated_unit"]

# The units a 3MF file may state (3MF core specification, ``model@unit``).
_UNITS = ("micron", "millimeter", "centimeter", "inch", "foot", "meter")


def check(path: Path, size: int, data: bytes | None = None) -> None:
    """Refuse a zip whose directory declares too much (``check_zip``), and a component graph
    with a cycle, too deep a nesting, or more instances or triangles than the limits."""
    check_zip(path, data)
    _check_graph(path, data)


def stated_unit(name: str, stated: str | None) -> tuple[str | None, str]:
    """The unit a 3MF file states (``stated``, as trimesh reports it).

    Raises
    ------
    InputError
        A unit blueprint does not know: the specification allows six, and a drawing's sizes
        would be wrong by a factor nothing tells, so the file is refused as a damaged one is.
    """
    if stated is None:
        return None, "the 3MF files state different units"
    unit = named_unit(stated)
    if unit is None:
        raise InputError(f"{name}: unknown length unit {stated!r} (3MF's units: {', '.join(_UNITS)})")
    return unit, "the 3MF model's unit, millimetres where it states none"


def _check_graph(path: Path, data: bytes | None) -> None:
    """The component graph of each model part of a 3MF (a zip whose expanded size
    ``blueprint.scene.archive.check_zip`` has bounded), walked as glTF nodes are: objects made
    of components of other objects, placed by build items."""
    import zipfile
    import zlib

    with contextlib.ExitStack() as stack:
        fh = (
            io.BytesIO(data)
            if data is not None
            else stack.enter_context(open_file(path, settings.MODEL_FILE_LIMIT, "a model file"))
        )
        try:
            archive = stack.enter_context(zipfile.ZipFile(fh))
            parts = [i for i in archive.infolist() if i.filename.lower().endswith(".model")]
            documents = [archive.read(i) for i in parts]
        except (zipfile.BadZipFile, zlib.error, OSError, ValueError, EOFError, NotImplementedError):
            return  # the loader says what is wrong
    for document in documents:
        _check_3mf_document(path, document)


def _check_3mf_document(path: Path, document: bytes) -> None:
    import xml.etree.ElementTree as ElementTree

    objects: dict[str, tuple[int, list[str]]] = {}  # id: triangles, component object ids
    items: list[str] = []
    current = None
    try:
        for event, element in ElementTree.iterparse(io.BytesIO(document), events=("start", "end")):
            tag = element.tag.rsplit("}", 1)[-1]
            if event == "start":
                if tag == "object":
                    current = element.get("id", "")
                    objects[current] = (0, [])
                elif tag == "component" and current is not None and not _elsewhere(element):
                    objects[current][1].append(element.get("objectid", ""))
                elif tag == "triangle" and current is not None:
                    count, components = objects[current]
                    objects[current] = (count + 1, components)
                elif tag == "item":
                    items.append(element.get("objectid", ""))
            else:
                if tag == "object":
                    current = None
                element.clear()
    except ElementTree.ParseError:
        return  # the loader says what is wrong

    def children(index: str) -> list[str]:
        found = objects[index][1]
        for child in found:
            if child not in objects:
                raise InputError(f"{path}: object {index} has a component {child!r}, which does not exist")
        return found

    roots = [item for item in items if item in objects]
    walk_graph(
        path,
        roots,
        children,
        lambda index: (
            int(objects[index][0] > 0),
            objects[index][0],
            index if objects[index][0] > 0 else None,
        ),
        "objects",
    )


def _elsewhere(component) -> bool:
    """Whether a 3MF component names an object of another model part (``p:path``)."""
    return any(key.rsplit("}", 1)[-1] == "path" for key in component.keys())
