"""Files of settings a user writes (glyphs, line styles): TOML or JSON, read and checked with one
line per problem naming the file and the entry; and ``check_file`` / ``read_file``, through
which every file a user gives (models and what they reference, settings, pipelines, images) is
read: regular files only, of a bounded size, both known from ``stat`` before anything is opened.
"""

from __future__ import annotations

import errno
import math
import os
import stat
from pathlib import Path
from typing import Any, BinaryIO

from blueprint.color import RGBA, hex_color
from blueprint.errors import InputError

__all__ = [
    "COINCIDENT_LIMIT",
    "COORDINATE_LIMIT",
    "EXPANDED_LIMIT",
    "EXPANSION_RATIO_LIMIT",
    "FRAME_LIMIT",
    "GLYPH_LIMIT",
    "IMAGE_FILE_LIMIT",
    "IMAGE_PIXEL_LIMIT",
    "INSTANCE_BYTES",
    "INSTANCE_LIMIT",
    "MEMORY_BUDGET",
    "MEMORY_ENV",
    "MODEL_FILE_LIMIT",
    "PART_BYTES",
    "PICTURE_TRIANGLE_BYTES",
    "PLACED_TRIANGLE_BYTES",
    "SAMPLE_BYTES",
    "SEGMENT_BYTES",
    "SETTINGS_FILE_LIMIT",
    "THREADS",
    "THREADS_ENV",
    "TRIANGLE_BYTES",
    "Entry",
    "available_memory",
    "check_file",
    "human_size",
    "memory_budget",
    "is_number",
    "one_line",
    "open_file",
    "parse_size",
    "parse_text",
    "read_at_most",
    "read_file",
    "read_settings",
    "show",
    "thread_count",
]

# The memory one run may plan to use: what the limits below are derived from, so that a
# machine with little memory refuses a big file in one line instead of being killed mid-read.
MEMORY_ENV = "BLUEPRINT_MEMORY_LIMIT"
_MEMORY_CAP = 16 << 30
_MEMORY_FLOOR = 64 << 20


def available_memory() -> int:
    """Bytes this process may still use: the memory the kernel reports available, or less
    where an address-space limit (``ulimit -v``) is set."""
    available = None
    try:
        with open("/proc/meminfo", "rb") as fh:
            for line in fh:
                if line.startswith(b"MemAvailable:"):
                    available = int(line.split()[1]) * 1024
                    break
    except (OSError, ValueError, IndexError):
        pass
    if available is None:
        try:
            available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (OSError, ValueError, AttributeError):
            available = 4 * _MEMORY_CAP
    try:
        import resource

        soft = resource.getrlimit(resource.RLIMIT_AS)[0]
        if soft != resource.RLIM_INFINITY:
            available = min(available, soft)
    except (ImportError, OSError, ValueError):
        pass
    return available


def memory_budget() -> int:
    """Bytes of memory the limits on inputs are set from: a quarter of the memory available,
    at most 16 GiB; the environment variable ``BLUEPRINT_MEMORY_LIMIT`` (bytes, or with a
    suffix K, M or G; at least 1 MiB) sets it instead."""
    # checked here, at import, where an error could not be one line: a value that is not a
    # size leaves the default
    size = parse_size(os.environ.get(MEMORY_ENV, ""))
    if size is not None:
        return max(size, 1 << 20)
    return max(min(available_memory() // 4, _MEMORY_CAP), _MEMORY_FLOOR)


def parse_size(text: str) -> int | None:
    """Bytes as an environment variable gives them: digits, or digits and a suffix K, M or G
    (powers of 1024); None where ``text`` is no such size."""
    text = text.strip()
    scale = {"K": 1 << 10, "M": 1 << 20, "G": 1 << 30}.get(text[-1:].upper(), 1)
    digits = text[:-1] if scale > 1 else text
    if digits.isdigit() and len(digits) <= 15:
        return int(digits) * scale
    return None


MEMORY_BUDGET = memory_budget()
# The threads a model's preparation splits its work over (blueprint.parallel).
THREADS_ENV = "BLUEPRINT_THREADS"


def thread_count() -> int:
    """Threads for the work on large arrays: the cores this process may run on (at most 64);
    the environment variable ``BLUEPRINT_THREADS`` (a whole number, at least 1) sets it
    instead."""
    text = os.environ.get(THREADS_ENV, "").strip()
    # checked at import, where an error could not be one line: a value that is not a count
    # leaves the default
    if text.isdigit() and 0 < int(text) <= 1024:
        return int(text)
    try:
        cores = len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        cores = os.cpu_count() or 1
    return max(1, min(cores, 64))


THREADS = thread_count()
# Largest files read, in bytes: they are read whole into memory (trimesh, Pillow, the TOML and
# JSON parsers) and copied a few times over, so a sparse or endless file must be refused before
# it is read, not while.
MODEL_FILE_LIMIT = min(2 << 30, MEMORY_BUDGET // 4)  # a model, or a file it references
# what the archives of models (zip, 3MF, 3DXML, .gz, .bz2, .xz) may expand to, all members
# together, and how many times their compressed size: a few kilobytes can expand to gigabytes
EXPANDED_LIMIT = MODEL_FILE_LIMIT
EXPANSION_RATIO_LIMIT = 200
IMAGE_FILE_LIMIT = min(1 << 30, MEMORY_BUDGET // 4)  # a pipeline's image input
SETTINGS_FILE_LIMIT = 16 << 20  # settings, line style, glyph and pipeline files
# Pixels an image input may declare (at most 256 MiB as RGBA, and four floats a pixel on the GPU
# within the budget): its header is read before any pixel, and a few kilobytes of PNG can
# declare an image larger than memory.
IMAGE_PIXEL_LIMIT = min(1 << 26, MEMORY_BUDGET // 16)
# Memory a drawn triangle takes at the peak of a drawing (loading, preparing, the GPU's copy,
# the lines of a vector drawing), over what the process holds before it: the peak's growth a
# triangle of the vector drawing, the larger, of benchmarks/scale.py's scans with a third more
# as a margin (benchmarks/notes/memory-guard.md). From it, the peak a model's header counts
# foretell (scene.headers.peak_estimate) and the triangles a model may have, all instances
# together (refused before they are made).
TRIANGLE_BYTES = 896
# ...and a vector drawing's line sample (about a pixel of line apart), beside its triangles: the
# samples grow with the drawing's size, not its triangles (a field of boxes at 8192 x 8192 took
# seven times its triangles' share); the peak's growth a sample from the samples' making on, the
# larger, of benchmarks/scale.py's engines and a field of boxes, with a third more
# (benchmarks/notes/memory-guard.md). Weighed once the lines are joined, before any sample is made.
SAMPLE_BYTES = 672
# ...and a vector drawing of a scene kept as instances, whose lines are found once a mesh and
# placed an instance at a time: a drawn triangle with its lines aside (the faces' planes and
# parts; a field of instanced spheres, whose lines are few), and a line segment placed (through
# their joining; instanced engines and a field of boxes), each the larger measured with a third
# more (benchmarks/notes/memory-guard.md). Weighed before any line is found, as the segments are
# placed, and with the samples (SAMPLE_BYTES) before they are made.
PLACED_TRIANGLE_BYTES = 128
SEGMENT_BYTES = 672
# ...and where the model is drawn only as pictures (scene.headers.pictures_only: no lines'
# adjacency), the growth a triangle of the PNG of a soup, the larger, with the same margin.
PICTURE_TRIANGLE_BYTES = 512
# ...and an instance of a scene kept as instances (scene.instances): the peak's growth an
# instance of a GLB of 10^5 instances of a box drawn to a PNG, with a third more as a margin
# (benchmarks/notes/instances.md); its unique triangles count at TRIANGLE_BYTES.
INSTANCE_BYTES = 3072
# ...and an instance of a scene flattened into one mesh, each a part with a name and, in a
# scene of distinct parts (a building's elements), a mesh of its own as the file holds it: the
# peak's growth a part of a GLB of 3 x 10^5 distinct one-triangle meshes, with a third more
# (benchmarks/notes/memory-guard.md).
PART_BYTES = 4864
# the mesh instances a scene may place, kept or flattened: those the budget holds at the least
# an instance takes, counted as a node graph is walked so that a graph that places a mesh
# millions of times over is refused before they are counted out
INSTANCE_LIMIT = MEMORY_BUDGET // INSTANCE_BYTES
# Frames of a video (an hour at 30 frames a second would be 108 000), glyphs of a glyph file (each
# is projected and stroked on the CPU), and the largest coordinate of a model or a glyph: beyond
# it, view and projection matrices overflow the GPU's 32-bit floats.
FRAME_LIMIT = 100_000
# copies of one triangle a model may hold: each is a layer to the peel, which stops at 256
COINCIDENT_LIMIT = 256
GLYPH_LIMIT = 10_000
COORDINATE_LIMIT = 1e18
# Settings and pipeline files: how deep tables and arrays nest and how many digits a number has;
# a 10^4-deep array or a 5000-digit integer is refused with the file and key named.
SETTINGS_DEPTH_LIMIT = 32
SETTINGS_DIGITS_LIMIT = 100
_TOO_BIG = 10**SETTINGS_DIGITS_LIMIT

_NOT_REGULAR = (
    (stat.S_ISDIR, "a directory"),
    (stat.S_ISFIFO, "a FIFO"),
    (stat.S_ISCHR, "a character device"),
    (stat.S_ISBLK, "a block device"),
    (stat.S_ISSOCK, "a socket"),
)


def human_size(n: int) -> str:
    """A count of bytes as messages give it: "3 GiB", "1.76 KiB", "100 bytes"."""
    for unit, scale in (("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)):
        if n >= scale:
            return f"{n / scale:.3g} {unit}"
    return f"{n} bytes"


def _checked(name: str, info: os.stat_result, limit: int | None, what: str) -> os.stat_result:
    if not stat.S_ISREG(info.st_mode):
        kind = next((k for test, k in _NOT_REGULAR if test(info.st_mode)), "a special file")
        raise InputError(f"{name}: not a regular file ({kind})")
    if limit is not None and info.st_size > limit:
        raise InputError(
            f"{name}: {human_size(info.st_size)} is over the limit of {human_size(limit)} for {what}"
        )
    return info


def check_file(path: str | os.PathLike, limit: int | None, what: str = "a file") -> os.stat_result:
    """``path``'s ``stat`` if it is a regular file of at most ``limit`` bytes (``None``: any size;
    ``what`` names the file's role in the message: "a model file"), else a one-line InputError.

    Nothing is opened: opening a FIFO for reading blocks until a writer comes, a device reads
    without end and a sparse file can be far larger than memory, so a reader that cannot bound
    its reads itself (trimesh, Pillow, ffmpeg) calls this first."""
    name = str(path)
    try:
        info = os.stat(path)
    except FileNotFoundError:
        raise InputError(f"{name}: no such file") from None
    except OSError as exc:  # a name too long, a path through a file, a loop of links
        raise InputError(f"{name}: cannot read ({exc.strerror or exc})") from None
    return _checked(name, info, limit, what)


def open_file(path: str | os.PathLike, limit: int, what: str = "a file") -> BinaryIO:
    """``path`` open for reading, checked as ``check_file`` does, and again on the open file,
    which might have been swapped for a FIFO in between (opened without blocking for that
    reason)."""
    check_file(path, limit, what)
    name = str(path)
    try:
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as exc:
        if exc.errno == errno.ENOENT:
            raise InputError(f"{name}: no such file") from None
        raise InputError(f"{name}: cannot read ({exc.strerror or exc})") from None
    fh = os.fdopen(fd, "rb")
    try:
        _checked(name, os.fstat(fd), limit, what)
    except InputError:
        fh.close()
        raise
    return fh


def read_at_most(fh: BinaryIO, most: int) -> bytes:
    """At most ``most`` bytes of ``fh`` from where it stands, read into room for what the file
    holds: ``fh.read(most)`` takes room for ``most`` bytes at once, the gigabytes of a model
    file's limit for a file of kilobytes. Should the file grow while it is read, what it grew
    by is read on, up to ``most``."""
    try:
        left = os.fstat(fh.fileno()).st_size - fh.tell()
    except (AttributeError, OSError, ValueError):
        return fh.read(most)  # a stream in memory, which holds what it reads already
    first = fh.read(min(max(left, 0) + 1, most))
    if len(first) <= left:
        return first
    return first + fh.read(most - len(first))


def read_file(path: str | os.PathLike, limit: int, what: str = "a file") -> bytes:
    """The bytes of a regular file of at most ``limit`` bytes (see ``open_file``); no more than
    ``limit`` bytes are ever read, should the file grow after the check."""
    with open_file(path, limit, what) as fh:
        try:
            data = read_at_most(fh, limit + 1)
        except OSError as exc:
            raise InputError(f"{path}: cannot read ({exc.strerror or exc})") from None
    if len(data) > limit:
        raise InputError(f"{path}: over the limit of {human_size(limit)} for {what}")
    return data


def read_settings(path: str | os.PathLike, what: str) -> Any:
    """The data of a ``.toml`` or ``.json`` file (``what`` names it in errors: "glyph file")."""
    path = Path(path)
    name = str(path)
    suffix = path.suffix.lower()
    if suffix not in (".toml", ".json"):
        raise InputError(f"{name}: {what} must end in .toml or .json")
    raw = read_file(path, SETTINGS_FILE_LIMIT, f"a {what}")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError:
        raise InputError(f"{name}: not UTF-8 text") from None
    return parse_text(text, name, suffix[1:])


def _number_text(name: str, kind: type):
    def parse(digits: str):
        if len(digits) > SETTINGS_DIGITS_LIMIT:
            raise InputError(f"{name}: a number of {len(digits)} digits (at most {SETTINGS_DIGITS_LIMIT})")
        return kind(digits)

    return parse


def parse_text(text: str, name: str, fmt: str) -> Any:
    """The data of TOML or JSON ``text`` (``fmt`` "toml" or "json") from the file ``name``, with
    nesting depth and number sizes bounded: a one-line InputError naming the file and the key."""
    # each parser imported by the runs that read its format: tomllib compiles regular
    # expressions at import, and a picture reads its pipeline's TOML but no JSON
    floats = _number_text(name, float)
    try:
        if fmt == "toml":
            data = _toml(text, name, floats)
        else:
            data = _json(text, name, floats)
    except RecursionError:
        raise InputError(f"{name}: tables or arrays nested deeper than {SETTINGS_DEPTH_LIMIT}") from None
    except ValueError:  # Python's own limit on the digits of an integer, met inside tomllib
        raise InputError(f"{name}: a number of too many digits (at most {SETTINGS_DIGITS_LIMIT})") from None
    _check_tree(data, name)
    return data


def _toml(text: str, name: str, floats) -> Any:
    import tomllib

    try:
        return tomllib.loads(text, parse_float=floats)
    except tomllib.TOMLDecodeError as exc:
        raise InputError(f"{name}: not valid TOML ({one_line(exc)})") from None


def _json(text: str, name: str, floats) -> Any:
    import json

    try:
        return json.loads(text, parse_int=_number_text(name, int), parse_float=floats)
    except json.JSONDecodeError as exc:
        raise InputError(f"{name}: not valid JSON ({exc.msg} at line {exc.lineno})") from None


def _check_tree(data: Any, name: str) -> None:
    # Walked with a stack, not recursion: the parsers' own recursion limit is far above ours.
    stack = [(data, "", 0)]
    while stack:
        value, key, depth = stack.pop()
        if depth > SETTINGS_DEPTH_LIMIT:
            raise InputError(f"{name}: {key}: nested deeper than {SETTINGS_DEPTH_LIMIT}")
        if isinstance(value, dict):
            stack.extend((v, f"{key}.{k}" if key else str(k), depth + 1) for k, v in value.items())
        elif isinstance(value, list):
            stack.extend((v, f"{key}[{i}]", depth + 1) for i, v in enumerate(value))
        elif isinstance(value, int) and not isinstance(value, bool) and abs(value) >= _TOO_BIG:
            raise InputError(f"{name}: {key}: a number of too many digits (at most {SETTINGS_DIGITS_LIMIT})")


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
        # bounded as model coordinates are: beyond, a projection overflows
        if not all(math.isfinite(v) and abs(v) <= COORDINATE_LIMIT for v in value):
            raise self.fail(f"{key} must be finite numbers within ±{COORDINATE_LIMIT:g}, got {show(value)}")
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
