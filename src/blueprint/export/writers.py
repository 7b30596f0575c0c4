"""The registry of output writers: an output file's suffix picks the writer that makes it.

A writer takes one kind of result (``Kind``): a raster image, peeled layers, a vector drawing or
video frames, and writes it atomically. ``WRITERS.choose(path, *kinds)`` checks an output path
before any work is done and returns the writer its suffix names among those kinds, or fails in
one line naming the suffixes allowed; the command line and the API choose every output this way.

Where a new format goes: its writer lives in the package that knows what it writes, and that
package registers it with one line, ``WRITERS.add(suffix, kind, write)``, beside the writer.
export/ may import only blueprint.errors and blueprint.scene (tests/test_layers.py), so only the
writers that need nothing above them register here (PNG, NPZ: the bottom of this file); vector
drawings register in blueprint.vector.drawing, beside the SVG, PDF and DXF writers, and video in
blueprint.api.files (the pipeline's VideoWriter encodes it). The registry does not look those
modules up by name when a suffix is missing: that would be an upward import at run time which
the layering test cannot see, and a cycle, since they import export for atomic writes. So a
suffix is known once the module registering it is imported: ``blueprint.api.files`` imports
every one, and its ``choose_writer`` is where the CLI and the API choose.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path

from blueprint.export.files import check_output, save_layers, save_png

__all__ = ["WRITERS", "Kind", "Writer", "Writers"]


class Kind(StrEnum):
    """What a writer takes.

    ``IMAGE``: an (H, W, 3 or 4) uint8 array, row 0 at the top. ``LAYERS``: peeled layers
    (``blueprint.Layers``). ``DRAWING``: a vector drawing (``blueprint.vector.Drawing``).
    ``VIDEO``: an iterable of (H, W, 3 or 4) uint8 frames of one size, with ``fps`` and ``crf``.
    """

    IMAGE = "raster image"
    LAYERS = "layers"
    DRAWING = "vector drawing"
    VIDEO = "video frames"


@dataclass(frozen=True)
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
    listed in the order they were added, which is the order error messages name them in."""

    def __init__(self) -> None:
        self._writers: dict[tuple[Kind, str], Writer] = {}

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
        found: dict[str, None] = {}
        for kind in kinds:
            found.update((s, None) for k, s in self._writers if k == kind)
        return tuple(found)

    def find(self, suffix: str, *kinds: Kind) -> Writer | None:
        """The writer of the first of ``kinds`` that writes ``suffix`` (any case), else None."""
        suffix = suffix.lower()
        return next((self._writers[k, suffix] for k in kinds if (k, suffix) in self._writers), None)

    def choose(self, path: str | os.PathLike, *kinds: Kind, suffix: str | None = None) -> tuple[Path, Writer]:
        """Check that ``path`` can be written with a writer of one of ``kinds`` (chosen by its
        suffix, or by ``suffix`` where given) and return the path and that writer.

        Raises ``InputError`` in one line where the suffix has no writer of those kinds (naming
        the suffixes that do), the path is a directory, or its folder is missing or read-only;
        ``LookupError`` where no writer of those kinds is registered at all (the module that
        registers them was not imported: a bug, not bad input).
        """
        allowed = self.suffixes(*kinds)
        if not allowed:
            raise LookupError(
                f"no writer of {' or '.join(kinds)} is registered: import blueprint.api.files first"
            )
        path = check_output(path, allowed, suffix)
        return path, self.find(suffix or path.suffix, *kinds)


WRITERS = Writers()
WRITERS.add(".png", Kind.IMAGE, save_png)
WRITERS.add(".npz", Kind.LAYERS, save_layers)
