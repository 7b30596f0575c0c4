"""Uniform values by program: each written only when it changed and only where the program
declares it. Every write to a program kept here must go through it, or the cache lies."""

from __future__ import annotations


class Uniforms:
    def __init__(self) -> None:
        self._values: dict[tuple[int, str], object] = {}
        self._members: dict[int, set[str]] = {}

    def has(self, prog, name: str) -> bool:
        members = self._members.get(prog.glo)
        if members is None:
            members = self._members[prog.glo] = set(prog)
        return name in members

    def set(self, prog, name: str, value) -> None:
        glo = prog.glo
        members = self._members.get(glo)
        if members is None:
            members = self._members[glo] = set(prog)
        if name not in members:
            return
        key = (glo, name)
        if self._values.get(key) == value:
            return
        self._values[key] = value
        member = prog[name]
        if isinstance(value, bytes):
            member.write(value)
        else:
            member.value = value
