"""Writing results: every file atomically (temporary file in the same folder, then rename),
each format by the writer its suffix names in ``WRITERS`` (``blueprint.export.writers``)."""

from blueprint.export.files import atomic_write, save_layers, save_png
from blueprint.export.writers import WRITERS, Kind, Writer, Writers

__all__ = ["WRITERS", "Kind", "Writer", "Writers", "atomic_write", "save_layers", "save_png"]
