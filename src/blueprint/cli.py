"""The command line: a thin shell over the Python API (every option is an API argument)."""

from __future__ import annotations

import contextlib
import json
import logging
import sys
from pathlib import Path

import click

from blueprint.errors import BlueprintError, InputError
from blueprint.scene.camera import VIEWS

STYLE_NAMES = ("blueprint", "paper", "transparent", "wireframe")


class _OneLine(logging.Handler):
    def emit(self, record: logging.LogRecord) -> None:
        click.echo(f"blueprint: warning: {record.getMessage()}", err=True)


def _setup_logging() -> None:
    log = logging.getLogger("blueprint")
    if not any(isinstance(h, _OneLine) for h in log.handlers):
        log.addHandler(_OneLine())
    log.setLevel(logging.WARNING)
    log.propagate = False


@contextlib.contextmanager
def progress_bar(label: str):
    """A rich progress bar on stderr, shown only on a terminal (in a pipe it would put blank
    lines around error messages). Yields ``update(done, total)``."""
    from rich.console import Console
    from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeRemainingColumn

    console = Console(stderr=True)
    with Progress(
        TextColumn("[progress.description]{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeRemainingColumn(),
        console=console,
        transient=True,
        disable=not console.is_terminal,
    ) as progress:
        task = progress.add_task(label, total=None)

        def update(done: int, total: int) -> None:
            progress.update(task, completed=done, total=total)

        yield update


def camera_options(func):
    """Options shared by every command that places a camera."""
    options = [
        click.option(
            "--size",
            nargs=2,
            type=int,
            default=None,
            metavar="W H",
            help="Image width and height in pixels.",
        ),
        click.option(
            "--view",
            default="iso",
            show_default=True,
            help=f"Named view: {', '.join(VIEWS)}; render also takes plan (a sheet of top, front, right).",
        ),
        click.option(
            "--azimuth", type=float, default=None, help="Degrees from the front, towards the right."
        ),
        click.option("--elevation", type=float, default=None, help="Degrees above the horizon."),
        click.option(
            "--fov",
            type=float,
            default=30.0,
            show_default=True,
            help="Vertical field of view, degrees.",
        ),
        click.option("--ortho", is_flag=True, help="Orthographic projection (plan views)."),
        click.option(
            "--up",
            type=click.Choice(["y", "z"]),
            default=None,
            help="Model up axis (default: z for STL/3MF, y otherwise).",
        ),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def _camera_kwargs(size, view, azimuth, elevation, fov, ortho, up, default_size, plan=False):
    names = [*VIEWS, "plan"] if plan else list(VIEWS)
    if view not in names:
        raise InputError(f"unknown view {view!r} (choose {', '.join(names)})")
    return dict(
        size=tuple(size) if size else default_size,
        view=view,
        azimuth=azimuth,
        elevation=elevation,
        fov=fov,
        ortho=ortho,
        up=up,
    )


class _Commands(click.Group):
    """Commands of other packages, imported when first used: they import this module's shared
    options, so importing them here would be circular."""

    LAZY = {
        "ops": "blueprint.pipeline.command:ops",
        "pipeline": "blueprint.pipeline.command:pipeline",
        "silhouettes": "blueprint.silhouette.command:silhouettes",
        "turntable": "blueprint.pipeline.command:turntable",
        "view": "blueprint.viewer.command:view",
    }

    def list_commands(self, ctx: click.Context) -> list[str]:
        return sorted({*super().list_commands(ctx), *self.LAZY})

    def get_command(self, ctx: click.Context, name: str) -> click.Command | None:
        if name in self.LAZY and name not in self.commands:
            import importlib

            module, attribute = self.LAZY[name].split(":")
            self.add_command(getattr(importlib.import_module(module), attribute), name)
        return super().get_command(ctx, name)


@click.group(cls=_Commands, context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="blueprint")
def cli() -> None:
    """Blueprints of 3D models: the visible and hidden edges of every part, drawn on the GPU."""
    _setup_logging()


@cli.command()
@click.argument("model", type=click.Path(path_type=Path))
@click.option("-o", "--output", type=click.Path(path_type=Path), required=True, help="PNG file to write.")
@camera_options
@click.option(
    "--style",
    default="blueprint",
    show_default=True,
    help=f"One of {', '.join(STYLE_NAMES)}; for .svg, .pdf and .dxf also a line style file "
    "(.toml or .json: colour, width, dash and opacity per occlusion level).",
)
@click.option("--grid", type=float, default=None, help="Grid spacing in pixels (0: none).")
@click.option(
    "--max-layers",
    type=int,
    default=8,
    show_default=True,
    help="Depth layers to peel at most (0: all).",
)
@click.option(
    "--min-fraction",
    type=float,
    default=0.0,
    show_default=True,
    help="Stop when a layer covers less than this fraction of the first.",
)
@click.option("--crease-angle", type=float, default=30.0, show_default=True, help="Degrees.")
@click.option("--line-width", type=float, default=1.0, show_default=True, help="Pixels.")
@click.option("--supersample", type=int, default=2, show_default=True, help="Anti-aliasing factor (1-4).")
@click.option("--highlight", default=None, help="Parts to outline: name globs or indices, comma-separated.")
@click.option(
    "--highlight-model",
    type=click.Path(path_type=Path),
    default=None,
    help="Outline the parts that this second model file lies on.",
)
@click.option(
    "--scale", default=None, help="Vector plan views to scale, e.g. 1:50 (orthographic, page in mm)."
)
@click.option("--units", default=None, help="The model's length unit for --scale (mm, cm, m, in, ft).")
@click.option("--id-silhouettes", is_flag=True, help="Add triangle-ID silhouettes to every layer's edges.")
@click.option("--shade", default=None, help="Parts to draw shaded inside the drawing: globs or indices.")
@click.option(
    "--shade-opacity", type=float, default=1.0, show_default=True, help="1 opaque, less see-through."
)
@click.option(
    "--glyphs",
    "glyph_file",
    type=click.Path(path_type=Path),
    default=None,
    help="TOML or JSON file of boxes, arrows, paths and labels in model coordinates.",
)
@click.option(
    "--reveal",
    type=float,
    default=None,
    help="Depth masking: peel until this fraction of the highlighted parts shows.",
)
def render(
    model,
    output,
    size,
    view,
    azimuth,
    elevation,
    fov,
    ortho,
    up,
    style,
    grid,
    max_layers,
    min_fraction,
    crease_angle,
    line_width,
    supersample,
    highlight,
    highlight_model,
    scale,
    units,
    id_silhouettes,
    shade,
    shade_opacity,
    glyph_file,
    reveal,
):
    """Draw the blueprint of MODEL into a PNG, or as vector lines into SVG, PDF or DXF."""
    from blueprint.api import default_renderer, render_frame
    from blueprint.compose.glyphs import load_glyphs
    from blueprint.compose.style import get_style
    from blueprint.export.files import check_output, save_png
    from blueprint.scene.loader import load_model

    output = check_output(output, (".png", *VECTOR_SUFFIXES))
    if output.suffix.lower() in VECTOR_SUFFIXES:
        if glyph_file or shade:
            raise InputError(
                f"{output}: vector drawings take no --glyphs or --shade yet; write a PNG for those"
            )
        camera = _camera_kwargs(size, view, azimuth, elevation, fov, ortho, up, (1024, 1024), plan=True)
        if highlight and highlight_model:
            raise InputError("give --highlight or --highlight-model, not both")
        if highlight_model:
            model = load_model(model, up=camera["up"])
            highlight = load_model(highlight_model, up=camera["up"])
        _render_vector(
            model,
            output,
            camera,
            style,
            max_layers,
            crease_angle,
            line_width,
            scale,
            units,
            highlight,
            reveal,
        )
        return
    if scale or units:
        raise InputError("--scale and --units are for vector drawings (.svg, .pdf, .dxf)")
    if _is_style_file(style):
        raise InputError(
            f"{style}: line style files are for vector drawings (.svg, .pdf, .dxf); "
            f"a PNG takes one of {', '.join(STYLE_NAMES)}"
        )
    chosen = get_style(style, grid)
    glyphs = load_glyphs(glyph_file) if glyph_file else None
    kwargs = _camera_kwargs(size, view, azimuth, elevation, fov, ortho, up, (1024, 1024), plan=True)
    up_axis = kwargs.pop("up")
    loaded = load_model(model, up=up_axis)
    if highlight and highlight_model:
        raise InputError("give --highlight or --highlight-model, not both")
    designated = load_model(highlight_model, up=up_axis) if highlight_model else highlight
    frame = render_frame(
        loaded,
        style=chosen,
        max_layers=max_layers or None,
        min_fraction=min_fraction,
        crease_angle=crease_angle,
        line_width=line_width,
        supersample=supersample,
        highlight=designated,
        reveal=reveal,
        glyphs=glyphs,
        shade=shade,
        shade_opacity=shade_opacity,
        id_silhouettes=id_silhouettes,
        **kwargs,
    )
    save_png(output, frame.image)
    info = default_renderer().info
    shown = f", {frame.revealed:.0%} of the highlighted parts shown" if frame.revealed is not None else ""
    click.echo(
        f"{output}: {frame.image.shape[1]}x{frame.image.shape[0]}, {loaded.triangle_count} triangles, "
        f"{frame.layers} layers{shown}, {frame.ms:.1f} ms on {info['renderer']}"
    )


VECTOR_SUFFIXES = (".svg", ".pdf", ".dxf")


def _is_style_file(style: str) -> bool:
    return Path(style).suffix.lower() in (".toml", ".json")


def _render_vector(
    model, output, camera, style, max_layers, crease_angle, line_width, scale, units, highlight, reveal
):
    from blueprint.api import default_renderer
    from blueprint.api.files import render_vector_file

    if _is_style_file(style):
        from blueprint.vector import load_vector_style

        style = load_vector_style(style)
    elif style not in STYLE_NAMES:
        raise InputError(f"unknown style {style!r} (choose {', '.join(STYLE_NAMES)} or a line style file)")
    summary = render_vector_file(
        model,
        output,
        style=style,
        max_layers=max_layers or None,
        crease_angle=crease_angle,
        line_width=line_width,
        scale=scale,
        units=units,
        highlight=highlight,
        reveal=reveal,
        **camera,
    )
    levels = ", ".join(f"level {k}: {n}" for k, n in sorted(summary["lines"].items()))
    click.echo(
        f"{output}: {summary['bytes']} bytes, polylines {levels or 'none'}, "
        f"{summary['seconds']['total']:.2f} s on {default_renderer().info['renderer']}"
    )


@cli.command()
@click.argument("model", type=click.Path(path_type=Path))
@click.option("-o", "--output", type=click.Path(path_type=Path), required=True, help="NPZ file to write.")
@camera_options
@click.option("--max-layers", type=int, default=0, show_default=True, help="Layers at most (0: all).")
@click.option("--min-fraction", type=float, default=0.0, show_default=True)
def layers(model, output, size, view, azimuth, elevation, fov, ortho, up, max_layers, min_fraction):
    """Peel MODEL's depth layers and write them as NPZ (depth, triangle, part, view, projection)."""
    from blueprint.api import peel
    from blueprint.export.files import check_output, save_layers
    from blueprint.scene.loader import load_model

    output = check_output(output, (".npz",))
    kwargs = _camera_kwargs(size, view, azimuth, elevation, fov, ortho, up, (512, 512))
    loaded = load_model(model, up=kwargs.pop("up"))
    result = peel(loaded, max_layers=max_layers or None, min_fraction=min_fraction, **kwargs)
    save_layers(output, result)
    click.echo(f"{output}: {len(result.depth)} layers of {result.depth.shape[2]}x{result.depth.shape[1]}")


@cli.command()
@click.argument("model", required=False, type=click.Path(path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def info(model, as_json):
    """Without MODEL: the OpenGL renderer. With MODEL: its parts, triangles and bounds."""
    if model is None:
        from blueprint.gpu import create_context, gl_info

        ctx = create_context()
        data = gl_info(ctx)
        ctx.release()
        if as_json:
            click.echo(json.dumps(data))
        else:
            click.echo(f"renderer: {data['renderer']}\nvendor: {data['vendor']}\nOpenGL: {data['version']}")
        return
    from blueprint.scene.loader import load_model

    loaded = load_model(model)
    counts = loaded.part_triangle_counts()
    lo, hi = loaded.bounds
    if as_json:
        click.echo(
            json.dumps(
                {
                    "file": str(model),
                    "triangles": loaded.triangle_count,
                    "up": loaded.up,
                    "bounds": [lo.tolist(), hi.tolist()],
                    "parts": [
                        {"index": i, "name": n, "triangles": int(c)}
                        for i, (n, c) in enumerate(zip(loaded.part_names, counts, strict=True))
                    ],
                }
            )
        )
        return
    click.echo(f"{model}: {loaded.triangle_count} triangles, {len(loaded.part_names)} parts, up {loaded.up}")
    click.echo(f"bounds: [{lo[0]:.6g}, {lo[1]:.6g}, {lo[2]:.6g}] - [{hi[0]:.6g}, {hi[1]:.6g}, {hi[2]:.6g}]")
    for i, (name, count) in enumerate(zip(loaded.part_names, counts, strict=True)):
        click.echo(f"  {i:4d}  {count:9d}  {name}")


@cli.command()
@click.argument("models", nargs=-1, required=True, type=click.Path(path_type=Path))
@click.option(
    "--size",
    "sizes",
    nargs=2,
    type=int,
    multiple=True,
    metavar="W H",
    help="Image size; repeat for several (default 512 512 and 1024 1024).",
)
@click.option(
    "--max-layers",
    "layer_options",
    type=int,
    multiple=True,
    help="Layers at most; 0 for all; repeat for several (default 5 and 0).",
)
@click.option(
    "--frames", type=click.IntRange(1), default=20, show_default=True, help="Timed frames per configuration."
)
@click.option("--warmup", type=click.IntRange(0), default=3, show_default=True)
@click.option("--supersample", type=int, default=2, show_default=True)
@click.option("--style", default="blueprint", show_default=True)
def bench(models, sizes, layer_options, frames, warmup, supersample, style):
    """Time whole frames (image read back) and print one JSON object per configuration."""
    from blueprint.bench import run_bench

    for record in run_bench(
        models,
        sizes=[tuple(s) for s in sizes] or [(512, 512), (1024, 1024)],
        layer_options=[n or None for n in layer_options] or [5, None],
        frames=frames,
        warmup=warmup,
        supersample=supersample,
        style=style,
    ):
        click.echo(json.dumps(record))


def main(argv: list[str] | None = None) -> None:
    """Entry point: user errors become one line on stderr and exit code 2."""
    run(cli, argv, "blueprint")


def run(command: click.Command, argv: list[str] | None, prog_name: str) -> None:
    """Run a click command as a program: user errors become one line on stderr and exit code 2."""
    _setup_logging()
    try:
        command.main(args=argv, prog_name=prog_name, standalone_mode=False)
    except click.exceptions.Abort:
        click.echo("blueprint: interrupted", err=True)
        sys.exit(130)
    except click.ClickException as exc:
        click.echo(f"blueprint: error: {exc.format_message()}", err=True)
        sys.exit(2)
    except BlueprintError as exc:
        click.echo(f"blueprint: error: {exc}", err=True)
        sys.exit(2)
    except MemoryError:
        click.echo("blueprint: error: out of memory (try a smaller --size)", err=True)
        sys.exit(2)
    except KeyboardInterrupt:
        click.echo("blueprint: interrupted", err=True)
        sys.exit(130)
    sys.exit(0)


if __name__ == "__main__":
    main()
