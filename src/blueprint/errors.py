"""Errors that carry a one-line message meant for the user."""

import contextlib
import unicodedata
from collections.abc import Iterator


class BlueprintError(Exception):
    """Base class: the CLI prints ``str(error)`` on one line and exits with code 2."""


class InputError(BlueprintError):
    """A model file, argument or output path that cannot be used."""


class GLUnavailableError(BlueprintError):
    """No usable OpenGL 3.3 context could be created."""


class ShaderError(BlueprintError):
    """A shader failed to compile or link; the message names the file and line."""


_ESCAPES = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}


def printable(text: str) -> str:
    """``text`` safe to print on one line, whatever the file names in it hold: the bytes of a
    name that are not UTF-8 (which Python decodes to lone surrogates, U+DC80 to U+DCFF, and
    which a UTF-8 stream refuses to encode) as ``\\xNN``, newlines and other control characters
    escaped (``\\n``, ``\\x1b``) so that a message can never span two lines or move the cursor."""
    out = []
    for c in text:
        code = ord(c)
        if c in _ESCAPES:
            out.append(_ESCAPES[c])
        elif 0xDC80 <= code <= 0xDCFF:
            out.append(f"\\x{code - 0xDC00:02x}")
        elif 0xD800 <= code <= 0xDFFF:
            out.append(f"\\u{code:04x}")
        elif unicodedata.category(c) in ("Cc", "Zl", "Zp"):
            out.append(f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}")
        else:
            out.append(c)
    return "".join(out)


@contextlib.contextmanager
def out_of_memory(name: str, hint: str = "try a smaller --size") -> Iterator[None]:
    """Turn a ``MemoryError`` inside the block into an ``InputError`` naming ``name``, the
    file being read or run (a model, a pipeline), with ``hint`` for what to change."""
    try:
        yield
    except MemoryError:
        raise InputError(f"{name}: out of memory ({hint})") from None
