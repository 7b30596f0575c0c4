"""3DXML (Dassault Systèmes): a zip of XML, read by trimesh (which needs lxml and networkx);
Z-up by the convention of CAD, no unit."""

from __future__ import annotations

from pathlib import Path

from blueprint.scene.archive import check_zip

__all__ = ["check"]


def check(path: Path, size: int, data: bytes | None = None) -> None:
    """Refuse a zip whose directory declares too much (``check_zip``): trimesh expands it whole."""
    check_zip(path, data)
