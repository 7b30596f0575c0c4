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
from helpers import ROOT
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
    # one polyline per vector line, on layers named by part, kind and occlusion level
    assert len(doc.modelspace()) == len(drawing.lines)
    names = {layer.dxf.name.rsplit("-L", 1)[0] for layer in doc.layers}
    assert {name.rsplit("-", 1)[0] for name in names if "-" in name} >= {"block", "pin0", "pin1"}
    with pytest.raises(InputError, match=r"a\.gif"):
        drawing.save(tmp_path / "a.gif")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a.dxf", "a.pdf", "a.png", "a.svg"]


def test_options_of_the_other_kind_are_refused(renderer, tmp_path):
    mesh = trimesh.creation.box()
    # shading is both kinds' now: a box from the iso view shows every one of its 12 faces
    assert len(blueprint.draw(mesh, size=SIZE, vector=True, shade="*").lines.shading) == 12
    with pytest.raises(InputError, match="scale is for vector drawings"):
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


# what a picture's drawing does without, each a measurable part of its start (benchmarks/startup.py)
PICTURE_HEAVY = ["scipy", "networkx", "trimesh", "moderngl", "blueprint.silhouette", "blueprint.vector"]
PICTURE_HEAVY += ["dask", "PIL", "click", "blueprint.compose.glyphs", "blueprint.api.sections"]
PICTURE_HEAVY += ["blueprint.api.files", "importlib.resources", "zipfile", "difflib"]
# the other formats' readers, plan sheets, dimensions and models kept as instances
PICTURE_HEAVY += [
    f"blueprint.scene.formats.{m}" for m in ("gltf", "obj", "ply", "off", "step", "threemf", "dxml")
]
PICTURE_HEAVY += ["blueprint.scene.sheet", "blueprint.scene.dimension", "blueprint.compose.sheet"]
PICTURE_HEAVY += ["blueprint.scene.instances", "blueprint.scene.instanced_parts"]
PICTURE_HEAVY += ["blueprint.vector.drawing", "blueprint.vector.occlusion"]
# a picture looks for smooth surfaces to outline by their contour lines (``vector.contour_ink``):
# the lines' modules, not the drawings' nor the occlusion's where it finds none
CONTOUR_CHECK = {"blueprint.vector", "blueprint.silhouette"}
# what a vector drawing does without (benchmarks/vector.py, whole processes)
VECTOR_HEAVY = ["scipy", "networkx", "trimesh", "PIL", "dask", "tomllib", "blueprint.pipeline.executor"]
VECTOR_HEAVY += ["blueprint.ops", "blueprint.gpu_silhouettes", "blueprint.compose.glyphs.values"]


def _loaded_after(code: str, heavy: list[str] = PICTURE_HEAVY) -> set[str]:
    # at exit, which the command line calls itself, on a line of its own among what the code prints
    report = f"print('loaded:', *(m for m in {heavy!r} if m in sys.modules))"
    probe = f"import atexit, sys\natexit.register(lambda: {report})\n{code}"
    out = subprocess.run(
        [sys.executable, "-c", probe], capture_output=True, text=True, timeout=120, check=True
    )
    line = next(line for line in out.stdout.splitlines() if line.startswith("loaded:"))
    return set(line.split()[1:])


def test_import_blueprint_loads_nothing_heavy():
    assert _loaded_after("import blueprint; blueprint.InputError; blueprint.__all__") == set()


def test_a_binary_stl_picture_loads_only_what_it_draws_with(tmp_path):
    stl = tmp_path / "part.stl"
    trimesh.creation.annulus(r_min=0.5, r_max=1.0, height=0.4, sections=24).export(stl)
    code = f"import blueprint\nblueprint.draw({str(stl)!r}, size=(64, 64)).save({str(tmp_path / 'p.png')!r})"
    assert _loaded_after(code) == {"moderngl", *CONTOUR_CHECK}
    plain = code.replace("size=(64, 64)", "size=(64, 64), smooth_contours=False")
    assert _loaded_after(plain) == {"moderngl"}
    argv = ["render", str(stl), "-o", str(tmp_path / "c.png"), "--size", "64", "64"]
    command = f"from blueprint.cli import main\nmain({argv!r})"
    # click's option parser imports difflib itself
    assert _loaded_after(command) - {"difflib"} == {"moderngl", "click", *CONTOUR_CHECK}
    np.testing.assert_array_equal(
        np.asarray(Image.open(tmp_path / "c.png")), np.asarray(Image.open(tmp_path / "p.png"))
    )
    # read without trimesh, the triangles are the ones trimesh reads, each corner held once
    fast = blueprint.load_model(stl)
    loaded = trimesh.load(stl, process=False)
    corners = np.asarray(loaded.vertices, np.float32)[loaded.faces]
    np.testing.assert_array_equal(fast.positions[fast.faces], corners)
    assert fast.soup and len(fast.positions) == len(np.unique(corners.reshape(-1, 3), axis=0))
    assert (fast.part_names, fast.up) == (("part",), "z")


def test_a_glb_vector_drawing_loads_only_what_it_draws_with(tmp_path):
    """The glTF reader, the pipeline, glyphs and the GPU silhouette methods stay out of an SVG
    drawing's process: together well over a CPU second of its start."""
    argv = ["render", str(examples.example_path()), "-o", str(tmp_path / "g.svg"), "--size", "64", "64"]
    assert _loaded_after(f"from blueprint.cli import main\nmain({argv!r})", VECTOR_HEAVY) == set()


# -- the command line's drawing options --------------------------------------------------------------
BOX_MM = (40.0, 20.0, 10.0)


def test_dimensions_measure_the_box_in_pictures_and_vectors(renderer):
    box = trimesh.creation.box(extents=BOX_MM)
    kw = dict(size=(160, 120), view="front", ortho=True, dimensions=True)
    picture = blueprint.draw(box, **kw)
    # the front view shows width (x) and height (y): 40 and 20 model units, in mm by default
    assert [t.text for t in picture.frame.marks.texts] == ["40", "20"]
    np.testing.assert_array_equal(picture.image, blueprint.render(blueprint.api.draw.to_model(box), **kw))
    # given in cm, the same box measures ten times as many millimetres
    assert [t.text for t in blueprint.draw(box, units="cm", **kw).frame.marks.texts] == ["400", "200"]
    svg = ET.fromstring(blueprint.draw(box, vector=True, **kw).svg())
    texts = [t.text for t in svg.iter("{http://www.w3.org/2000/svg}text")]
    assert texts == ["40", "20"]


def test_a_plan_sheet_has_the_title_block_asked_for(renderer, tmp_path):
    box = trimesh.creation.box(extents=BOX_MM)
    picture = blueprint.draw(box, size=(320, 240), view="plan", title="Bracket 7", units="cm")
    texts = [t.text for t in picture.frame.marks.texts]
    assert texts[texts.index("TITLE") + 1] == "Bracket 7"
    assert texts[texts.index("UNITS") + 1] == "mm (model in cm)"
    drawing = blueprint.draw(box, size=(320, 240), view="plan", title="Bracket 7", sheet="A3", vector=True)
    root = ET.fromstring(drawing.svg())
    # an A3 sheet, landscape, in millimetres
    assert (root.get("width"), root.get("height")) == ("420mm", "297mm")
    texts = [t.text for t in root.iter("{http://www.w3.org/2000/svg}text")]
    assert texts[texts.index("TITLE") + 1] == "Bracket 7"
    # a picture drawing keeps its sheet for its vector files and refuses it for pictures
    sheet_picture = blueprint.draw(box, size=(320, 240), view="plan", sheet="A3")
    assert ET.parse(sheet_picture.save(tmp_path / "s.svg")).getroot().get("width") == "420mm"
    with pytest.raises(InputError, match=r"s\.png: sheet is for vector drawings"):
        sheet_picture.save(tmp_path / "s.png")
    assert [p.name for p in tmp_path.iterdir()] == ["s.svg"]


def test_include_and_exclude_choose_a_scenes_parts(renderer, scene):
    assert blueprint.draw(scene, size=SIZE, exclude="pin*").model.part_names == ("block",)
    assert blueprint.draw(scene, size=SIZE, include="pin1,0").model.part_names == ("block", "pin1")
    pair = (trimesh.creation.box().vertices, trimesh.creation.box().faces)
    with pytest.raises(InputError, match=r"^\(vertices, faces\): --include/--exclude leave no part"):
        blueprint.draw(pair, size=SIZE, exclude="mesh")


def test_a_section_cuts_pictures_and_vectors(renderer, scene):
    kw = dict(size=SIZE, view="front", section="z=0", section_keep="pin0")
    picture = blueprint.draw(scene, **kw)
    model = blueprint.api.draw.to_model(scene)
    np.testing.assert_array_equal(picture.image, blueprint.render(model, **kw))
    assert not np.array_equal(picture.image, blueprint.draw(scene, size=SIZE, view="front").image)
    groups = ET.fromstring(blueprint.draw(scene, vector=True, **kw).svg()).iter(
        "{http://www.w3.org/2000/svg}g"
    )
    assert "section" in {g.get("id") for g in groups}


@pytest.mark.parametrize(
    ("flags", "options"),
    [
        (["--title", "T"], dict(title="T")),
        (["--dimensions"], dict(dimensions=True)),
        (
            ["--units", "furlong", "--dimensions", "--ortho"],
            dict(units="furlong", dimensions=True, ortho=True),
        ),
        (["--section", "q=1"], dict(section="q=1")),
        (["--include", "nosuch"], dict(include="nosuch")),
        (["--view", "bogus"], dict(view="bogus")),
        (["--supersample", "9"], dict(supersample=9)),
        (["--view", "plan", "--glyphs", "MARKS"], dict(view="plan", glyphs="MARKS")),
        (["--sheet", "A3"], dict(sheet="A3", vector=True)),
        (["--sheet", "A9", "--view", "plan"], dict(sheet="A9", view="plan", vector=True)),
    ],
)
def test_bad_options_raise_the_command_lines_line(renderer, tmp_path, capsys, flags, options):
    from blueprint import cli

    marks = str(ROOT / "examples" / "marks.toml")
    path = str(examples.example_path())
    flags = [marks if f == "MARKS" else f for f in flags]
    options = {k: marks if v == "MARKS" else v for k, v in options.items()}
    output = tmp_path / ("out.svg" if options.get("vector") else "out.png")
    with pytest.raises(SystemExit) as exited:
        cli.main(["render", path, "-o", str(output), "--size", "64", "64", *flags])
    assert exited.value.code == 2
    printed = capsys.readouterr().err.strip().splitlines()[-1]
    with pytest.raises(InputError) as caught:
        blueprint.draw(path, size=(64, 64), **options)
    assert printed == f"blueprint: error: {caught.value}"
    assert not list(tmp_path.iterdir())
