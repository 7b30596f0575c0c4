"""``blueprint.draw``: objects in (paths, trimesh meshes and scenes, arrays), a ``Drawing`` out
that Jupyter shows and that saves by suffix; objects that cannot be drawn raise one line."""

from __future__ import annotations

import io
import subprocess
import sys
import xml.etree.ElementTree as ET

import ezdxf
import numpy as np
import pytest
import trimesh
from IPython.core.formatters import DisplayFormatter
from PIL import Image

import blueprint
from blueprint import InputError, examples

SIZE = (96, 80)


@pytest.fixture(scope="module")
def scene() -> trimesh.Scene:
    """Two meshes, one of them instanced twice with translations, named by node and geometry."""
    s = trimesh.Scene()
    s.add_geometry(trimesh.creation.box(extents=(1, 1, 1)), node_name="base", geom_name="block")
    cyl = trimesh.creation.cylinder(radius=0.3, height=1.0, sections=12)
    move = trimesh.transformations.translation_matrix
    s.add_geometry(cyl, node_name="pin0", geom_name="pin", transform=move([2.0, 0.5, 0]))
    s.graph.update(frame_to="pin1", geometry="pin", matrix=move([-2.0, 0.5, 0]))
    return s


def test_trimesh_pair_and_model_draw_the_same_image(renderer):
    mesh = trimesh.creation.box(extents=(1.0, 2.0, 0.5))
    from_mesh = blueprint.draw(mesh, size=SIZE)
    from_pair = blueprint.draw((mesh.vertices, mesh.faces), size=SIZE)
    model = blueprint.Model.from_arrays(mesh.vertices, mesh.faces, part_names=["mesh"])
    expected = blueprint.render(model, size=SIZE)
    assert from_mesh.image.shape == (SIZE[1], SIZE[0], 4)
    np.testing.assert_array_equal(from_mesh.image, expected)
    np.testing.assert_array_equal(from_pair.image, expected)
    np.testing.assert_array_equal(np.asarray(from_mesh), expected)
    # a box seen from a corner: its front, and its back faces peeled behind it
    assert from_mesh.layers == 2


def test_scene_parts_are_named_and_placed(scene):
    model = blueprint.api.draw.to_model(scene)
    assert model.part_names == ("block", "pin0", "pin1")
    assert model.part_triangle_counts().tolist() == [12, 48, 48]
    # the instances moved by their node transforms, as trimesh itself concatenates them
    dumped = scene.to_geometry()
    np.testing.assert_allclose(model.bounds, dumped.bounds, atol=1e-6)
    pins = model.positions[model.faces[model.face_part == 2].ravel()]
    np.testing.assert_allclose(pins[:, 0].mean(), -2.0, atol=1e-6)


def test_a_path_draws_as_render_draws_it(renderer):
    path = examples.example_path()
    np.testing.assert_array_equal(
        blueprint.draw(path, size=SIZE, view="top").image, blueprint.render(path, size=SIZE, view="top")
    )


def test_highlight_names_a_scene_part(renderer, scene):
    plain = blueprint.draw(scene, size=SIZE, view="front")
    lit = blueprint.draw(scene, size=SIZE, view="front", highlight="pin*")
    ink = np.array(blueprint.STYLES["blueprint"].highlight[:3]) * 255
    near = np.abs(lit.image[..., :3].astype(float) - ink).max(axis=-1) < 40
    assert near.any() and not (np.abs(plain.image[..., :3].astype(float) - ink).max(axis=-1) < 40).any()
    # highlighted pixels lie only where the pins are: x beyond the block's right or left edge
    cols = np.nonzero(near.any(axis=0))[0]
    assert not ((cols > SIZE[0] * 0.42) & (cols < SIZE[0] * 0.58)).any()


def test_jupyter_shows_a_raster_drawing_as_png(renderer):
    drawing = blueprint.draw(trimesh.creation.icosphere(subdivisions=1), size=SIZE)
    bundle, _ = DisplayFormatter().format(drawing)
    assert "image/png" in bundle and "image/svg+xml" not in bundle
    decoded = np.asarray(Image.open(io.BytesIO(bundle["image/png"])).convert("RGBA"))
    np.testing.assert_array_equal(decoded, drawing.image)


def test_jupyter_shows_a_vector_drawing_as_svg(renderer, scene):
    drawing = blueprint.draw(scene, size=SIZE, view="top", vector=True)
    bundle, _ = DisplayFormatter().format(drawing)
    assert "image/svg+xml" in bundle and "image/png" not in bundle
    root = ET.fromstring(bundle["image/svg+xml"])
    assert root.tag == "{http://www.w3.org/2000/svg}svg"
    assert len(root.findall(".//{http://www.w3.org/2000/svg}path")) > 0
    assert drawing.svg() == bundle["image/svg+xml"]


def test_save_chooses_the_writer_by_suffix(renderer, scene, tmp_path):
    drawing = blueprint.draw(scene, size=SIZE, view="front")
    png = drawing.save(tmp_path / "a.png")
    np.testing.assert_array_equal(np.asarray(Image.open(png)), drawing.image)
    svg = drawing.save(tmp_path / "a.svg")
    assert svg.read_text(encoding="utf-8") == drawing.svg()
    assert drawing.save(tmp_path / "a.pdf").read_bytes()[:5] == b"%PDF-"
    doc = ezdxf.readfile(drawing.save(tmp_path / "a.dxf"))
    # one polyline per vector line, on layers named by part and occlusion level
    assert len(doc.modelspace()) == len(drawing.lines)
    assert {layer.dxf.name.rsplit("-L", 1)[0] for layer in doc.layers} >= {"block", "pin0", "pin1"}
    with pytest.raises(InputError, match=r"a\.gif"):
        drawing.save(tmp_path / "a.gif")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.dxf", "a.pdf", "a.png", "a.svg"]


def test_options_of_the_other_kind_are_refused(renderer, tmp_path):
    mesh = trimesh.creation.box()
    # shading is both kinds' now: a box from the iso view shows every one of its 12 faces
    assert len(blueprint.draw(mesh, size=SIZE, vector=True, shade="*").lines.shading) == 12
    with pytest.raises(InputError, match="scale are for vector drawings"):
        blueprint.draw(mesh, size=SIZE, view="top", scale="1:10").save(tmp_path / "x.png")
    assert not list(tmp_path.iterdir())


@pytest.mark.parametrize(
    ("obj", "message"),
    [
        (trimesh.PointCloud(np.eye(3)), "trimesh.PointCloud: a point cloud has no triangles to draw"),
        (trimesh.Scene(), "trimesh.Scene: no triangles in the scene (it holds no meshes with faces)"),
        (
            (np.array([[0, 0, 0], [1, 0, 0], [np.nan, 1, 0]]), np.array([[0, 1, 2]])),
            "(vertices, faces): 1 vertices have NaN or infinite coordinates",
        ),
        (
            trimesh.Trimesh(np.array([[0, 0, 0], [1, 0, 0], [0, np.inf, 0]]), [[0, 1, 2]], process=False),
            "trimesh.Trimesh: 1 vertices have NaN or infinite coordinates",
        ),
        ((np.zeros((3, 2)), np.array([[0, 1, 2]])), "(vertices, faces): vertices must be a (V, 3) array"),
        ((np.eye(3), np.array([[0, 1, 5]])), "(vertices, faces): faces refer to vertices that do not exist"),
        ((np.eye(3), np.array([[0.5, 1, 2]])), "(vertices, faces): faces must be a (F, 3) array of vertex"),
        ((np.zeros((3, 3)), np.array([[0, 1, 2]])), "(vertices, faces): all 1 faces are degenerate"),
        ("nowhere.stl", "nowhere.stl: "),
        (42, "int: cannot draw this object"),
    ],
)
def test_objects_that_cannot_be_drawn_raise_one_line(obj, message):
    with pytest.raises(InputError) as caught:
        blueprint.draw(obj, size=SIZE)
    text = str(caught.value)
    assert text.startswith(message)
    assert "\n" not in text


def _loaded_after(code: str) -> set[str]:
    heavy = ["scipy", "networkx", "trimesh", "moderngl", "blueprint.silhouette", "blueprint.vector", "dask"]
    probe = f"import sys\n{code}\nprint(' '.join(m for m in {heavy!r} if m in sys.modules))"
    out = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True
    )
    return set(out.stdout.split())


def test_import_blueprint_loads_nothing_heavy():
    assert _loaded_after("import blueprint; blueprint.InputError; blueprint.__all__") == set()


def test_a_binary_stl_drawing_loads_no_trimesh_scipy_or_networkx(tmp_path):
    stl = tmp_path / "part.stl"
    trimesh.creation.annulus(r_min=0.5, r_max=1.0, height=0.4, sections=24).export(stl)
    code = f"import blueprint\nblueprint.draw({str(stl)!r}, size=(64, 64)).save({str(tmp_path / 'p.png')!r})"
    assert _loaded_after(code) == {"moderngl"}
    # read without trimesh, the model is the one trimesh reads
    fast = blueprint.load_model(stl)
    loaded = trimesh.load(stl, process=False)
    np.testing.assert_array_equal(fast.positions, np.asarray(loaded.vertices, np.float32))
    np.testing.assert_array_equal(fast.faces, loaded.faces)
    assert (fast.part_names, fast.up) == (("part",), "z")
