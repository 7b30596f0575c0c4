"""``open_default_renderer``: the default renderer made on a thread of its own while the caller
reads its model, then taken by ``default_renderer`` in the thread that draws."""

from __future__ import annotations

import ctypes
import threading

import numpy as np
import pytest

import blueprint.api
from blueprint import examples
from blueprint.api import default_renderer, open_default_renderer, render_frame
from blueprint.errors import GLUnavailableError

SIZE = (96, 80)


def _current_context() -> int | None:
    egl = ctypes.CDLL("libEGL.so.1")
    egl.eglGetCurrentContext.restype = ctypes.c_void_p
    return egl.eglGetCurrentContext()


@pytest.fixture
def no_default(monkeypatch):
    """No default renderer made yet, as in a fresh process; the session's left as it was."""
    monkeypatch.setattr(blueprint.api, "_renderer", None)
    monkeypatch.setattr(blueprint.api, "_opening", None)


def test_a_renderer_opened_on_a_thread_draws_here_as_one_made_here(no_default, renderer):
    model = examples.gearbox()
    expected = render_frame(model, size=SIZE, renderer=renderer).image
    open_default_renderer()
    thread, _ = blueprint.api._opening
    assert thread is not threading.current_thread()
    opened = default_renderer()
    assert not thread.is_alive()
    try:
        assert opened is not renderer and blueprint.api._opening is None
        # its context is this thread's once made current here: the opening thread let it go
        renderer.make_current()
        session = _current_context()
        opened.make_current()
        assert _current_context() not in (None, session)
        assert default_renderer() is opened
        np.testing.assert_array_equal(render_frame(model, size=SIZE, renderer=opened).image, expected)
    finally:
        opened.release()
        renderer.make_current()


def test_opening_twice_or_with_a_renderer_made_starts_nothing(no_default, renderer, monkeypatch):
    monkeypatch.setattr(blueprint.api, "_renderer", renderer)
    open_default_renderer()
    assert blueprint.api._opening is None
    assert default_renderer() is renderer


def test_what_the_thread_raised_is_raised_where_the_renderer_is_taken(no_default, monkeypatch):
    def unavailable():
        raise GLUnavailableError("no usable OpenGL 3.3 context (test)")

    monkeypatch.setattr(blueprint.api, "Renderer", unavailable)
    open_default_renderer()
    with pytest.raises(GLUnavailableError, match="test"):
        default_renderer()
    assert blueprint.api._renderer is None and blueprint.api._opening is None
