"""``DrawOptions``: every drawing option in one frozen value, each check made once where the
value is made, its messages naming the API argument; ``takes_options``, which gives the entry
points their keywords from its fields."""

from __future__ import annotations

import dataclasses
import inspect
import sys
import threading

import numpy as np
import pytest
from helpers import ROOT

from blueprint import examples
from blueprint.api.options import GROUPS, DrawOptions, option_fields, takes_options, zero_layers_are_all
from blueprint.compose.glyphs import Glyphs
from blueprint.compose.linestyle import load_raster_style, load_vector_style
from blueprint.compose.style import STYLES
from blueprint.errors import InputError
from blueprint.scene.model import Model

LINES = ROOT / "examples" / "lines.toml"
MARKS = ROOT / "examples" / "marks.toml"

# every check, and the one line it fails with
REFUSED = [
    (
        dict(view="sideways"),
        "unknown view 'sideways' (choose iso, front, back, left, right, top, bottom, plan)",
    ),
    (dict(size=(0, 0)), "size must be at least 1x1 pixels, got 0x0"),
    (dict(size=("wide", 3)), "size must be two integers W H, got ('wide', 3)"),
    (dict(supersample=5), "supersample must be 1, 2, 3 or 4, got 5"),
    (dict(size=None, supersample=0), "supersample must be 1, 2, 3 or 4, got 0"),
    (dict(max_layers=0), "max_layers must be between 1 and 256, got 0"),
    (dict(max_layers=257), "max_layers must be between 1 and 256, got 257"),
    (dict(min_fraction=-0.1), "min_fraction must be in [0, 1], got -0.1"),
    (dict(min_fraction=1.5), "min_fraction must be in [0, 1], got 1.5"),
    (dict(reveal=0.5), "reveal needs parts to reveal: give highlight as well"),
    (dict(reveal=0.0, highlight="gear"), "reveal must be in (0, 1], got 0.0"),
    (dict(reveal=1.5, highlight="gear"), "reveal must be in (0, 1], got 1.5"),
    (
        dict(style="neon"),
        "unknown style 'neon' (choose blueprint, paper, transparent, wireframe or a line style file)",
    ),
    (dict(grid=float("nan")), "grid must be a spacing of pixels >= 0, got nan"),
    (dict(grid=-1.0), "grid must be a spacing of pixels >= 0, got -1.0"),
    (dict(line_width=0.5), "line_width must be in [1, 16] pixels, got 0.5"),
    (dict(line_width=20), "line_width must be in [1, 16] pixels, got 20"),
    (dict(crease_angle=-1.0), "crease_angle must be in [0, 180] degrees, got -1.0"),
    (dict(crease_angle=181), "crease_angle must be in [0, 180] degrees, got 181"),
    (dict(depth_threshold=0.0), "depth_threshold must be in [0.1, 1000] pixel footprints, got 0.0"),
    (dict(shade_opacity=0.0), "shade_opacity must be in (0, 1], got 0.0"),
    (dict(shade_opacity=1.5), "shade_opacity must be in (0, 1], got 1.5"),
    (dict(section="q=1"), "section 'q=1' is not of the form x=VALUE, y=VALUE or z=VALUE (model units)"),
    (dict(section="x=1", section_plane="0,0,0,1,0,0"), "give --section or --section-plane, not both"),
    (dict(section_keep="pin"), "--section-keep names parts left uncut: give --section or --section-plane"),
    (dict(units="furlong"), "unknown units 'furlong' (choose um, mm, cm, m, km, in, ft)"),
    (dict(scale="fifty"), "scale must look like 1:50, got 'fifty'"),
    (dict(view="plan", sheet="A9"), "unknown sheet 'A9' (choose A4, A3, A2, A1, A0)"),
    (dict(sheet="A3"), "--sheet A3 sets the paper of a plan sheet: give --view plan"),
    (dict(view="plan", glyphs=MARKS), "glyphs need one view; the plan sheet draws four"),
]


@pytest.mark.parametrize(
    ("options", "message"), REFUSED, ids=[m.split(" ")[0] + str(i) for i, (_, m) in enumerate(REFUSED)]
)
def test_each_check_is_one_line_naming_the_argument(options, message):
    with pytest.raises(InputError) as caught:
        DrawOptions(**options)
    assert str(caught.value) == message


def test_a_variant_is_checked_too():
    options = DrawOptions(line_width=2.0)
    with pytest.raises(InputError, match=r"^line_width must be in \[1, 16\] pixels, got 17$"):
        dataclasses.replace(options, line_width=17)
    top = dataclasses.replace(options, view="top", ortho=True)
    assert (top.view, top.ortho, top.line_width) == ("top", True, 2.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        options.view = "top"


def test_the_defaults_and_what_is_made_of_the_values():
    options = DrawOptions(size=[64.0, np.int64(48)])
    assert options.size == (64, 48) and all(type(v) is int for v in options.size)
    assert (options.view, options.max_layers, options.supersample, options.style) == (
        "iso",
        8,
        2,
        "blueprint",
    )
    assert DrawOptions(size=None).size is None  # a pipeline's own size
    assert options.plane is None
    cut = DrawOptions(section="z=2.5")
    assert cut.plane.axis == "z" and cut.plane.point.tolist() == [0.0, 0.0, 2.5]


def test_styles_by_name_file_and_object():
    named = DrawOptions(style="paper", grid=8)
    assert named.raster_style == STYLES["paper"].with_options(grid=8.0)
    assert named.vector_style.name == "paper"
    assert DrawOptions(style=STYLES["wireframe"]).raster_style is STYLES["wireframe"]
    # a line style file is read once, when the options are made
    from_file = DrawOptions(style=str(LINES))
    assert from_file.vector_style == load_vector_style(LINES)
    assert from_file.raster_style == load_raster_style(LINES)
    lines = load_vector_style(LINES)
    assert DrawOptions(style=lines).vector_style is lines


def test_a_bad_style_file_is_refused_when_the_options_are_made(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[[levels]]\nwidth = 'wide'\n")
    with pytest.raises(InputError, match=f"^{bad}: levels 0: width must be a number"):
        DrawOptions(style=bad)
    thin = tmp_path / "thin.toml"
    thin.write_text("highlight_width = 0.5\n")
    options = DrawOptions(style=thin)  # a vector drawing takes it
    assert options.vector_style.highlight_width == 0.5
    with pytest.raises(InputError, match=r"thin.toml: .*highlight_width must be in \[1, 8\]"):
        options.raster_style  # noqa: B018 - a picture does not


def test_glyph_files_are_read_when_the_options_are_made():
    options = DrawOptions(glyphs=MARKS)
    assert isinstance(options.glyphs, Glyphs) and options.glyphs.source == str(MARKS)
    assert len(options.glyphs.boxes) > 0
    assert dataclasses.replace(options, view="top").glyphs is options.glyphs


def test_frame_keywords_resolve_style_and_parts():
    model = examples.gearbox()
    names = model.part_names
    options = DrawOptions(style="paper", grid=4, highlight=names[0], reveal=0.5, shade=[0])
    frame = options.frame_keywords(model)
    assert frame["style"] == STYLES["paper"].with_options(grid=4.0)
    expected = np.zeros(len(names), bool)
    expected[0] = True
    np.testing.assert_array_equal(frame["highlight"], expected)
    np.testing.assert_array_equal(frame["shade"], expected)
    assert frame["reveal"] == 0.5 and frame["size"] == (1024, 1024)


def test_every_field_says_what_the_command_line_makes_of_it():
    for name, f in option_fields().items():
        assert f.metadata["group"] in GROUPS, name
        assert f.metadata["help"], name
    groups = [f.metadata["group"] for f in option_fields().values()]
    assert groups == sorted(groups, key=GROUPS.index), "fields are listed group by group"
    off = {n for n, f in option_fields().items() if not f.metadata["cli"]}
    assert off == {"camera", "depth_threshold", "part_edges", "profile"}


# -- takes_options ----------------------------------------------------------------------------------
@takes_options("size", "view", "max_layers", size=(512, 512), max_layers=None)
def _entry(model, options, *, normals=True):
    return model, options, normals


def test_an_entry_point_takes_the_fields_it_names_as_keywords():
    params = inspect.signature(_entry).parameters
    assert list(params) == ["model", "options", "size", "view", "max_layers", "normals"]
    assert {n: params[n].default for n in ("size", "view", "max_layers", "normals")} == {
        "size": (512, 512),
        "view": "iso",
        "max_layers": None,
        "normals": True,
    }
    assert params["size"].annotation == option_fields()["size"].type
    model, options, normals = _entry("m")
    assert (model, options.size, options.max_layers, normals) == ("m", (512, 512), None, True)
    _, options, normals = _entry("m", size=(3, 4), view="top", normals=False)
    assert (options.size, options.view, normals) == ((3, 4), "top", False)


def test_an_entry_point_takes_a_ready_value_and_overrides_of_it():
    ready = DrawOptions(size=(9, 9), view="front")
    _, options, _ = _entry("m", options=ready)
    assert options is not ready and options == ready  # its own defaults do not override it
    _, options, _ = _entry("m", options=ready, view="top")
    assert (options.size, options.view) == ((9, 9), "top")
    with pytest.raises(InputError, match="^max_layers must be"):
        _entry("m", options=ready, max_layers=0)
    with pytest.raises(TypeError, match="unexpected keyword argument 'line_width'"):
        _entry("m", line_width=2.0)


def test_an_entry_point_binds_every_call_its_signature_takes():
    """The usual call is bound by hand, any other by the signature, as it would be."""
    model, options, normals = _entry(model="m", view="top", normals=False)
    assert (model, options.view, normals) == ("m", "top", False)
    with pytest.raises(TypeError, match="missing a required argument: 'model'"):
        _entry(view="top")
    with pytest.raises(TypeError, match="too many positional arguments"):
        _entry("m", "n")


def test_a_repeated_call_checks_its_options_once():
    """A stream's frames ask for the same options: the value made for the last call is passed
    again where every value given is the same and hashable, and no file is read."""
    _, first, _ = _entry("m", size=(3, 4), view="top")
    _, again, _ = _entry("m", size=(3, 4), view="top")
    assert again is first
    _, other, _ = _entry("m", size=(3, 4), view="front")
    assert other is not first and other.view == "front"
    size = [3, 4]  # a list may change between calls: made again
    _, listed, _ = _entry("m", size=size)
    size[0] = 5
    _, changed, _ = _entry("m", size=size)
    assert (listed.size, changed.size) == ((3, 4), (5, 4))


def test_threads_each_get_the_options_they_asked_for():
    """The last call's options are kept as one value: a thread never gets another's."""
    wrong = []

    def calls(view):
        for _ in range(3000):
            _, options, _ = _entry("m", size=(3, 4), view=view)
            if options.view != view:
                wrong.append(options.view)

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        threads = [threading.Thread(target=calls, args=(view,)) for view in ("top", "front", "iso")]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join()
    finally:
        sys.setswitchinterval(interval)
    assert not wrong


def test_a_style_file_is_read_again_by_each_call(tmp_path):
    @takes_options("style")
    def entry(options):
        return options

    path = tmp_path / "lines.toml"
    path.write_text("highlight_width = 2\n")
    assert entry(style=str(path)).vector_style.highlight_width == 2
    path.write_text("highlight_width = 3\n")
    assert entry(style=str(path)).vector_style.highlight_width == 3


def test_frame_keywords_are_each_models_own():
    gearbox = examples.gearbox()
    options = DrawOptions(highlight=gearbox.part_names[0])
    first = options.frame_keywords(gearbox)
    first["highlight"] = None  # the caller's copy
    assert options.frame_keywords(gearbox)["highlight"][0]
    two = Model(
        np.eye(3), np.array([[0, 1, 2], [0, 2, 1]]), np.array([0, 1]), ("other", gearbox.part_names[0])
    )
    assert options.frame_keywords(two)["highlight"].tolist() == [False, True]


def test_zero_layers_are_all_where_an_entry_point_says_so():
    @takes_options("max_layers", prepare=zero_layers_are_all)
    def entry(options):
        return options.max_layers

    assert (entry(max_layers=0), entry(max_layers=3), entry()) == (None, 3, 8)


# -- the command line --------------------------------------------------------------------------------
def test_the_command_line_names_its_flags_where_the_api_names_an_argument():
    from blueprint.cli.options import with_flags

    assert (
        with_flags("line_width must be in [1, 16] pixels, got 20")
        == "--line-width must be in [1, 16] pixels, got 20"
    )
    assert with_flags("shade_opacity must be in (0, 1], got 0") == "--shade-opacity must be in (0, 1], got 0"
    # spelled the same either way, or not an option: as it is
    for same in (
        "supersample must be 1, 2, 3 or 4, got 9",
        "p.toml: variables.line_width: unknown variable",
        "/tmp/line_width.stl: no triangles in the file",
        "style x: hidden_width must be in (0, 16], got 20",
    ):
        assert with_flags(same) == same


def test_the_render_command_takes_its_options_from_the_fields():
    from blueprint.cli.render import RENDER_OPTIONS
    from blueprint.cli.render import render as command

    params = {p.name: p for p in command.params}
    on_cli = {n for n, f in option_fields().items() if f.metadata["cli"]}
    assert set(RENDER_OPTIONS) == on_cli
    assert set(params) == on_cli | {"model", "output", "highlight_model"}
    for name in on_cli:
        f, option = option_fields()[name], params[name]
        assert option.opts == ["--" + name.replace("_", "-")]
        assert option.help == f.metadata["help"]
        expected = (1024, 1024) if name == "size" else f.default
        assert option.default == expected, name


@pytest.mark.parametrize(
    ("flags", "line"),
    [
        (["--line-width", "20"], "--line-width must be in [1, 16] pixels, got 20.0"),
        (["--max-layers", "300"], "--max-layers must be between 1 and 256, got 300"),
        (["--shade", "0", "--shade-opacity", "0"], "--shade-opacity must be in (0, 1], got 0.0"),
        (["--supersample", "9"], "supersample must be 1, 2, 3 or 4, got 9"),
        (["--reveal", "0.5"], "reveal needs parts to reveal: give highlight as well"),
    ],
)
def test_the_command_line_prints_the_check_with_its_flag(tmp_path, capsys, flags, line):
    from blueprint import cli

    with pytest.raises(SystemExit) as exited:
        cli.main(["render", str(examples.example_path()), "-o", str(tmp_path / "x.png"), *flags])
    assert exited.value.code == 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == f"blueprint: error: {line}"
    assert not list(tmp_path.iterdir())
