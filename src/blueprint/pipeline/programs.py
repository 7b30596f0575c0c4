"""The executor's programs: full-screen passes of the library's operations and of users' own
shaders and their vertex arrays; uniforms go through the device's cache of the values each
program last got."""

from __future__ import annotations

from pathlib import Path

from blueprint.errors import ShaderError
from blueprint.gpu.shaders import VERSION, _explain, preprocess
from blueprint.pipeline.user import user_source

FULLSCREEN = "fullscreen.vert"
# programs of the pipeline are built with this define, so they are instances of their own and
# the uniform cache is never fooled by other code setting the same program's uniforms
OWN = {"BLUEPRINT_PIPELINE": 1}


class Programs:
    """Programs on ``r``'s context (library shaders through ``r``'s cache, user shaders here,
    rebuilt when their file changes); ``set`` writes a uniform only when its value changed
    and only where the program declares it (``gpu.uniforms``)."""

    def __init__(self, r) -> None:
        self.r, self.ctx = r, r.ctx
        # the device's cache itself, not a method of ours around it: a frame sets hundreds
        self.has, self.set, self.update = r.uniforms.has, r.uniforms.set, r.uniforms.update
        self._vaos: dict[int, object] = {}
        self._user: dict[tuple, object] = {}

    def release(self) -> None:
        for prog in self._user.values():
            self.r.uniforms.forget(prog)
            prog.release()
        for vao in self._vaos.values():
            vao.release()
        self._user.clear()
        self._vaos.clear()

    def library(self, fragment: str, vertex: str = FULLSCREEN, defines=None, modern: bool = False):
        return self.r.program(fragment, vertex, {**OWN, **(defines or {})}, modern)

    def compute(self, ref: str, defines=None):
        return self.r.compute(ref, {**OWN, **(defines or {})})

    def user(self, path: Path):
        key = (str(path), path.stat().st_mtime_ns)
        prog = self._user.get(key)
        if prog is None:
            text, files = user_source(path, str(path), "shader")
            vs, _ = preprocess(FULLSCREEN)
            try:
                prog = self.ctx.program(vertex_shader=vs, fragment_shader=f"{VERSION}\n{text}")
            except Exception as exc:
                raise ShaderError(f"shader error: {_explain(str(exc), files)}") from None
            self._user[key] = prog
        return prog

    def vao(self, prog):
        """The empty vertex array a full-screen triangle draws with."""
        vao = self._vaos.get(prog.glo)
        if vao is None:
            vao = self._vaos[prog.glo] = self.ctx.vertex_array(prog, [])
        return vao
