"""Shader sources, the package's files and users' own: ``#include``, defines, and errors that
name file and line. The one preprocessor of the package."""

from __future__ import annotations

import importlib.util
import re
from functools import cache
from pathlib import Path

from blueprint.errors import ShaderError

VERSION = "#version 330 core"
COMPUTE_VERSION = "#version 430 core"
# Line numbers carry the file: line n of file k is numbered k * LINE_BASE + n, since some
# compilers (Mesa, for undeclared names) report source-string 0 whatever #line said.
LINE_BASE = 100_000
_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$')
# Mesa: "0:12(3): error: ..."; NVIDIA: "0(12) : error ..."
# NVIDIA's form swallows the space before its colon, so both read "file:line: error ..."
_LOCATION = re.compile(r"\b(\d+)(?::(\d+)\(\d+\)|\((\d+)\) ?(?=:))")


@cache
def package_files(package: str):
    """The folder of a package's files (shaders, presets): a ``Path`` where the package is
    installed as files, as pip installs it, else ``importlib.resources.files(package)`` (a
    package imported from a zip archive).

    Found from the package's import spec: importlib.resources would bring tempfile, shutil and
    zipfile into every drawing's start.
    """
    spec = importlib.util.find_spec(package)
    for location in (spec.submodule_search_locations or []) if spec is not None else []:
        folder = Path(location)
        if folder.is_dir():
            return folder
    from importlib import resources

    return resources.files(package)


@cache
def _read(package: str, name: str) -> str:
    if not _is_file(package, name):
        # the package's own shaders: one missing is a broken installation, not the user's input
        raise ShaderError(
            f"shader file {package}/{name} not found in {package_files(package)}: the installation "
            "is incomplete (reinstall blueprint-drawings)"
        )
    return package_files(package).joinpath(name).read_text(encoding="utf-8")


@cache
def _is_file(package: str, name: str) -> bool:
    """Whether the package has the file ``name``: asked for every ``#include`` of every program
    a frame builds, answered once."""
    return package_files(package).joinpath(name).is_file()


def _resolve(ref: str) -> tuple[str, str]:
    """'pkg.mod:file.glsl' or 'file.glsl' (in blueprint.gpu's glsl folder)."""
    if ":" in ref:
        package, name = ref.split(":", 1)
        return package, name
    return "blueprint.gpu", f"glsl/{ref}"


def _source(ref: str | Path) -> tuple[str, str, object]:
    """(name for messages, text, where its includes are looked for first: a folder on disk, or
    the package and folder it lies in) of a file reference or a user's file."""
    if isinstance(ref, Path):
        if not ref.is_file():
            raise ShaderError(f"shader file {ref} not found")
        try:
            text = ref.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise ShaderError(f"cannot read shader {ref}: {exc}") from None
        return str(ref), text, ref.parent
    package, name = _resolve(ref)
    folder = name.rsplit("/", 1)[0] + "/" if "/" in name else ""
    return f"{package.replace('.', '/')}/{name}", _read(package, name), (package, folder)


def _include(target: str, here: object) -> str | Path:
    """An ``#include``'s file: beside the including file first, else blueprint's own
    ``gpu/glsl`` files (``depth.glsl``...)."""
    if ":" in target:
        return target
    if isinstance(here, Path):
        local = here / target
        if local.is_file():
            return local
        if not _is_file("blueprint.gpu", f"glsl/{target}"):
            raise ShaderError(f"shader file {local} not found")
        return target
    package, folder = here
    if package != "blueprint.gpu" and _is_file(package, folder + target):
        return f"{package}:{folder}{target}"
    return target


def preprocess(
    ref: str | Path, defines: dict[str, object] | None = None, version: str | None = VERSION
) -> tuple[str, list[str]]:
    """Expand includes and prepend the version (None: none) and defines. ``ref`` is a file
    reference (``"package:path"``, or a bare name in ``blueprint/gpu/glsl``) or a user's file
    (a Path, whose own ``#version`` lines are dropped).

    Returns the source and the list of file names, indexed as the ``#line`` directives number
    them (see ``LINE_BASE``), so compiler messages can be mapped back to files.
    """
    files: list[str] = []

    def expand(ref: str | Path, stack: tuple[str, ...]) -> list[str]:
        name, text, here = _source(ref)
        if name in stack:
            raise ShaderError(f"#include cycle through {' -> '.join((*stack, name))}")
        index = len(files)
        files.append(name)
        out = [f"#line {index * LINE_BASE + 1} {index}"]
        for number, line in enumerate(text.splitlines(), start=1):
            match = _INCLUDE.match(line)
            if match:
                out += expand(_include(match.group(1), here), (*stack, name))
                out.append(f"#line {index * LINE_BASE + number + 1} {index}")
            elif line.lstrip().startswith("#version"):
                out.append("")
            else:
                out.append(line)
        return out

    head = [version] if version else []
    head += [f"#define {k} {_literal(v)}" for k, v in (defines or {}).items()]
    return "\n".join(head + expand(ref, ())) + "\n", files


def _literal(value: object) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    return str(value)


def _explain(message: str, files: list[str]) -> str:
    def name(match: re.Match) -> str:
        index, line = divmod(int(match.group(2) or match.group(3)), LINE_BASE)
        return f"{files[index]}:{line}" if index < len(files) else match.group(0)

    lines = [ln.strip() for ln in message.strip().splitlines() if ln.strip()]
    first = next((ln for ln in lines if "error" in ln.lower()), lines[0] if lines else message)
    return _LOCATION.sub(name, first, count=1)


def build_program(
    ctx,
    vertex: str,
    fragment: str,
    defines: dict[str, object] | None = None,
    version: str = VERSION,
    geometry: str | None = None,
):
    """Compile and link a program from shader file references (GLSL ``version``), with a
    geometry shader where ``geometry`` names one.

    References are ``"package:path"`` or a bare name in ``blueprint/gpu/glsl``.

    Raises
    ------
    ShaderError
        One line naming the file and line the compiler complained about.
    """
    vs, vs_files = preprocess(vertex, defines, version)
    fs, fs_files = preprocess(fragment, defines, version)
    gs, gs_files = preprocess(geometry, defines, version) if geometry else (None, [])
    try:
        return ctx.program(vertex_shader=vs, fragment_shader=fs, geometry_shader=gs)
    except Exception as exc:
        text = str(exc)
        lowered = text.lower()
        files = fs_files if "fragment" in lowered else gs_files if "geometry" in lowered else vs_files
        raise ShaderError(f"shader error: {_explain(text, files)}") from None


def build_compute(ctx, ref: str, defines: dict[str, object] | None = None):
    """Compile a compute shader (OpenGL 4.3) from a file reference; errors as ``build_program``."""
    source, files = preprocess(ref, defines, COMPUTE_VERSION)
    try:
        return ctx.compute_shader(source)
    except Exception as exc:
        raise ShaderError(f"shader error: {_explain(str(exc), files)}") from None
