"""The registry of output writers: an output file's suffix picks the writer that makes it.

A writer takes one kind of result (``Kind``): a raster image, peeled layers, a vector drawing or
video frames, and writes it atomically. ``WRITERS.choose(path, *kinds)`` checks an output path
before any work is done and returns the writer its suffix names among those kinds, or fails in
one line naming the suffixes allowed; the command line and the API choose every output this way.

Where a new format goes: its writer lives in the package that knows what it writes and is
registered by one line, ``writers.add(suffix, kind, write)``. export/ may import only
blueprint.errors and blueprint.scene (tests/test_layers.py), so only the writers that need
nothing above them are added here (PNG, NPZ: the bottom of this file). The kinds made above
export register in a function of their package, ``register_writers(writers)``, which the
registry calls when a suffix of that kind is first looked for (``PROVIDERS``): vector drawings
in blueprint.vector.drawing, beside the SVG, PDF and DXF writers, and video in
blueprint.pipeline.media, beside its encoder. Nothing registers on import, and a picture's
drawing loads neither package.
"""

from __future__ import annotations

import importlib
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path

from blueprint.export.files import check_output, save_layers, save_png

__all__ = ["PROVIDERS", "WRITERS", "Kind", "Writer", "Writers"]


class Kind(StrEnum):
    """What a writer takes.

    ``IMAGE``: an (H, W, 3 or 4) uint8 array, row 0 at the top. ``LAYERS``: peeled layers
    (``blueprint.Layers``). ``DRAWING``: a vector drawing (``blueprint.vector.VectorDrawing``).
    ``VIDEO``: an iterable of (H, W, 3 or 4) uint8 frames of one size, with ``fps`` and ``crf``.
    """

    IMAGE = "raster image"
    LAYERS = "layers"
    DRAWING = "vector drawing"
    VIDEO = "video frames"


# compared by identity: one record a registered kind and suffix
@dataclass(frozen=True, eq=False)
class Writer:
    """Writes one ``kind`` of result to files ending in ``suffix``: ``writer(path, value,
    **options)`` writes atomically and returns the path."""

    suffix: str
    kind: Kind
    write: Callable[..., Path]

    def __call__(self, path: str | os.PathLike, value, **options) -> Path:
        return self.write(Path(path), value, **options)


class Writers:
    """Writers by kind and suffix. A suffix has at most one writer of each kind; suffixes are
    listed in the order they were added, which is the order error messages name them in.

    ``providers`` names, for a kind, the function that registers its writers
    (``"package.module:function"``, called with this registry): it is imported and called the
    first time a suffix of that kind is looked for while none of that kind is registered.
    """

    def __init__(self, providers: Mapping[Kind, str] | None = None) -> None:
        self._writers: dict[tuple[Kind, str], Writer] = {}
        self._providers = dict(providers or {})

    def _provide(self, kinds: tuple[Kind, ...]) -> None:
        """Register the writers of ``kinds`` that have a provider and none registered yet."""
        registered = {kind for kind, _ in self._writers}
        for kind in kinds:
            if kind not in registered and kind in self._providers:
                module, function = self._providers[kind].split(":")
                getattr(importlib.import_module(module), function)(self)

    def add(self, suffix: str, kind: Kind, write: Callable[..., Path]) -> Writer:
        """Register ``write(path, value, **options) -> Path`` for ``kind`` and ``suffix``."""
        if not suffix.startswith(".") or suffix != suffix.lower() or len(suffix) < 2:
            raise ValueError(f"a suffix is a dot and lower-case characters, got {suffix!r}")
        if (kind, suffix) in self._writers:
            raise ValueError(f"a writer of {kind} for {suffix} is registered already")
        writer = self._writers[kind, suffix] = Writer(suffix, kind, write)
        return writer

    def suffixes(self, *kinds: Kind) -> tuple[str, ...]:
        """The suffixes written for ``kinds``: the first kind's first, without repeats."""
        self._provide(kinds)
        found: dict[str, None] = {}
        for kind in kinds:
            found.update((s, None) for k, s in self._writers if k == kind)
        return tuple(found)

    def find(self, suffix: str, *kinds: Kind) -> Writer | None:
        """The writer of the first of ``kinds`` that writes ``suffix`` (any case), else None."""
        suffix = suffix.lower()
        for kind in kinds:
            # kind by kind, so that a picture's suffix is found before the vector writers load
            self._provide((kind,))
            if (kind, suffix) in self._writers:
                return self._writers[kind, suffix]
        return None

    def choose(self, path: str | os.PathLike, *kinds: Kind, suffix: str | None = None) -> tuple[Path, Writer]:
        """Check that ``path`` can be written with a writer of one of ``kinds`` (chosen by its
        suffix, or by ``suffix`` where given) and return the path and that writer.

        Raises ``InputError`` in one line where the suffix has no writer of those kinds (naming
        the suffixes that do), the path is a directory, or its folder is missing or read-only;
        ``LookupError`` where no writer of those kinds is registered at all (none was added and
        no provider names them: a bug, not bad input).
        """
        writer = self.find(suffix or Path(path).suffix, *kinds)
        # the suffixes of every kind are listed (and their writers loaded) only to refuse one
        allowed = (writer.suffix,) if writer is not None else self.suffixes(*kinds)
        if not allowed:
            raise LookupError(f"no writer of {' or '.join(kinds)} is registered")
        return check_output(path, allowed, suffix), writer


#: The functions that register the writers of the kinds made above export, by kind.
PROVIDERS = {
    Kind.DRAWING: "blueprint.vector.drawing:register_writers",
    Kind.VIDEO: "blueprint.pipeline.media:register_writers",
}

WRITERS = Writers(PROVIDERS)
WRITERS.add(".png", Kind.IMAGE, save_png)
WRITERS.add(".npz", Kind.LAYERS, save_layers)
