"""Shader sources as package files: ``#include``, defines, and errors that name file and line."""

from __future__ import annotations

import re
from functools import cache
from importlib import resources

from blueprint.errors import ShaderError

VERSION = "#version 330 core"
COMPUTE_VERSION = "#version 430 core"
# Line numbers carry the file: line n of file k is numbered k * LINE_BASE + n, since some
# compilers (Mesa, for undeclared names) report source-string 0 whatever #line said.
LINE_BASE = 100_000
_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$')
# Mesa: "0:12(3): error: ..."; NVIDIA: "0(12) : error ..."
_LOCATION = re.compile(r"\b(\d+)(?::(\d+)\(\d+\)|\((\d+)\))")


@cache
def _read(package: str, name: str) -> str:
    path = resources.files(package).joinpath(name)
    if not path.is_file():
        raise ShaderError(f"shader file {package}/{name} not found")
    return path.read_text(encoding="utf-8")


def _resolve(ref: str) -> tuple[str, str]:
    """'pkg.mod:file.glsl' or 'file.glsl' (in blueprint.gpu's glsl folder)."""
    if ":" in ref:
        package, name = ref.split(":", 1)
        return package, name
    return "blueprint.gpu", f"glsl/{ref}"


def preprocess(
    ref: str, defines: dict[str, object] | None = None, version: str = VERSION
) -> tuple[str, list[str]]:
    """Expand includes and prepend the version and defines.

    Returns the source and the list of file names, indexed as the ``#line`` directives number
    them (see ``LINE_BASE``), so compiler messages can be mapped back to files.
    """
    files: list[str] = []

    def expand(ref: str, stack: tuple[str, ...]) -> list[str]:
        if ref in stack:
            raise ShaderError(f"{ref}: #include cycle through {' -> '.join(stack)}")
        package, name = _resolve(ref)
        index = len(files)
        files.append(f"{package.replace('.', '/')}/{name}")
        out = [f"#line {index * LINE_BASE + 1} {index}"]
        for number, line in enumerate(_read(package, name).splitlines(), start=1):
            match = _INCLUDE.match(line)
            if match:
                target = match.group(1)
                if ":" not in target and package != "blueprint.gpu":
                    folder = name.rsplit("/", 1)[0] + "/" if "/" in name else ""
                    local = resources.files(package).joinpath(folder + target)
                    target = f"{package}:{folder}{target}" if local.is_file() else target
                out += expand(target, (*stack, ref))
                out.append(f"#line {index * LINE_BASE + number + 1} {index}")
            else:
                out.append(line)
        return out

    head = [version] + [f"#define {k} {_literal(v)}" for k, v in (defines or {}).items()]
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
):
    """Compile and link a program from shader file references.

    References are ``"package:path"`` or a bare name in ``blueprint/gpu/glsl``.

    Raises
    ------
    ShaderError
        One line naming the file and line the compiler complained about.
    """
    vs, vs_files = preprocess(vertex, defines)
    fs, fs_files = preprocess(fragment, defines)
    try:
        return ctx.program(vertex_shader=vs, fragment_shader=fs)
    except Exception as exc:
        text = str(exc)
        files = fs_files if "fragment" in text.lower() else vs_files
        raise ShaderError(f"shader error: {_explain(text, files)}") from None


def build_compute(ctx, ref: str, defines: dict[str, object] | None = None):
    """Compile a compute shader (OpenGL 4.3) from a file reference; errors as ``build_program``."""
    source, files = preprocess(ref, defines, COMPUTE_VERSION)
    try:
        return ctx.compute_shader(source)
    except Exception as exc:
        raise ShaderError(f"shader error: {_explain(str(exc), files)}") from None
