"""Errors that carry a one-line message meant for the user."""


class BlueprintError(Exception):
    """Base class: the CLI prints ``str(error)`` on one line and exits with code 2."""


class InputError(BlueprintError):
    """A model file, argument or output path that cannot be used."""


class GLUnavailableError(BlueprintError):
    """No usable OpenGL 3.3 context could be created."""


class ShaderError(BlueprintError):
    """A shader failed to compile or link; the message names the file and line."""
