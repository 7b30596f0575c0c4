"""The interactive viewer: a window on a model, drawn by the same ``Renderer`` as ``render``.

``blueprint view MODEL`` (see ``command.py``); from Python ``run_viewer(path, ...)``. The state
and camera rules (``state.py``) and the CPU overlays (``overlay.py``) need neither a window nor
a GPU; ``app.py`` imports the windowing library (glfw) only when a window is opened.
"""

# blueprint.cli registers ``view`` from command.py, and command.py reuses cli's options: importing
# cli first, whichever of the two a program imports first, keeps that cycle working.
import blueprint.cli  # noqa: F401
from blueprint.viewer.state import VIEW_KEYS, ViewState

__all__ = ["VIEW_KEYS", "ViewState", "run_viewer"]


def run_viewer(*args, **kwargs):
    """Open the viewer on a model file (see ``blueprint.viewer.app.run_viewer``)."""
    from blueprint.viewer.app import run_viewer as run

    return run(*args, **kwargs)
