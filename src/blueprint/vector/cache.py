"""View-independent line work kept per model: the welded adjacency and the intersection lines
between parts are computed once and found again by the model object, or by its content where a
batch, a benchmark or a second load of one file hands over a new object with the same mesh."""

from __future__ import annotations

import weakref
from collections import OrderedDict
from collections.abc import Callable
from typing import TypeVar

from blueprint.scene.model import Model

__all__ = ["ModelCache", "content_key"]

T = TypeVar("T")


def content_key(model: Model) -> str:
    """A digest of what the lines depend on (positions, faces, their parts, the part count),
    computed once per model object (``Model.content_digest``)."""
    return model.content_digest().hex()


class ModelCache:
    """Results of one kind per model: by identity while the model lives, and by content for the
    last ``entries`` meshes seen."""

    def __init__(self, entries: int = 8) -> None:
        self.entries = entries
        self._by_object: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
        self._by_content: OrderedDict[str, object] = OrderedDict()

    def get(self, model: Model, build: Callable[[], T]) -> T:
        """The result for ``model``, from ``build()`` the first time its mesh is seen."""
        held = self._by_object.get(model)
        if held is not None:
            return held
        key = content_key(model)
        held = self._by_content.get(key)
        if held is None:
            held = build()
            self._by_content[key] = held
            while len(self._by_content) > self.entries:
                self._by_content.popitem(last=False)
        else:
            self._by_content.move_to_end(key)
        self._by_object[model] = held
        return held

    def clear(self) -> None:
        """Forget everything (benchmarks that time the work from scratch)."""
        self._by_object.clear()
        self._by_content.clear()
