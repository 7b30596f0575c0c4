"""The interactive viewer: a window on a model, drawn by the same ``Renderer`` as ``render``.

``blueprint view MODEL`` (the command is ``blueprint.cli.view``); from Python
``run_viewer(path, ...)``. The state and camera rules (``state.py``) and the CPU overlays
(``overlay.py``) need neither a window nor a GPU; ``window.py`` imports the windowing library
(glfw) only when a window is opened.
"""

from blueprint.viewer.state import VIEW_KEYS, ViewState

__all__ = ["VIEW_KEYS", "ViewState", "run_viewer"]


def run_viewer(*args, **kwargs):
    """Open the viewer on a model file (see ``blueprint.viewer.app.run_viewer``)."""
    from blueprint.viewer.app import run_viewer as run

    return run(*args, **kwargs)
