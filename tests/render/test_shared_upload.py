"""A pass that reads no normals (the vector drawings' faces, the ID peel) draws with a copy of
the model already uploaded with normals: the same depths and faces, one upload held."""

from __future__ import annotations

import numpy as np

import blueprint
from blueprint import examples

SIZE = (160, 120)


def test_an_id_peel_after_a_picture_draws_with_its_upload(renderer):
    model = examples.gearbox()
    options = dict(size=SIZE, max_layers=None, normals=False, renderer=renderer)

    def uploads():
        return [key for key, (m, _) in renderer.capturer._meshes.items() if m is model]

    alone = blueprint.peel(model, **options)
    assert [key[1] for key in uploads()] == [None]
    renderer.forget(model)
    blueprint.render(model, size=SIZE, renderer=renderer)  # uploaded with normals (crease splits)
    after = blueprint.peel(model, **options)
    assert [key[1] for key in uploads()] == [30.0]
    assert len(alone.depth) == len(after.depth) > 2
    np.testing.assert_array_equal(alone.depth, after.depth)
    np.testing.assert_array_equal(alone.triangle, after.triangle)
    renderer.forget(model)


def test_an_upload_remade_for_an_id_pass_keeps_to_its_own_crease(renderer):
    """Where the copy with normals must be uploaded again (in smaller chunks), the pass without
    normals uploads its own: a picture after it still draws with normals."""
    model = examples.gearbox()
    chunk = model.triangle_count // 3
    renderer.forget(model)
    try:
        renderer.chunk_faces = chunk
        expected = blueprint.render(model, size=SIZE, renderer=renderer)
        renderer.forget(model)
        renderer.chunk_faces = None
        blueprint.render(model, size=SIZE, renderer=renderer)  # uploaded whole, with normals
        renderer.chunk_faces = chunk
        blueprint.peel(model, size=SIZE, normals=False, renderer=renderer)  # no longer fits whole
        after = blueprint.render(model, size=SIZE, renderer=renderer)
    finally:
        renderer.chunk_faces = None
        renderer.forget(model)
    np.testing.assert_array_equal(after, expected)
