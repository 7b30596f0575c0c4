"""``blueprint render`` (PNG, or vector lines as SVG, PDF, DXF) and ``blueprint layers`` (NPZ)."""

from __future__ import annotations

from pathlib import Path

import click

from blueprint.api.draw import output_writer
from blueprint.cli.options import STYLE_NAMES, camera_kwargs, camera_options
from blueprint.compose.linestyle import FILE_SUFFIXES, is_style_file
from blueprint.errors import InputError, printable
from blueprint.export.writers import WRITERS, Kind
from blueprint.scene.up import guessed_up


def _suffixes(kind: Kind) -> str:
    """The suffixes of ``kind`` as the registry has them."""
    return ", ".join(WRITERS.suffixes(kind))


class _OutputOption(click.Option):
    """``-o``, its help naming every format written: made when help is shown, since listing the
    vector formats loads the vector package, which a picture's drawing does without."""

    def get_help_record(self, ctx: click.Context):
        self.help = (
            f"File to write: a picture ({_suffixes(Kind.IMAGE)}) or vector lines "
            f"({_suffixes(Kind.DRAWING)}); depth layers (.npz) come from blueprint layers."
        )
        return super().get_help_record(ctx)


@click.command()
@click.argument("model", type=click.Path(path_type=Path))
@click.option("-o", "--output", cls=_OutputOption, type=click.Path(path_type=Path), required=True)
@camera_options
@click.option(
    "--style",
    default="blueprint",
    show_default=True,
    help=f"One of {', '.join(STYLE_NAMES)}, or a line style file ({' or '.join(FILE_SUFFIXES)}: "
    "colour, width, dash and opacity per occlusion level; pictures draw no dashes).",
)
@click.option("--grid", type=float, default=None, help="Grid spacing in pixels (0: none).")
@click.option(
    "--max-layers",
    type=int,
    default=8,
    show_default=True,
    help="Depth layers to peel at most (0: all; --reveal peels as deep as it needs).",
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
@click.option(
    "--units",
    default=None,
    help="The model's length unit for --scale, dimensions and plan sheets (um, mm, cm, m, km, in, ft); "
    "default: the file's (glTF, STEP: m; 3MF: its own), else mm, with a warning.",
)
@click.option("--id-silhouettes", is_flag=True, help="Add triangle-ID silhouettes to every layer's edges.")
@click.option("--shade", default=None, help="Parts to draw shaded inside the drawing: globs or indices.")
@click.option(
    "--shade-opacity", type=float, default=1.0, show_default=True, help="1 opaque, less see-through."
)
@click.option(
    "--glyphs",
    type=click.Path(path_type=Path),
    default=None,
    help="TOML or JSON file of boxes, arrows, paths, labels and dimensions in model coordinates.",
)
@click.option(
    "--reveal",
    type=float,
    default=None,
    help="Depth masking: peel until this fraction of the highlighted parts shows.",
)
@click.option(
    "--section",
    default=None,
    help="Section view: x=VALUE, y=VALUE or z=VALUE (model units); the side facing the camera is removed.",
)
@click.option(
    "--section-plane",
    default=None,
    metavar="PX,PY,PZ,NX,NY,NZ",
    help="Section by any plane: a point of it and a normal towards the side removed.",
)
@click.option("--section-keep", default=None, help="Parts drawn uncut in a section: globs or indices.")
@click.option(
    "--sheet",
    default=None,
    help="Paper of a vector plan sheet: A4, A3, A2, A1 or A0 (landscape); the scale fits it unless --scale.",
)
@click.option(
    "--dimensions",
    is_flag=True,
    help="Overall dimensions and circle diameters of orthographic views and plan sheets (ISO 129, mm).",
)
@click.option(
    "--title", default=None, help="Title of a plan sheet's title block (default: the model's name)."
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
    include,
    exclude,
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
    glyphs,
    reveal,
    section,
    section_plane,
    section_keep,
    sheet,
    title,
    dimensions,
):
    """Draw the blueprint of MODEL into a picture (PNG), or as vector lines into SVG, PDF or DXF."""
    from blueprint.api import default_renderer, render_frame
    from blueprint.scene.loader import load_model

    output, write = output_writer(output, Kind.IMAGE, Kind.DRAWING)
    if highlight and highlight_model:
        raise InputError("give --highlight or --highlight-model, not both")
    camera = camera_kwargs(size, view, azimuth, elevation, fov, ortho, up, (1024, 1024), plan=True)
    if write.kind is Kind.DRAWING:
        if highlight_model:
            model = load_model(model, up=camera["up"], include=include, exclude=exclude)
            highlight = load_model(highlight_model, up=camera["up"])
        _render_vector(
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
            section=section,
            section_plane=section_plane,
            section_keep=section_keep,
            sheet=sheet,
            title=title,
            dimensions=dimensions,
            glyphs=glyphs,
            shade=shade,
            shade_opacity=shade_opacity,
            include=include,
            exclude=exclude,
            **camera,
        )
        return
    if scale or sheet:
        raise InputError(f"--scale and --sheet are for vector drawings ({_suffixes(Kind.DRAWING)})")
    if is_style_file(style):
        # read before the model, so a bad file is refused at once
        from blueprint.compose.linestyle import load_raster_style

        style = load_raster_style(style)
    up_axis = camera.pop("up")
    loaded = load_model(model, up=up_axis, include=include, exclude=exclude)
    designated = load_model(highlight_model, up=up_axis) if highlight_model else highlight
    frame = render_frame(
        loaded,
        style=style,
        grid=grid,
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
        section=section,
        section_plane=section_plane,
        section_keep=section_keep,
        dimensions=dimensions,
        units=units,
        title=title,
        **camera,
    )
    write(output, frame.image)
    info = default_renderer().info
    shown = f", {frame.revealed:.0%} of the highlighted parts shown" if frame.revealed is not None else ""
    click.echo(
        printable(
            f"{output}: {frame.image.shape[1]}x{frame.image.shape[0]}, {loaded.triangle_count} triangles"
            f"{guessed_up(loaded.up, loaded.up_reason)}, {frame.layers_shown}{shown}, {frame.ms:.1f} ms "
            f"on {info['renderer']}"
        )
    )


def _render_vector(model, output, **options) -> None:
    """Write the vector drawing (``render_vector_file``'s options) and print its line."""
    from blueprint.api import default_renderer
    from blueprint.api.files import render_vector_file

    summary = render_vector_file(model, output, **options)
    levels = ", ".join(f"level {k}: {n}" for k, n in sorted(summary["lines"].items()))
    click.echo(
        printable(
            f"{output}: {summary['bytes']} bytes{guessed_up(summary['up'], summary['up_reason'])}, "
            f"polylines {levels or 'none'}, "
            f"{summary['seconds']['total']:.2f} s on {default_renderer().info['renderer']}"
        )
    )


@click.command()
@click.argument("model", type=click.Path(path_type=Path))
@click.option(
    "-o",
    "--output",
    type=click.Path(path_type=Path),
    required=True,
    help=f"File to write ({', '.join(WRITERS.suffixes(Kind.LAYERS))}).",
)
@camera_options
@click.option("--max-layers", type=int, default=0, show_default=True, help="Layers at most (0: all).")
@click.option("--min-fraction", type=float, default=0.0, show_default=True)
def layers(
    model, output, size, view, azimuth, elevation, fov, ortho, up, include, exclude, max_layers, min_fraction
):
    """Peel MODEL's depth layers and write them as NPZ (depth, triangle, part, view, projection)."""
    from blueprint.api import peel
    from blueprint.scene.loader import load_model

    output, write = output_writer(output, Kind.LAYERS)
    kwargs = camera_kwargs(size, view, azimuth, elevation, fov, ortho, up, (512, 512))
    loaded = load_model(model, up=kwargs.pop("up"), include=include, exclude=exclude)
    result = peel(loaded, max_layers=max_layers or None, min_fraction=min_fraction, **kwargs)
    write(output, result)
    click.echo(
        printable(f"{output}: {len(result.depth)} layers of {result.depth.shape[2]}x{result.depth.shape[1]}")
    )
