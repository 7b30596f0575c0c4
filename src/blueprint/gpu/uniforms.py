"""Uniform values by program: each written only when it changed and only where the program
declares it. Every write to a program kept here must go through it, or the cache lies."""

from __future__ import annotations

_UNSET = object()


class Uniforms:
    def __init__(self) -> None:
        # program -> {name of each uniform it declares: the value it last got}; keyed by the
        # program itself, not its GL name, which a program built after one released may reuse.
        # Looked up with operators, not dict methods: a streamed frame sets dozens.
        self._values: dict[object, dict[str, object]] = {}

    def _learn(self, prog) -> dict[str, object]:
        values = self._values[prog] = dict.fromkeys(prog, _UNSET)
        return values

    def has(self, prog, name: str) -> bool:
        values = self._values[prog] if prog in self._values else self._learn(prog)
        return name in values

    def set(self, prog, name: str, value) -> None:
        values = self._values[prog] if prog in self._values else self._learn(prog)
        if name not in values or values[name] == value:
            return
        values[name] = value
        _write(prog[name], value)

    def update(self, prog, values: dict) -> None:
        """``set`` for each of ``values`` (name -> value) in one call."""
        held = self._values[prog] if prog in self._values else self._learn(prog)
        for name, value in values.items():
            if name not in held or held[name] == value:
                continue
            held[name] = value
            _write(prog[name], value)

    def forget(self, prog) -> None:
        """Drop a program about to be released."""
        self._values.pop(prog, None)


def _write(member, value) -> None:
    """A uniform's new value (matrices come as bytes; an array as a tuple, of which moderngl
    takes the first alone where the array has one element or the compiler kept only one)."""
    if isinstance(value, bytes):
        member.write(value)
    elif isinstance(value, tuple) and member.array_length == 1 and member.dimension == 1:
        member.value = value[0]
    else:
        member.value = value
