"""Validation of pipeline files, all before any GPU work: every kind of mistake gives one
InputError of one line that names the file, the key and the allowed values."""

from __future__ import annotations

import textwrap

import pytest

from blueprint.errors import InputError
from blueprint.pipeline import load_pipeline, plan, preset_names

BASE = """
[pipeline]
output = "e"
[attributes]
normal = {}
[passes.e]
op = "roberts"
inputs = { source = "normal" }
"""

SHADER = """
uniform sampler2D u_src;
uniform float u_gain;
out vec4 o_value;
void main() { o_value = texelFetch(u_src, ivec2(gl_FragCoord.xy), 0) * u_gain; }
"""

USER = """
[pipeline]
output = "t"
[images.photo]
[passes.t]
shader = "tint.frag"
inputs = { src = "photo" }
[passes.t.uniforms]
gain = { type = "float", default = 1.0, min = 0.0, max = 2.0 }
"""

# (name, toml, fragments the one-line message must contain)
CASES = [
    ("toml", "[pipeline\n", ["not valid TOML"]),
    (
        "section",
        BASE + "[extra]\n",
        ["extra: unknown key", "choose pipeline, variables, attributes, images, passes"],
    ),
    (
        "pipeline key",
        BASE.replace("[pipeline]", "[pipeline]\nlayer = 2"),
        ["pipeline.layer: unknown key", "layers"],
    ),
    ("no output", "[pipeline]\nname = 'x'\n", ["pipeline.output: missing"]),
    (
        "output name",
        BASE.replace('output = "e"', 'output = "f"'),
        ["pipeline.output: unknown name 'f'", "choose normal, e"],
    ),
    (
        "attribute",
        BASE.replace("normal = {}", "normal = {}\ncolour = {}"),
        ["attributes.colour: unknown attribute", "base_color", "linear_depth"],
    ),
    (
        "attribute format",
        BASE.replace("normal = {}", 'normal = { format = "rgba8" }'),
        ["attributes.normal.format", "'rgba8' is not allowed", "choose rgba16f"],
    ),
    ("scale", BASE.replace("normal = {}", "normal = { scale = 0 }"), ["attributes.normal.scale", "(0, 8]"]),
    (
        "op",
        BASE.replace('"roberts"', '"robert"'),
        ["passes.e.op: unknown operation 'robert'", "roberts", "sobel"],
    ),
    ("op and shader", BASE + 'shader = "x.frag"\n', ["passes.e: give either op", "or shader"]),
    (
        "input key",
        BASE.replace("{ source =", "{ src ="),
        ["passes.e.inputs.src: roberts has no input 'src'", "choose source"],
    ),
    (
        "missing input",
        BASE.replace('inputs = { source = "normal" }', ""),
        ["passes.e.inputs: missing input 'source'"],
    ),
    (
        "unknown source",
        BASE.replace('source = "normal"', 'source = "normals"'),
        ["passes.e.inputs.source: unknown name 'normals'", "choose normal"],
    ),
    (
        "cycle",
        BASE.replace('source = "normal"', 'source = "f"')
        + '[passes.f]\nop = "invert"\ninputs = { source = "e" }\n',
        ["cycle e -> f -> e"],
    ),
    (
        "int into float",
        BASE.replace("normal = {}", "ids = {}").replace('source = "normal"', 'source = "ids"'),
        ["passes.e.inputs.source: 'ids' is rg32i", "needs a non-integer format", "rgba16f"],
    ),
    (
        "float into int",
        BASE.replace('op = "roberts"', 'op = "id_edges"').replace("{ source =", "{ ids ="),
        ["passes.e.inputs.ids: 'normal' is rgba16f", "needs an integer format (r32i, rg32i)"],
    ),
    (
        "depth only",
        BASE.replace("normal = {}", "normal = {}\nlinear_depth = {}\nbase_color = {}")
        + '[passes.s]\nop = "lambert"\n'
        + 'inputs = { normal = "normal", depth = "linear_depth", color = "base_color" }\n',
        ["passes.s.inputs.depth: 'linear_depth' is r32f", "needs the depth attribute"],
    ),
    (
        "output format",
        BASE.replace('inputs = { source = "normal" }', 'inputs = { source = "normal" }\nformat = "r32i"'),
        ["passes.e.format", "'r32i' is not allowed", "choose r8, rgba8"],
    ),
    (
        "param range",
        BASE + "params = { threshold = 200 }\n",
        ["passes.e.params.threshold", "must be in [0, 100], got 200"],
    ),
    (
        "param name",
        BASE + "params = { treshold = 0.1 }\n",
        ["passes.e.params.treshold: unknown parameter of roberts", "choose threshold, channels, invert"],
    ),
    ("param type", BASE + "params = { invert = 1 }\n", ["passes.e.params.invert", "must be true or false"]),
    ("param int", BASE + "params = { channels = 2.5 }\n", ["passes.e.params.channels", "whole number"]),
    (
        "param choice",
        BASE.replace('op = "roberts"', 'op = "downsample"') + 'params = { filter = "tent" }\n',
        ["passes.e.params.filter", "one of box, gaussian", "'tent'"],
    ),
    (
        "scale mismatch",
        BASE.replace("normal = {}", "normal = { scale = 2 }") + "scale = 1\n",
        ["passes.e.inputs.source: 'normal' is at scale 2", "needs equal scales", "downsample"],
    ),
    (
        "resample ratio",
        BASE.replace("normal = {}", "normal = { scale = 1.5 }").replace('"roberts"', '"downsample"'),
        ["passes.e.inputs.source", "scale 1.5", "whole ratio from 1 to 8"],
    ),
    (
        "stack of a once-pass",
        BASE.replace('output = "e"', 'output = "c"')
        + '[passes.c]\nop = "composite"\ninputs = { layers = "e" }\n',
        ["passes.c.inputs.layers", "every depth layer of a per-layer pass", "per_layer = true"],
    ),
    (
        "per-layer reads all layers",
        BASE.replace('output = "e"', 'output = "x"')
        + "per_layer = true\n"
        + '[passes.c]\nop = "composite"\ninputs = { layers = "e" }\nformat = "rgba8"\n'
        + '[passes.x]\nop = "invert"\ninputs = { source = "c" }\nper_layer = true\n',
        ["passes.x.inputs", "'c' needs every depth layer", "a per-layer pass cannot read it"],
    ),
    (
        "attribute after the peel",
        BASE.replace('output = "e"', 'output = "m"')
        + "per_layer = true\n"
        + '[passes.c]\nop = "composite"\ninputs = { layers = "e" }\n'
        + '[passes.m]\nop = "mix"\ninputs = { a = "c", b = "normal" }\n',
        ["passes.m.inputs.b: attribute 'normal' is gone once every layer is peeled"],
    ),
    ("layers", BASE.replace("[pipeline]", "[pipeline]\nlayers = 300"), ["pipeline.layers", "[0, 256]"]),
    (
        "expression variable",
        BASE + 'params = { threshold = "= tresh * 2" }\n[variables]\nthresh = 0.1\n',
        ["passes.e.params.threshold: unknown variable 'tresh'", "choose thresh"],
    ),
    (
        "expression syntax",
        BASE + 'params = { threshold = "= 1 +" }\n',
        ["passes.e.params.threshold", "cannot read"],
    ),
    (
        "names",
        BASE + '[passes.normal]\nop = "invert"\ninputs = { source = "e" }\n',
        ["passes.normal: name 'normal' is already used by attributes.normal"],
    ),
    (
        "bad name",
        BASE + '[passes."a b"]\nop = "invert"\ninputs = { source = "e" }\n',
        ["letters, digits and _"],
    ),
    (
        "part attribute without parts",
        BASE + '[attributes.mine]\nof = "depth"\n',
        ["attributes.mine", "gives both of (what) and parts (which)"],
    ),
    (
        "part attribute of what",
        BASE + '[attributes.mine]\nof = "uv"\nparts = "p"\n',
        ["attributes.mine.of", "one of depth, normal, ids"],
    ),
    ("when type", BASE + 'when = "on"\n', ["passes.e.when", "true, false or a number, got 'on'"]),
    (
        "input is off",
        BASE.replace('output = "e"', 'output = "f"')
        + "when = false\n"
        + '[passes.f]\nop = "invert"\ninputs = { source = "e" }\n',
        ["passes.f.inputs.source: 'e' is off here"],
    ),
    ("output is off", BASE + "when = 0\n", ["pipeline.output: 'e' is off here"]),
    (
        "accumulate once",
        BASE + "accumulate = true\n",
        ["passes.e.accumulate", "only a per-layer pass accumulates"],
    ),
    (
        "stop rule name",
        BASE + '[stop.halfway]\ndepth = "normal"\nfraction = 0.5\n',
        ["stop.halfway: unknown stop rule", "choose reveal"],
    ),
    (
        "reveal of a plain attribute",
        BASE.replace("normal = {}", "normal = {}\ndepth = {}")
        + '[stop.reveal]\ndepth = "depth"\nfraction = 0.5\n',
        ["stop.reveal.depth: 'depth' is not a depth attribute of chosen parts"],
    ),
    (
        "reveal fraction",
        BASE
        + '[attributes.mine]\nof = "depth"\nparts = "p"\n'
        + '[stop.reveal]\ndepth = "mine"\nfraction = 0\n',
        ["stop.reveal.fraction: must be above 0"],
    ),
    (
        "reveal without the layers' depth",
        BASE
        + '[attributes.mine]\nof = "depth"\nparts = "p"\n'
        + '[stop.reveal]\ndepth = "mine"\nfraction = 0.5\n',
        ["stop.reveal.depth: 'mine' is compared with every layer's depth", "declare the depth attribute"],
    ),
    (
        "image file kind",
        BASE + '[images.photo]\nfile = "photo.txt"\n',
        ["images.photo.file: unknown kind of file", ".png", ".mp4"],
    ),
]


def write(tmp_path, text: str, name: str = "p.toml"):
    path = tmp_path / name
    path.write_text(textwrap.dedent(text), encoding="utf-8")
    return path


def assert_one_error(path, fragments, **bind):
    with pytest.raises(InputError) as info:
        spec = load_pipeline(str(path))
        spec.bind(bind or None)
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith(f"{path}: "), message
    for fragment in fragments:
        assert fragment in message, message
    return message


@pytest.mark.parametrize("case", CASES, ids=[c[0] for c in CASES])
def test_validation_error(tmp_path, case):
    _, text, fragments = case
    assert_one_error(write(tmp_path, text), fragments)


def test_base_is_valid(tmp_path):
    spec = load_pipeline(str(write(tmp_path, BASE)))
    assert spec.bind().passes["e"].format == "r8"


def test_unknown_variable_override(tmp_path):
    path = write(tmp_path, BASE + "[variables]\nthresh = 0.1\n")
    assert_one_error(path, ["variables.thres: unknown variable", "choose thresh"], thres=1)


def test_variable_override_is_checked(tmp_path):
    path = write(tmp_path, BASE + 'params = { threshold = "= thresh" }\n[variables]\nthresh = 0.1\n')
    spec = load_pipeline(str(path))
    assert spec.bind({"thresh": 0.5}).passes["e"].uniforms["u_threshold"] == 0.5
    with pytest.raises(InputError, match=r"passes\.e\.params\.threshold.*must be in \[0, 100\], got -1"):
        spec.bind({"thresh": -1})


def test_dump_names_are_checked(tmp_path):
    bound = load_pipeline(str(write(tmp_path, BASE))).bind()
    with pytest.raises(InputError, match=r"--dump: unknown name 'nope' \(choose normal, e\)"):
        plan(bound, ("nope",))


def test_missing_file_and_suffix(tmp_path):
    with pytest.raises(InputError, match="no such pipeline file"):
        load_pipeline(str(tmp_path / "none.toml"))
    with pytest.raises(InputError, match="must end in .toml"):
        load_pipeline(str(tmp_path / "none.txt"))
    with pytest.raises(InputError, match="unknown pipeline preset 'bluprint'.*blueprint, dilated-edges"):
        load_pipeline("bluprint")


# -- user shaders ------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    "shader, toml, fragments",
    [
        (None, USER, ["passes.t.shader: shader file", "tint.frag not found"]),
        (
            SHADER.replace("u_src", "u_source"),
            USER,
            ["passes.t.inputs.src", "declares no 'uniform sampler2D u_src;'"],
        ),
        (
            SHADER.replace("uniform float u_gain", "uniform int u_gain"),
            USER,
            ["passes.t.uniforms.gain", "must declare 'uniform float u_gain;'", "it declares int"],
        ),
        (
            SHADER,
            USER.replace('type = "float"', 'type = "double"'),
            ["passes.t.uniforms.gain.type", "choose float"],
        ),
        (
            SHADER,
            USER.replace("default = 1.0", "default = 3.0"),
            ["passes.t.uniforms.gain.default", "[0, 2]"],
        ),
        (
            SHADER,
            USER + "[passes.t.params]\ngain = 5.0\n",
            ["passes.t.params.gain", "must be in [0, 2], got 5"],
        ),
        (
            SHADER,
            USER + "[passes.t.params]\ngian = 1.0\n",
            ["passes.t.params.gian: unknown parameter", "choose gain"],
        ),
        (
            SHADER.replace("sampler2D u_src", "isampler2D u_src"),
            USER,
            ["passes.t.inputs.src: 'photo' is rgba8", "needs an integer format"],
        ),
        (SHADER, USER + '[passes.u]\nop = "invert"\nuniforms = {}\n', ["passes.u.uniforms"]),
    ],
)
def test_user_shader_errors(tmp_path, shader, toml, fragments):
    if shader is not None:
        (tmp_path / "tint.frag").write_text(shader)
    assert_one_error(write(tmp_path, toml), fragments)


def test_user_shader_valid(tmp_path):
    (tmp_path / "tint.frag").write_text(SHADER)
    spec = load_pipeline(str(write(tmp_path, USER + "[passes.t.params]\ngain = 1.5\n")))
    bound = spec.bind()
    assert bound.passes["t"].uniforms == {"u_gain": 1.5}
    assert bound.passes["t"].format == "rgba8"


# -- presets and plans ---------------------------------------------------------------------------------
def test_presets_are_valid():
    assert {
        "blueprint",
        "edges-roberts",
        "edges-sobel",
        "dilated-edges",
        "supersampled-blur",
        "screening",
        "toon",
    } <= set(preset_names())
    for name in preset_names():
        plan(load_pipeline(name).bind())


def test_blueprint_plan_is_per_layer_edges_then_composite():
    # at line width 1 visible lines keep the edges' width and hidden ones, half as wide, keep
    # half the ink: the edges pass takes that share, and there is nothing to dilate
    for variables in ({}, {"hidden_width": 1.0}):
        pl = plan(load_pipeline("blueprint").bind(variables))
        assert pl.per_layer == ["edges"] and pl.after == ["drawing"] and pl.stacked == {"edges"}
        assert pl.aliases == {"lines": "edges"}
        assert pl.bound.passes["edges"].uniforms["u_hidden_ink"] == variables.get("hidden_width", 0.5)
    pl = plan(load_pipeline("blueprint").bind({"line_width": 2.0}))
    assert pl.per_layer == ["edges", "lines"] and pl.stacked == {"lines"}
    assert pl.bound.passes["lines"].uniforms == {"u_radius": 1.0, "u_hidden_width": 0.5}
    assert pl.bound.passes["edges"].uniforms["u_hidden_ink"] == 1.0
    # hidden lines a third of visible ones 2 wide (4 supersampled): narrower than the edges
    pl = plan(load_pipeline("blueprint").bind({"line_width": 2.0, "hidden_width": 1 / 3}))
    assert pl.bound.passes["lines"].uniforms["u_hidden_width"] == 0.5
    assert abs(pl.bound.passes["edges"].uniforms["u_hidden_ink"] - 2 / 3) < 1e-12


def test_blueprint_highlight_shade_and_reveal_are_passes_of_the_preset():
    """Off by default: no attribute of chosen parts is read and no stop rule peels."""
    pl = plan(load_pipeline("blueprint").bind())
    assert pl.parts == [] and pl.accumulated == [] and pl.bound.stops == ()
    bound = load_pipeline("blueprint").bind({"highlight": True, "reveal": 0.9, "shade": True})
    pl = plan(bound)
    assert pl.parts == ["highlight_depth", "highlight_ids", "highlight_normal", "shade_depth", "shade_normal"]
    assert [(s.rule, s.depth, s.fraction) for s in bound.stops] == [("reveal", "highlight_depth", 0.9)]
    assert pl.per_layer == ["edges", "shade_layers"] and pl.accumulated == ["shade_layers"]
    assert pl.slots["shade_layers"].space == "A" and "shade_layers" not in pl.stacked
    assert set(pl.iteration0) >= {"highlight_edges", "shading"} and pl.after == ["drawing"]
    drawing = bound.passes["drawing"].inputs
    assert drawing == {
        "layers": "lines",
        "highlight": "highlight_lines",
        "shade_color": "shading",
        "shade_index": "shade_layers",
    }
    # the highlight's lines are the style's highlight width times the line width
    assert bound.passes["highlight_lines"].uniforms["u_radius"] == (1.0 * 2.0 - 1) * 2 / 2
    # the optional inputs of passes that are off are left unwired
    assert load_pipeline("blueprint").bind({"shade": True}).passes["drawing"].inputs.keys() == {
        "layers",
        "shade_color",
        "shade_index",
    }


def test_targets_are_reused_once_read(tmp_path):
    chain = ["[pipeline]\noutput = 'p5'\n[images.photo]\n"]
    previous = "photo"
    for k in range(1, 6):
        chain.append(f'[passes.p{k}]\nop = "invert"\ninputs = {{ source = "{previous}" }}\n')
        previous = f"p{k}"
    pl = plan(load_pipeline(str(write(tmp_path, "".join(chain)))).bind())
    assert len(set(pl.slots.values())) == 2  # a chain ping-pongs between two targets
    assert pl.slots["p1"] == pl.slots["p3"] == pl.slots["p5"] != pl.slots["p2"]


def test_once_result_read_by_every_layer_keeps_its_target(tmp_path):
    text = """
    [pipeline]
    output = "c"
    [attributes]
    normal = {}
    depth = {}
    [images.photo]
    [passes.g]
    op = "invert"
    inputs = { source = "photo" }
    [passes.e]
    op = "roberts"
    inputs = { source = "normal" }
    per_layer = true
    [passes.m]
    op = "mix"
    inputs = { a = "e", b = "g" }
    format = "r8"
    per_layer = true
    [passes.c]
    op = "composite"
    inputs = { layers = "m" }
    """
    pl = plan(load_pipeline(str(write(tmp_path, text))).bind())
    assert pl.iteration0 == ["g", "e", "m"] and pl.after == ["c"]
    assert pl.slots["g"].space == "F" and pl.slots["e"].space == "L"
    # g is read again at every layer: nothing run in the loop may take its target
    assert all(pl.slots[n] != pl.slots["g"] for n in pl.iteration0 if n != "g" and n in pl.slots)
    assert pl.stacked == {"m"}
