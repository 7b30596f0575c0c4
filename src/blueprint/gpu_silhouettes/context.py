"""The renderer's context made current around GL work, since a process may hold several."""

from __future__ import annotations

import contextlib
import functools
from collections.abc import Iterator

from blueprint.render.renderer import LayerRenderer


class CurrentContext:
    """Makes a renderer's context current for a block, once however deeply blocks nest.

    Entering a moderngl context makes it current and leaving it makes *none* current, so only
    the outermost block of nested calls enters it.
    """

    def __init__(self, renderer: LayerRenderer) -> None:
        self.renderer = renderer
        self._entered = 0

    @contextlib.contextmanager
    def __call__(self) -> Iterator[None]:
        if self._entered:
            yield
            return
        self._entered += 1
        try:
            with self.renderer.ctx:
                yield
        finally:
            self._entered -= 1


def on_gl(method):
    """Run the method inside ``self.current()`` (a :class:`CurrentContext` block)."""

    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        with self.current():
            return method(self, *args, **kwargs)

    return wrapper
