"""Occlusion queries by name: every set of query slots has one owner and one name, so passes
of different modules never count into each other's slots."""

from __future__ import annotations


class QuerySet:
    """Sample-counting queries ``0, 1, ...`` of one name, created on first use."""

    def __init__(self, ctx) -> None:
        self.ctx = ctx
        self._queries: list = []

    def __getitem__(self, index: int):
        try:
            return self._queries[index]  # a peel asks twice a layer
        except IndexError:
            while len(self._queries) <= index:
                self._queries.append(self.ctx.query(samples=True))
            return self._queries[index]

    def release(self) -> None:
        # moderngl queries have no release of their own: they go with their context
        self._queries.clear()


class Queries:
    """Every query set of one context, by name."""

    def __init__(self, ctx) -> None:
        self.ctx = ctx
        self._sets: dict[str, QuerySet] = {}

    def __call__(self, name: str) -> QuerySet:
        held = self._sets.get(name)
        if held is None:
            held = self._sets[name] = QuerySet(self.ctx)
        return held

    def release(self) -> None:
        for held in self._sets.values():
            held.release()
        self._sets.clear()
