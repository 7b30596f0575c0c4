"""Length units: the unit a file states (glTF and STEP: metres; 3MF: its model's ``unit``) is the
model's, and dimensions, drawings to scale and title blocks measure it in that; ``--units``
overrides it; formats without one are assumed millimetres, with a warning; a unit blueprint
does not know is refused in one line. The models are written here: a 3MF, a glTF and a GLB by
hand, and a STEP file's text that OpenCASCADE meshes."""

from __future__ import annotations

import base64
import itertools
import json
import logging
import struct
import xml.etree.ElementTree as ET
import zipfile

import numpy as np
import pytest
import trimesh
from helpers import no_output, one_error, run_cli

import blueprint
from blueprint.api.files import render_vector_file
from blueprint.errors import InputError
from blueprint.scene.camera import fit_camera
from blueprint.scene.formats import FORMATS
from blueprint.scene.loader import model_from_object
from blueprint.scene.units import UNITS_MM, drawing_unit, named_unit

SVG = "{http://www.w3.org/2000/svg}"
CORNERS = np.array(list(itertools.product((0, 1), repeat=3)), np.float64)
# the box's 12 triangles over CORNERS, facing out
TRIANGLES = np.array(
    [[0, 2, 6], [0, 6, 4], [1, 5, 7], [1, 7, 3], [0, 4, 5], [0, 5, 1]]
    + [[2, 3, 7], [2, 7, 6], [0, 1, 3], [0, 3, 2], [4, 6, 7], [4, 7, 5]]
)


def write_3mf(path, size, unit: str | None):
    """A 3MF file of one box from the origin to ``size`` whose model states ``unit`` (none
    where None: millimetres by the specification)."""
    vertices = "".join(f'<vertex x="{x:g}" y="{y:g}" z="{z:g}"/>' for x, y, z in CORNERS * size)
    triangles = "".join(f'<triangle v1="{a}" v2="{b}" v3="{c}"/>' for a, b, c in TRIANGLES)
    stated = f' unit="{unit}"' if unit is not None else ""
    model = (
        f'<?xml version="1.0" encoding="UTF-8"?>\n<model{stated} xml:lang="en-US" '
        'xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02"><resources>'
        f'<object id="1" type="model"><mesh><vertices>{vertices}</vertices>'
        f"<triangles>{triangles}</triangles></mesh></object></resources>"
        '<build><item objectid="1"/></build></model>'
    )
    package = "http://schemas.openxmlformats.org/package/2006"
    with zipfile.ZipFile(path, "w") as archive:
        archive.writestr(
            "[Content_Types].xml",
            f'<?xml version="1.0" encoding="UTF-8"?><Types xmlns="{package}/content-types">'
            '<Default Extension="rels" '
            'ContentType="application/vnd.openxmlformats-package.relationships+xml"/>'
            '<Default Extension="model" '
            'ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>'
            "</Types>",
        )
        archive.writestr(
            "_rels/.rels",
            f'<?xml version="1.0" encoding="UTF-8"?><Relationships xmlns="{package}/relationships">'
            '<Relationship Target="/3D/3dmodel.model" Id="rel0" '
            'Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/></Relationships>',
        )
        archive.writestr("3D/3dmodel.model", model)
    return path


def write_gltf(path, size):
    """A glTF (.gltf, its buffer inline) or GLB file of one box from the origin to ``size``."""
    positions = (CORNERS * size).astype("<f4").tobytes()
    indices = TRIANGLES.astype("<u4").tobytes()
    binary = positions + indices
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "name": "box"}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {
                "bufferView": 0,
                "componentType": 5126,
                "count": 8,
                "type": "VEC3",
                "min": [0.0, 0.0, 0.0],
                "max": [float(v) for v in size],
            },
            {"bufferView": 1, "componentType": 5125, "count": TRIANGLES.size, "type": "SCALAR"},
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": len(positions)},
            {"buffer": 0, "byteOffset": len(positions), "byteLength": len(indices)},
        ],
        "buffers": [{"byteLength": len(binary)}],
    }
    if path.suffix == ".gltf":
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(binary).decode()
        path.write_text(json.dumps(doc))
        return path
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    chunks = struct.pack("<II", len(text), 0x4E4F534A) + text + struct.pack("<II", len(binary), 0x004E4942)
    chunks += binary
    path.write_bytes(struct.pack("<III", 0x46546C67, 2, 12 + len(chunks)) + chunks)
    return path


# a STEP file's length unit, as its representation context assigns it
STEP_UNITS = {
    "mm": "( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT(.MILLI.,.METRE.) )",
    "m": "( LENGTH_UNIT() NAMED_UNIT(*) SI_UNIT($,.METRE.) )",
}


def step_text(size, unit: str) -> str:
    """A STEP AP214 file of one box (a B-rep of six planar faces) from the origin to ``size``,
    its lengths in ``unit`` (a key of ``STEP_UNITS``)."""
    lines: list[str] = []

    def add(text: str) -> str:
        lines.append(text)
        return f"#{len(lines)}"

    def point(p) -> str:
        x, y, z = (float(v) for v in p)
        return add(f"CARTESIAN_POINT('',({x!r},{y!r},{z!r}))")

    def direction(d) -> str:
        x, y, z = (float(v) for v in d)
        return add(f"DIRECTION('',({x!r},{y!r},{z!r}))")

    corners = {tuple(c): c * size for c in CORNERS.astype(int)}
    vertex = {c: add(f"VERTEX_POINT('',{point(p)})") for c, p in corners.items()}
    edges: dict = {}

    def edge(a, b) -> str:
        key = (min(a, b), max(a, b))
        if key not in edges:
            along = direction(np.subtract(key[1], key[0]))
            vector = add(f"VECTOR('',{along},1.)")
            line = add(f"LINE('',{point(corners[key[0]])},{vector})")
            edges[key] = add(f"EDGE_CURVE('',{vertex[key[0]]},{vertex[key[1]]},{line},.T.)")
        return add(f"ORIENTED_EDGE('',*,*,{edges[key]},{'.T.' if (a, b) == key else '.F.'})")

    faces = []
    for axis, side in itertools.product(range(3), (0, 1)):
        u, v = (k for k in range(3) if k != axis)

        def corner(i, j, axis=axis, side=side, u=u, v=v):
            c = [0, 0, 0]
            c[axis], c[u], c[v] = side, i, j
            return tuple(c)

        ring = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)]
        ring = ring if side else ring[::-1]
        loop = add(f"EDGE_LOOP('',({','.join(edge(ring[k], ring[(k + 1) % 4]) for k in range(4))}))")
        normal, across = np.zeros(3), np.zeros(3)
        normal[axis], across[u] = (1 if side else -1), 1
        place = add(
            f"AXIS2_PLACEMENT_3D('',{point(corners[corner(0, 0)])},{direction(normal)},{direction(across)})"
        )
        bound = add(f"FACE_OUTER_BOUND('',{loop},.T.)")
        plane = add(f"PLANE('',{place})")
        faces.append(add(f"ADVANCED_FACE('',({bound}),{plane},.T.)"))
    shell = add(f"CLOSED_SHELL('',({','.join(faces)}))")
    solid = add(f"MANIFOLD_SOLID_BREP('box',{shell})")
    length = add(STEP_UNITS[unit])
    angle = add("( NAMED_UNIT(*) PLANE_ANGLE_UNIT() SI_UNIT($,.RADIAN.) )")
    solid_angle = add("( NAMED_UNIT(*) SI_UNIT($,.STERADIAN.) SOLID_ANGLE_UNIT() )")
    accuracy = add(
        f"UNCERTAINTY_MEASURE_WITH_UNIT(LENGTH_MEASURE(1.E-07),{length},'distance_accuracy_value','')"
    )
    context = add(
        f"( GEOMETRIC_REPRESENTATION_CONTEXT(3) GLOBAL_UNCERTAINTY_ASSIGNED_CONTEXT(({accuracy})) "
        f"GLOBAL_UNIT_ASSIGNED_CONTEXT(({length},{angle},{solid_angle})) REPRESENTATION_CONTEXT('','') )"
    )
    world = add(f"AXIS2_PLACEMENT_3D('',{point((0, 0, 0))},{direction((0, 0, 1))},{direction((1, 0, 0))})")
    shape = add(f"ADVANCED_BREP_SHAPE_REPRESENTATION('',({solid},{world}),{context})")
    application = add("APPLICATION_CONTEXT('automotive design')")
    mechanical = add(f"MECHANICAL_CONTEXT('',{application},'mechanical')")
    product = add(f"PRODUCT('box','box','',({mechanical}))")
    formation = add(f"PRODUCT_DEFINITION_FORMATION('','',{product})")
    design = add(f"PRODUCT_DEFINITION_CONTEXT('part definition',{application},'design')")
    definition = add(f"PRODUCT_DEFINITION('design','',{formation},{design})")
    definition_shape = add(f"PRODUCT_DEFINITION_SHAPE('','',{definition})")
    add(f"SHAPE_DEFINITION_REPRESENTATION({definition_shape},{shape})")
    data = "\n".join(f"#{i}={text};" for i, text in enumerate(lines, 1))
    return (
        "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('box','',(''),(''),'','','');\n"
        "FILE_SCHEMA(('AUTOMOTIVE_DESIGN { 1 0 10303 214 1 1 1 1 }'));\nENDSEC;\nDATA;\n"
        f"{data}\nENDSEC;\nEND-ISO-10303-21;\n"
    )


def svg_texts(path) -> list[str]:
    return [t.text for t in ET.parse(path).getroot().iter(f"{SVG}text")]


def top_dimensions(model, renderer, tmp_path, **options) -> tuple[list[str], list[str]]:
    """The texts of the top view's dimensions, of the picture and of the SVG drawing."""
    frame = blueprint.render_frame(
        model, size=(400, 300), view="top", ortho=True, dimensions=True, renderer=renderer, **options
    )
    path = tmp_path / "top.svg"
    render_vector_file(
        model, path, size=(400, 300), view="top", ortho=True, dimensions=True, renderer=renderer, **options
    )
    return [t.text for t in frame.marks.texts], svg_texts(path)


# -- what files state --------------------------------------------------------------------------


def test_names_of_units():
    names = ("micron", "millimeter", "centimeter", "inch", "foot", "meter")
    assert [named_unit(n) for n in names] == ["um", "mm", "cm", "in", "ft", "m"]
    # trimesh's names (its 3MF default, its glTF unit) and the file's case do not matter
    assert [named_unit(n) for n in ("millimeters", "meters", "inches", "Inch", " feet ")] == [
        "mm",
        "m",
        "in",
        "in",
        "ft",
    ]
    assert named_unit("furlong") is None
    with pytest.raises(InputError, match=r"^x\.3mf: unknown length unit 'furlong' \(3MF's units: micron, "):
        FORMATS.unit("x.3mf", "3mf", "furlong")


def test_formats_that_state_a_unit():
    assert FORMATS.unit("a.glb", "glb") == ("m", "glTF is in metres by its specification")
    assert FORMATS.unit("a.gltf", "gltf")[0] == "m"
    assert FORMATS.unit("a.STEP", "step") == ("m", "OpenCASCADE meshes STEP in metres")
    assert FORMATS.unit("a.3mf", "3mf", "inch")[0] == "in"
    for ext in ("stl", "obj", "ply", "off", "3dxml"):
        assert FORMATS.unit(f"a.{ext}", ext) == (None, f"{ext.upper()} files carry no unit")


@pytest.mark.parametrize(
    "unit, expected",
    [("inch", "in"), ("millimeter", "mm"), (None, "mm"), ("centimeter", "cm"), ("meter", "m")],
)
def test_3mf_unit_is_the_models(tmp_path, unit, expected):
    model = blueprint.load_model(write_3mf(tmp_path / "box.3mf", (2.0, 1.0, 0.5), unit))
    assert model.unit == expected and model.unit_reason.startswith("the 3MF model's unit")
    np.testing.assert_allclose(model.bounds, [[0, 0, 0], [2, 1, 0.5]])  # the file's numbers, unscaled


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_gltf_is_in_metres(tmp_path, suffix):
    model = blueprint.load_model(write_gltf(tmp_path / f"box{suffix}", (0.02, 0.005, 0.01)))
    assert (model.unit, model.up) == ("m", "y")


def test_formats_without_a_unit_have_none(tmp_path):
    path = tmp_path / "box.stl"
    trimesh.Trimesh(CORNERS * 2.0, TRIANGLES).export(path)
    model = blueprint.load_model(path)
    assert (model.unit, model.unit_reason) == (None, "STL files carry no unit")
    assert drawing_unit(model) == "mm" and drawing_unit(model, "in") == "in"
    obj = tmp_path / "box.obj"
    obj.write_text(
        "".join(f"v {x} {y} {z}\n" for x, y, z in CORNERS)
        + "".join(f"f {a + 1} {b + 1} {c + 1}\n" for a, b, c in TRIANGLES)
    )
    assert blueprint.load_model(obj).unit is None


def test_objects_keep_their_units():
    mesh = trimesh.Trimesh(CORNERS, TRIANGLES)
    assert model_from_object(mesh).unit is None
    mesh.units = "inches"
    assert model_from_object(mesh).unit == "in"
    assert model_from_object(trimesh.Scene(mesh)).unit_reason == "its units, inches"
    # an object's unknown unit is assumed, as a file without one is
    mesh.units = "furlongs"
    assert (model_from_object(mesh).unit, drawing_unit(model_from_object(mesh))) == (None, "mm")
    assert blueprint.Model.from_arrays(CORNERS, TRIANGLES, unit="cm").unit == "cm"
    with pytest.raises(ValueError, match="unit must be one of"):
        blueprint.Model.from_arrays(CORNERS, TRIANGLES, unit="furlong")


def test_parts_and_sections_keep_the_unit():
    from blueprint.scene.environment import choose_parts
    from blueprint.scene.section import SectionPlane, cut_model

    two = blueprint.Model.from_arrays(
        np.r_[CORNERS, CORNERS + 2], np.r_[TRIANGLES, TRIANGLES + 8], np.repeat([0, 1], 12), unit="in"
    )
    one = choose_parts(two, [1])
    assert (one.part_names, one.unit, one.unit_reason) == (("part1",), "in", "given")
    plane = SectionPlane(np.array([0.5, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), None, "x=0.5")
    assert cut_model(two, plane).model.unit == "in"


# -- drawings measure in the file's unit ---------------------------------------------------------


def test_3mf_in_inches_is_dimensioned_in_mm(renderer, tmp_path):
    model = write_3mf(tmp_path / "box.3mf", (2.0, 1.0, 0.5), "inch")
    assert top_dimensions(model, renderer, tmp_path) == (["50.8", "25.4"], ["50.8", "25.4"])
    # --units states the model's unit, over the file's
    assert top_dimensions(model, renderer, tmp_path, units="mm") == (["2", "1"], ["2", "1"])


def test_3mf_in_millimetres(renderer, tmp_path):
    model = write_3mf(tmp_path / "box.3mf", (20.0, 10.0, 5.0), "millimeter")
    assert top_dimensions(model, renderer, tmp_path) == (["20", "10"], ["20", "10"])


@pytest.mark.parametrize("suffix", [".glb", ".gltf"])
def test_gltf_is_dimensioned_from_metres(renderer, tmp_path, suffix):
    model = write_gltf(tmp_path / f"box{suffix}", (0.02, 0.005, 0.01))
    # Y up: the top view sees x and z
    assert top_dimensions(model, renderer, tmp_path) == (["20", "10"], ["20", "10"])


@pytest.mark.parametrize("unit, size", [("mm", (20.0, 10.0, 5.0)), ("m", (0.02, 0.01, 0.005))])
def test_step_in_any_unit_arrives_in_metres(renderer, tmp_path, unit, size):
    pytest.importorskip("cascadio")
    path = tmp_path / "box.step"
    path.write_text(step_text(size, unit))
    model = blueprint.load_model(path)
    assert model.unit == "m"
    np.testing.assert_allclose(model.bounds, [[0, 0, 0], [0.02, 0.01, 0.005]], atol=1e-9)
    assert top_dimensions(model, renderer, tmp_path) == (["20", "10"], ["20", "10"])


def test_scale_and_title_block_take_the_files_unit(renderer, tmp_path):
    model = blueprint.load_model(write_3mf(tmp_path / "box.3mf", (2.0, 1.0, 0.5), "inch"))
    path = tmp_path / "plan.svg"
    render_vector_file(model, path, view="plan", sheet="A4", renderer=renderer)
    assert "mm (model in in)" in svg_texts(path)
    frame = blueprint.render_frame(model, size=(400, 300), view="plan", renderer=renderer)
    texts = [t.text for t in frame.marks.texts]
    assert texts[texts.index("UNITS") + 1] == "mm (model in in)"
    # 1:1, the page is the view's model height in mm: the camera's height in inches, 25.4 mm each
    camera = fit_camera(model, (300, 300), "top", ortho=True)
    drawing = blueprint.draw(model, vector=True, size=(300, 300), view="top", scale="1:1").lines
    assert drawing.page.model_unit == "in"
    assert drawing.page.height == pytest.approx(camera.height * 25.4, rel=1e-6)


# -- no unit in the file: millimetres, said ------------------------------------------------------


@pytest.fixture
def stl(tmp_path):
    path = tmp_path / "box.stl"
    trimesh.Trimesh(CORNERS * (2.0, 1.0, 0.5), TRIANGLES).export(path)
    return path


def test_assumed_unit_is_a_warning_in_python(renderer, stl, tmp_path, caplog):
    expected = f"{stl}: STL files carry no unit; assumed mm (set --units)"
    with caplog.at_level(logging.WARNING, logger="blueprint"):
        assert top_dimensions(stl, renderer, tmp_path) == (["2", "1"], ["2", "1"])
    assert [r.getMessage() for r in caplog.records] == [expected, expected]  # picture, drawing
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="blueprint"):
        sheet = blueprint.draw(stl, vector=True, size=(200, 200), view="plan", sheet="A4", dimensions=True)
        assert sheet.lines.page.scale is not None
    assert [r.getMessage() for r in caplog.records] == [expected]  # once a drawing
    caplog.clear()
    with caplog.at_level(logging.WARNING, logger="blueprint"):
        top_dimensions(stl, renderer, tmp_path, units="in")  # stated
        blueprint.render_frame(stl, size=(200, 200), view="top", renderer=renderer)  # not measured
        render_vector_file(stl, tmp_path / "a.svg", size=(200, 200), view="plan", renderer=renderer)
    assert caplog.records == []


@pytest.mark.parametrize(
    "args",
    [["-o", "x.svg", "--dimensions"], ["-o", "x.png", "--dimensions"], ["-o", "x.svg", "--scale", "10:1"]],
)
def test_assumed_unit_is_a_warning_line(stl, tmp_path, args):
    args = [tmp_path / a if a.startswith("x.") else a for a in args]
    proc = run_cli("render", stl, "--size", 64, 48, "--view", "top", "--ortho", *args)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr == f"blueprint: warning: {stl}: STL files carry no unit; assumed mm (set --units)\n"
    stated = run_cli("render", stl, "--size", 64, 48, "--view", "top", "--ortho", "--units", "mm", *args)
    assert stated.returncode == 0 and stated.stderr == ""


def test_refused_drawing_says_only_why(stl, tmp_path):
    # dimensions of a perspective view: the error, no warning about the unit before it
    proc = run_cli("render", stl, "-o", tmp_path / "x.svg", "--size", 64, 48, "--dimensions")
    one_error(proc, "dimensions need an orthographic view")


# -- bad units -----------------------------------------------------------------------------------


@pytest.mark.parametrize("command", [["render", "-o", "x.png", "--size", "32", "32"], ["info"]])
def test_unknown_unit_in_a_file_is_one_line(tmp_path, command):
    model = write_3mf(tmp_path / "box.3mf", (2.0, 1.0, 0.5), "furlong")
    folder = tmp_path / "out"
    folder.mkdir()
    args = [folder / a if a.startswith("x.") else a for a in command[1:]]
    one_error(run_cli(command[0], model, *args), str(model), "unknown length unit 'furlong'", "inch")
    no_output(folder)


def test_unknown_units_option_is_one_line(stl, tmp_path):
    for output in ("x.png", "x.svg"):
        proc = run_cli("render", stl, "-o", tmp_path / output, "--units", "furlong")
        one_error(proc, "unknown units 'furlong'", ", ".join(UNITS_MM))
    with pytest.raises(InputError, match="unknown units 'parsec'"):
        drawing_unit(blueprint.load_model(stl), "parsec")


# -- blueprint info ------------------------------------------------------------------------------


def test_info_prints_the_unit_and_size(tmp_path, stl):
    model = write_3mf(tmp_path / "box.3mf", (2.0, 1.0, 0.5), "inch")
    lines = run_cli("info", model).stdout.splitlines()
    assert lines[2] == "unit: in, from the file (the 3MF model's unit, millimetres where it states none)"
    assert lines[3] == "size: 2 x 1 x 0.5 in = 50.8 x 25.4 x 12.7 mm"
    lines = run_cli("info", stl).stdout.splitlines()
    assert lines[2] == "unit: mm, assumed (STL files carry no unit; render --units sets it)"
    assert lines[3] == "size: 2 x 1 x 0.5 mm"
    data = json.loads(run_cli("info", model, "--json").stdout)
    assert (data["unit"], data["unit_assumed"], data["size"]) == ("in", False, [2.0, 1.0, 0.5])
    np.testing.assert_allclose(data["size_mm"], [50.8, 25.4, 12.7])
    assert json.loads(run_cli("info", stl, "--json").stdout)["unit_assumed"] is True


# -- the models of the report: featuretype in STEP (metres) and STL (inches) ---------------------


@pytest.fixture(scope="module")
def featuretype(shared_models):
    pytest.importorskip("cascadio")
    folder = shared_models / "trimesh"
    return blueprint.load_model(folder / "featuretype.STEP"), folder / "featuretype.STL"


@pytest.mark.parametrize(
    "view, expected", [("top", ["127", "63.5", "8× Ø 11.1", "8× Ø 6.8"]), ("front", ["127", "34.9", "Ø 9.9"])]
)
def test_featuretype_step_is_dimensioned_as_its_stl_in_inches(
    renderer, featuretype, tmp_path, view, expected
):
    step, stl = featuretype
    for model, units in ((step, None), (stl, "in")):
        frame = blueprint.render_frame(
            model, size=(512, 384), view=view, ortho=True, dimensions=True, units=units, renderer=renderer
        )
        assert [t.text for t in frame.marks.texts] == expected
        path = tmp_path / f"{view}.svg"
        render_vector_file(
            model,
            path,
            size=(512, 384),
            view=view,
            ortho=True,
            dimensions=True,
            units=units,
            renderer=renderer,
        )
        assert svg_texts(path) == expected


def test_featuretype_step_from_the_command_line(featuretype, tmp_path, shared_models):
    path = tmp_path / "f.svg"
    step = shared_models / "trimesh" / "featuretype.STEP"
    proc = run_cli("render", step, "-o", path, "--view", "top", "--ortho", "--dimensions")
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    assert svg_texts(path) == ["127", "63.5", "8× Ø 11.1", "8× Ø 6.8"]
    # 1:1 lays the page out as large as the part: as the STL in inches does
    pages = []
    for model, units in ((step, []), (featuretype[1], ["--units", "in"])):
        scaled = tmp_path / "scaled.svg"
        proc = run_cli("render", model, "-o", scaled, "--view", "top", "--scale", "1:1", *units)
        assert proc.returncode == 0, proc.stderr
        root = ET.parse(scaled).getroot()
        pages.append([float(root.get(k).removesuffix("mm")) for k in ("width", "height")])
    assert pages[0] == pytest.approx(pages[1], rel=1e-5)
    assert pages[0][0] > 127.0  # the part and the fit's margin
    lines = run_cli("info", step).stdout.splitlines()
    assert lines[2] == "unit: m, from the file (OpenCASCADE meshes STEP in metres)"
    assert lines[3] == "size: 0.127 x 0.0635 x 0.034925 m = 127 x 63.5 x 34.925 mm"
