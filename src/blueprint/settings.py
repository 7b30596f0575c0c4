"""Files of settings a user writes (glyphs, line styles): TOML or JSON, read and checked with one
line per problem naming the file and the entry."""

from __future__ import annotations

import json
import math
import os
import tomllib
from pathlib import Path
from typing import Any

from blueprint.color import RGBA, hex_color
from blueprint.errors import InputError

__all__ = ["Entry", "is_number", "one_line", "read_settings", "show"]


def read_settings(path: str | os.PathLike, what: str) -> Any:
    """The data of a ``.toml`` or ``.json`` file (``what`` names it in errors: "glyph file")."""
    path = Path(path)
    name = str(path)
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise InputError(f"{name}: {what} must end in .toml or .json")
    try:
        raw = path.read_bytes()
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{name}: is a directory") from None
    except OSError as exc:
        raise InputError(f"{name}: cannot read ({exc.strerror or exc})") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{name}: not UTF-8 text") from None
    if suffix == ".toml":
        try:
            return tomllib.loads(text)
        except tomllib.TOMLDecodeError as exc:
            raise InputError(f"{name}: not valid TOML ({one_line(exc)})") from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise InputError(f"{name}: not valid JSON ({exc.msg} at line {exc.lineno})") from None


def one_line(exc: Exception) -> str:
    return " ".join(str(exc).split())


def show(value: Any) -> str:
    """A value as an error message quotes it: short, on one line."""
    text = one_line(repr(value)) if not isinstance(value, str) else repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def is_number(value: Any) -> bool:
    return isinstance(value, int | float) and not isinstance(value, bool)


class Entry:
    """One table of a file: checks its keys and values, naming ``where`` in every error."""

    def __init__(self, where: str, table: Any, allowed: tuple[str, ...], required=()) -> None:
        self.where = where
        if not isinstance(table, dict):
            raise InputError(f"{where}: must be a table of keys, got {show(table)}")
        for key in table:
            if key not in allowed:
                raise InputError(f"{where}: unknown key {key!r} (allowed: {', '.join(allowed)})")
        for key in required:
            if key not in table:
                raise InputError(f"{where}: {key} is missing")
        self.table = table

    def fail(self, message: str) -> InputError:
        return InputError(f"{self.where}: {message}")

    def number(self, key: str, default: float, lo: float, hi: float, lo_open: bool = False) -> float:
        value = self.table.get(key, default)
        if not is_number(value):
            raise self.fail(f"{key} must be a number, got {show(value)}")
        if not math.isfinite(value):
            raise self.fail(f"{key} must be a finite number, got {show(value)}")
        if value < lo or value > hi or (lo_open and value == lo):
            bracket = "(" if lo_open else "["
            raise self.fail(f"{key} must be in {bracket}{lo:g}, {hi:g}], got {value:g}")
        return float(value)

    def point(self, key: str, value: Any = None) -> tuple[float, float, float]:
        value = self.table[key] if value is None else value
        if not isinstance(value, list | tuple) or len(value) != 3 or not all(map(is_number, value)):
            raise self.fail(f"{key} must be 3 numbers, got {show(value)}")
        if not all(math.isfinite(v) for v in value):
            raise self.fail(f"{key} must be finite numbers, got {show(value)}")
        return tuple(float(v) for v in value)

    def color(self, key: str, default: str) -> RGBA:
        value = self.table.get(key, default)
        if not isinstance(value, str):
            raise self.fail(f"{key} must be a string #rrggbb, got {show(value)}")
        try:
            return hex_color(value)
        except InputError:
            raise self.fail(f"{key} {value!r} is not of the form #rrggbb") from None

    def string(self, key: str, default: str, nonempty: bool = False) -> str:
        value = self.table.get(key, default)
        if not isinstance(value, str):
            raise self.fail(f"{key} must be a string, got {show(value)}")
        if nonempty and not value.strip():
            raise self.fail(f"{key} must not be empty")
        return value

    def choice(self, key: str, default: str, allowed: tuple[str, ...]) -> str:
        value = self.table.get(key, default)
        if value not in allowed:
            raise self.fail(f"{key} must be one of {', '.join(allowed)}, got {show(value)}")
        return value

    def boolean(self, key: str, default: bool) -> bool:
        value = self.table.get(key, default)
        if not isinstance(value, bool):
            raise self.fail(f"{key} must be true or false, got {show(value)}")
        return value

    def dash(
        self, key: str = "dash", default=None, unit: str = "pixels", solid_ok: bool = False
    ) -> tuple[float, ...] | None:
        """An even count of on, off lengths; with ``solid_ok``, ``[]`` (a solid line) gives ``()``."""
        value = self.table.get(key, default)
        if value is None:
            return None
        if solid_ok and isinstance(value, list | tuple) and len(value) == 0:
            return ()
        message = f"{key} must be an even count (2 to 16) of positive lengths in {unit} (on, off, ...)"
        if (
            not isinstance(value, list | tuple)
            or not 2 <= len(value) <= 16
            or len(value) % 2
            or not all(map(is_number, value))
        ):
            raise self.fail(f"{message}, got {show(value)}")
        if not all(math.isfinite(v) and 0 < v <= 1000 for v in value):
            raise self.fail(f"{message}, got {show(value)}")
        return tuple(float(v) for v in value)
