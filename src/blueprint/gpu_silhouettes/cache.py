"""The tables of static models, uploaded on a model's first drawing and kept until it is
forgotten, so that drawing a model again uploads nothing."""

from __future__ import annotations

from dataclasses import dataclass

from blueprint.scene.model import Model
from blueprint.silhouette.edgerecords import edge_records
from blueprint.silhouette.idlist import build_id_lists
from blueprint.silhouette.mesh import build_adjacency

from .lines import EdgeBuffer
from .tables import TABLE_WIDTH, Corners, ListTextures, _rows, diagonal


@dataclass
class Held:
    """What a static model holds on the GPU besides the renderer's upload."""

    model: Model
    corners: Corners
    tolerance: float
    diagonal: float
    lists: ListTextures | None = None
    edges: EdgeBuffer | None = None

    def release(self) -> None:
        self.corners.release()
        for held in (self.lists, self.edges):
            if held is not None:
                held.release()


class ModelTables:
    """Corner, ID-list and edge tables per static model, on the context `ctx`.

    Models are told apart by identity. `tolerance` is a fraction of each model's bounding-box
    diagonal. Call with the context current.
    """

    def __init__(self, ctx, tolerance: float) -> None:
        self.ctx = ctx
        self.tolerance = tolerance
        self._held: dict[int, Held] = {}

    def entry(self, model: Model) -> Held:
        """The model's corners and welding tolerance, uploaded on first use."""
        held = self._held.get(id(model))
        if held is None or held.model is not model:
            corners = model.positions[model.faces]
            store = Corners(self.ctx, len(model.faces))
            store.write(corners)
            size = diagonal(corners)
            held = self._held[id(model)] = Held(model, store, self.tolerance * size, size)
        return held

    def to_upload(self, model: Model, *, lists: bool, edges: bool) -> dict[str, int]:
        """The GPU bytes at most that drawing ``model`` uploads into its tables where not held
        yet, by kind (``render.budget.frame_bytes``'s ``extra``): its corners (a buffer and the
        texture it is copied into), its edge records where ``edges`` (at most three edges a
        face), its ID lists where ``lists`` (at most a vertex and a list entry a corner). Each
        table is padded to whole rows of ``TABLE_WIDTH`` entries."""
        faces = model.triangle_count
        held = self._held.get(id(model))
        held = held if held is not None and held.model is model else None
        out = {}
        if held is None:
            out["corners"] = 2 * _rows(3 * faces) * TABLE_WIDTH * 12
        if edges and (held is None or held.edges is None):
            out["edge records"] = 3 * faces * 16
        if lists and (held is None or held.lists is None):
            # (F, 3) face vertices, (V, 2) pointers and K list entries, V and K at most 3 F
            out["ID lists"] = TABLE_WIDTH * (12 * _rows(faces) + 12 * _rows(3 * faces))
        return out

    def lists(self, model: Model) -> ListTextures:
        """The model's ID lists, built (welded with its tolerance) on first use."""
        held = self.entry(model)
        if held.lists is None:
            lists = build_id_lists(model.positions, model.faces, held.tolerance)
            held.lists = ListTextures(self.ctx, lists)
        return held.lists

    def edges(self, model: Model) -> EdgeBuffer:
        """The model's edge records, built (welded with its tolerance, oriented) on first use."""
        held = self.entry(model)
        if held.edges is None:
            adjacency = build_adjacency(model.positions, model.faces, held.tolerance)
            held.edges = EdgeBuffer(self.ctx, edge_records(adjacency))
        return held.edges

    def forget(self, model: Model) -> None:
        held = self._held.pop(id(model), None)
        if held is not None:
            held.release()

    def release(self) -> None:
        for model in [held.model for held in self._held.values()]:
            self.forget(model)
