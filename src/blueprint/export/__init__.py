"""Writing results: every file atomically (temporary file in the same folder, then rename)."""

from blueprint.export.files import atomic_write, save_layers, save_png

__all__ = ["atomic_write", "save_layers", "save_png"]
