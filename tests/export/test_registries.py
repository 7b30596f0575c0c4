"""The registries: output writers by suffix (export.writers), raster styles by name
(compose.style.STYLES), and the API's typed keywords, which the command line's options map to.
"""

from __future__ import annotations

import importlib
import inspect
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from helpers import ROOT

import blueprint.vector.drawing as drawing
from blueprint import examples
from blueprint.api import peel, render, render_frame
from blueprint.api.files import choose_writer, render_vector_file
from blueprint.api.renderer import Renderer
from blueprint.bench import time_frames
from blueprint.cli import STYLE_NAMES
from blueprint.cli.render import layers as layers_command
from blueprint.cli.render import render as render_command
from blueprint.compose.compositor import COMPOSITE
from blueprint.compose.style import STYLES
from blueprint.errors import InputError
from blueprint.export.files import save_layers, save_png
from blueprint.export.writers import PROVIDERS, WRITERS, Kind, Writers
from blueprint.pipeline.media import write_video
from blueprint.pipeline.spec import OPERATIONS
from blueprint.vector.style import is_style_file, vector_style

LINE_STYLE = ROOT / "examples" / "lines.toml"


def _writes(tag: str):
    def write(path: Path, value) -> Path:
        path.write_text(f"{tag} {value}")
        return path

    return write


# -- the registry, on one of its own --------------------------------------------------------------
@pytest.fixture
def writers() -> Writers:
    own = Writers()
    own.add(".png", Kind.IMAGE, _writes("png"))
    own.add(".svg", Kind.DRAWING, _writes("svg"))
    own.add(".pdf", Kind.DRAWING, _writes("pdf"))
    own.add(".npz", Kind.LAYERS, _writes("npz"))
    return own


def test_a_suffix_picks_its_writer(writers, tmp_path):
    path, writer = writers.choose(tmp_path / "plan.PDF", Kind.IMAGE, Kind.DRAWING)
    assert path == tmp_path / "plan.PDF"
    assert (writer.suffix, writer.kind) == (".pdf", Kind.DRAWING)
    assert writer(path, 7) == path and path.read_text() == "pdf 7"


def test_suffixes_come_in_the_order_of_the_kinds_asked(writers):
    assert writers.suffixes(Kind.IMAGE, Kind.DRAWING) == (".png", ".svg", ".pdf")
    assert writers.suffixes(Kind.DRAWING, Kind.IMAGE) == (".svg", ".pdf", ".png")
    assert writers.suffixes(Kind.VIDEO) == ()


def test_an_unknown_suffix_is_one_line_naming_the_allowed_ones(writers, tmp_path):
    with pytest.raises(InputError) as caught:
        writers.choose(tmp_path / "x.jpg", Kind.IMAGE, Kind.DRAWING)
    assert str(caught.value) == f"{tmp_path / 'x.jpg'}: output must end in .png or .svg or .pdf"
    # a suffix another kind writes is not allowed either
    with pytest.raises(InputError) as caught:
        writers.choose(tmp_path / "x.npz", Kind.IMAGE)
    assert str(caught.value) == f"{tmp_path / 'x.npz'}: output must end in .png"


def test_a_format_given_overrides_the_suffix(writers, tmp_path):
    path, writer = writers.choose(tmp_path / "drawing.out", Kind.DRAWING, suffix=".svg")
    assert (path, writer.suffix) == (tmp_path / "drawing.out", ".svg")


def test_unwritable_paths_fail_before_any_work(writers, tmp_path):
    with pytest.raises(InputError, match="does not exist"):
        writers.choose(tmp_path / "missing" / "x.png", Kind.IMAGE)
    (tmp_path / "folder.png").mkdir()
    with pytest.raises(InputError, match="is a directory"):
        writers.choose(tmp_path / "folder.png", Kind.IMAGE)


def test_registering_mistakes_are_bugs(writers):
    with pytest.raises(ValueError, match="registered already"):
        writers.add(".png", Kind.IMAGE, _writes("again"))
    for suffix in ("png", ".PNG", "."):
        with pytest.raises(ValueError, match="suffix"):
            writers.add(suffix, Kind.IMAGE, _writes("bad"))
    with pytest.raises(LookupError, match="no writer of video frames"):
        writers.choose("x.mp4", Kind.VIDEO)


def test_one_suffix_may_have_a_writer_per_kind(writers, tmp_path):
    writers.add(".npz", Kind.IMAGE, _writes("image npz"))
    assert writers.choose(tmp_path / "x.npz", Kind.LAYERS)[1].kind == Kind.LAYERS
    assert writers.choose(tmp_path / "x.npz", Kind.IMAGE, Kind.LAYERS)[1].kind == Kind.IMAGE


# -- the package's registry ---------------------------------------------------------------------------
def test_every_format_and_its_writer():
    """The kinds made above export are registered by the functions ``PROVIDERS`` names, each
    of its own kind, when a suffix of that kind is first looked for."""
    assert PROVIDERS == {
        Kind.DRAWING: "blueprint.vector.drawing:register_writers",
        Kind.VIDEO: "blueprint.pipeline.media:register_writers",
    }
    for kind, provider in PROVIDERS.items():
        own = Writers()
        module, function = provider.split(":")
        getattr(importlib.import_module(module), function)(own)
        assert {k for k, _ in own._writers} == {kind}
    assert WRITERS.suffixes(*Kind)
    table = {(w.kind, w.suffix): w.write for w in WRITERS._writers.values()}
    assert table == {
        (Kind.IMAGE, ".png"): save_png,
        (Kind.LAYERS, ".npz"): save_layers,
        (Kind.DRAWING, ".svg"): drawing._write_svg,
        (Kind.DRAWING, ".pdf"): drawing._write_pdf,
        (Kind.DRAWING, ".dxf"): drawing._write_dxf,
        **{(Kind.VIDEO, s): write_video for s in (".mp4", ".mov", ".mkv", ".avi", ".m4v")},
    }
    assert drawing.FORMATS == (".svg", ".pdf", ".dxf")


def test_the_commands_choices(tmp_path):
    path, writer = choose_writer(tmp_path / "a.Svg", Kind.IMAGE, Kind.DRAWING)
    assert writer.write is drawing._write_svg
    with pytest.raises(InputError) as caught:
        choose_writer(tmp_path / "a.jpg", Kind.IMAGE, Kind.DRAWING)
    assert str(caught.value) == f"{tmp_path / 'a.jpg'}: output must end in .png or .svg or .pdf or .dxf"


def test_a_format_added_in_one_line_is_chosen_by_the_command_line(renderer, tmp_path, monkeypatch):
    """A PPM writer and the one line that registers it: ``blueprint render -o x.ppm`` writes
    through it, and the message for an unknown suffix names it."""
    monkeypatch.setattr(WRITERS, "_writers", dict(WRITERS._writers))

    def save_ppm(path: Path, image: np.ndarray) -> Path:
        path.write_bytes(b"P6 %d %d 255\n" % (image.shape[1], image.shape[0]) + image[..., :3].tobytes())
        return path

    WRITERS.add(".ppm", Kind.IMAGE, save_ppm)
    model = str(examples.example_path())
    out = tmp_path / "x.ppm"
    result = CliRunner().invoke(render_command, [model, "-o", str(out), "--size", "16", "12"])
    assert result.exit_code == 0, result.output
    assert out.read_bytes().startswith(b"P6 16 12 255\n") and len(out.read_bytes()) == 13 + 16 * 12 * 3
    result = CliRunner().invoke(render_command, [model, "-o", str(tmp_path / "x.gif")], standalone_mode=False)
    assert str(result.exception).endswith("output must end in .png or .ppm or .svg or .pdf or .dxf")


def test_layers_take_only_their_writers(tmp_path):
    model = str(examples.example_path())
    result = CliRunner().invoke(layers_command, [model, "-o", str(tmp_path / "x.png")], standalone_mode=False)
    assert isinstance(result.exception, InputError)
    assert str(result.exception) == f"{tmp_path / 'x.png'}: output must end in .npz"


def test_a_video_suffix_without_animation_asks_for_it(tmp_path):
    from blueprint.api.silhouettes import render_silhouettes_file

    with pytest.raises(InputError, match="a video needs --animate"):
        render_silhouettes_file("unread.glb", tmp_path / "x.mkv")
    with pytest.raises(InputError, match=r"output must end in \.mp4 or \.mov or \.mkv or \.avi or \.m4v"):
        render_silhouettes_file("unread.glb", tmp_path / "x.png", animate="twist")


# -- styles ------------------------------------------------------------------------------------------
def test_one_list_of_raster_styles():
    assert STYLE_NAMES == tuple(STYLES) == ("blueprint", "paper", "transparent", "wireframe")
    # the composite op takes its style names from STYLES, and pipelines find it by name
    [style] = [p for p in COMPOSITE.params if p.name == "style"]
    assert style.choices == tuple(STYLES)
    assert OPERATIONS["composite"] is COMPOSITE


def test_vector_styles_by_name_file_or_object(tmp_path):
    assert vector_style("paper").name == "paper"
    from_file = vector_style(str(LINE_STYLE))
    assert from_file.name == "lines" and vector_style(LINE_STYLE) == from_file
    assert vector_style(from_file) is from_file
    assert vector_style(STYLES["wireframe"]).name == "wireframe"
    with pytest.raises(InputError) as caught:
        vector_style("neon")
    assert str(caught.value) == (
        "unknown style 'neon' (choose blueprint, paper, transparent, wireframe or a line style file)"
    )
    with pytest.raises(InputError, match="line style file must end in .toml or .json"):
        vector_style(tmp_path / "lines.yaml")
    assert is_style_file("a/b.TOML") and is_style_file(Path("b.json"))
    assert not is_style_file("paper") and not is_style_file(STYLES["paper"])


# -- the API's keywords --------------------------------------------------------------------------------
def _keywords(function) -> dict[str, object]:
    params = inspect.signature(function).parameters.values()
    assert not [p for p in params if p.kind is p.VAR_KEYWORD], f"{function.__name__} takes **kwargs"
    return {p.name: p.default for p in params if p.kind is p.KEYWORD_ONLY}


def test_frames_take_every_renderer_argument_by_name_with_its_default():
    frame = _keywords(render_frame)
    assert _keywords(render) == frame
    renderer = _keywords(Renderer.render)
    assert renderer.pop("on_gpu") is False  # a window's frames alone stay on the GPU
    assert {k: frame[k] for k in renderer} == renderer
    layers = _keywords(Renderer.peel)
    assert {k: v for k, v in _keywords(peel).items() if k in layers} == layers
    assert set(_keywords(time_frames)) == {"size", "max_layers", "supersample", "style", "frames", "warmup"}


def test_every_render_option_is_an_api_argument():
    """``--highlight-model`` is the one exception: it loads a model for ``highlight``."""
    frame, vector = set(_keywords(render_frame)), set(_keywords(render_vector_file))
    for param in render_command.params:
        if param.name in ("model", "output", "highlight_model"):
            continue
        assert param.name in frame | vector, f"--{param.name} is no argument of the API"
    assert {p.name for p in layers_command.params} - {"model", "output"} <= set(_keywords(peel))
    assert "output" in inspect.signature(render_vector_file).parameters


def test_writers_register_when_their_kind_is_first_looked_for(tmp_path):
    """A picture's suffix is found without loading the vector drawings' writers; a vector
    drawing's loads them, and a suffix of no kind asked for lists every kind's."""
    code = (
        "import sys\n"
        "from blueprint.export.writers import WRITERS, Kind\n"
        f"WRITERS.choose({str(tmp_path / 'a.png')!r}, Kind.IMAGE, Kind.DRAWING)\n"
        "print('blueprint.vector.drawing' in sys.modules, 'blueprint.pipeline.media' in sys.modules)\n"
        f"WRITERS.choose({str(tmp_path / 'a.svg')!r}, Kind.IMAGE, Kind.DRAWING)\n"
        "print('blueprint.vector.drawing' in sys.modules, 'blueprint.pipeline.media' in sys.modules)\n"
    )
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.split("\n")[:2] == ["False False", "True False"]
