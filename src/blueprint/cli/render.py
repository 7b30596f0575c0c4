"""``blueprint render`` (PNG, or vector lines as SVG, PDF, DXF) and ``blueprint layers`` (NPZ)."""

from __future__ import annotations

from pathlib import Path

import click

from blueprint.api.draw import output_writer
from blueprint.cli.options import CAMERA_OPTIONS, drawing_options, drawing_values, phase_bar
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


# every option of the API's that the command line has (DrawOptions' fields)
RENDER_OPTIONS = (
    *CAMERA_OPTIONS, "supersample", "max_layers", "min_fraction", "reveal", "style", "grid", "line_width",
    "crease_angle", "id_silhouettes", "smooth_contours", "highlight", "shade", "shade_opacity", "section",
    "section_plane", "section_keep", "dimensions", "units", "title", "scale", "sheet", "glyphs",
)  # fmt: skip


@click.command()
@click.argument("model", type=click.Path(path_type=Path))
@click.option("-o", "--output", cls=_OutputOption, type=click.Path(path_type=Path), required=True)
@drawing_options(*RENDER_OPTIONS, size=(1024, 1024))
@click.option(
    "--highlight-model",
    type=click.Path(path_type=Path),
    default=None,
    help="Outline the parts that this second model file lies on.",
)
def render(model, output, highlight_model, **values):
    """Draw the blueprint of MODEL into a picture (PNG), or as vector lines into SVG, PDF or DXF."""
    from blueprint.api import default_renderer, render_frame, stages
    from blueprint.api.options import DrawOptions
    from blueprint.scene.headers import pictures_only
    from blueprint.scene.loader import load_model
    from blueprint.scene.prepare import topologies_kept

    output, write = output_writer(output, Kind.IMAGE, Kind.DRAWING)
    chosen = drawing_values(values)
    if highlight_model:
        if chosen.get("highlight"):
            raise InputError("give --highlight or --highlight-model, not both")
        chosen["highlight"] = load_model(highlight_model, up=chosen.get("up"))
    # BLUEPRINT_STAGES: the stages timed, the frame's synchronised (blueprint.api.stages)
    timing = stages.enabled()
    options = DrawOptions(**chosen, **({"profile": True} if timing else {}))
    if write.kind is Kind.DRAWING:
        from blueprint.api.files import render_vector_file

        # one model drawn once: what its preparation finds has no later reader
        with phase_bar(), topologies_kept(False):
            summary = render_vector_file(model, output, options=options)
        _vector_done(output, summary)
        return
    if options.scale or options.sheet:
        raise InputError(f"--scale and --sheet are for vector drawings ({_suffixes(Kind.DRAWING)})")
    options.raster_style  # noqa: B018 - a line style file a picture cannot take fails before the model loads
    with phase_bar(), topologies_kept(False), pictures_only():
        with stages.timed("read"):
            loaded = load_model(model, up=options.up, include=options.include, exclude=options.exclude)
        if timing or stages.listening():
            stages.watch(default_renderer())
        frame = render_frame(loaded, options=options)
        with stages.timed("write"):
            write(output, frame.image)
    info = default_renderer().info
    if timing:
        stages.add_frame(frame.stages)
        stages.report(default_renderer())
    shown = f", {frame.revealed:.0%} of the highlighted parts shown" if frame.revealed is not None else ""
    shown += _chunked(default_renderer().capturer.chunks(loaded))
    click.echo(
        printable(
            f"{output}: {frame.image.shape[1]}x{frame.image.shape[0]}, {loaded.triangle_count} triangles"
            f"{guessed_up(loaded.up, loaded.up_reason)}, {frame.layers_shown}{shown}, {frame.ms:.1f} ms "
            f"on {info['renderer']}"
        )
    )


def _chunked(chunks: int) -> str:
    """What a command's line says of a mesh that did not fit the GPU beside its frame: drawn,
    slower, a chunk at a time (``Capturer.chunks``)."""
    return f", drawn in {chunks} chunks" if chunks else ""


def _vector_done(output, summary: dict) -> None:
    """Print the line of a vector drawing written (``render_vector_file``'s summary)."""
    from blueprint.api import default_renderer, stages

    if stages.enabled():
        for name, seconds in summary["seconds"].items():
            if name != "total":
                stages.add("read" if name == "load" else name, seconds)
        stages.report(default_renderer())
    levels = ", ".join(f"level {k}: {n}" for k, n in sorted(summary["lines"].items()))
    click.echo(
        printable(
            f"{output}: {summary['bytes']} bytes{guessed_up(summary['up'], summary['up_reason'])}, "
            f"polylines {levels or 'none'}{_chunked(summary['chunks'])}, "
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
@drawing_options(*CAMERA_OPTIONS, "max_layers", "min_fraction", size=(512, 512), max_layers=0)
def layers(model, output, **values):
    """Peel MODEL's depth layers and write them as NPZ (depth, triangle, part, view, projection)."""
    from blueprint.api import default_renderer, peel, stages
    from blueprint.api.frames import as_model
    from blueprint.api.options import DrawOptions
    from blueprint.scene.headers import pictures_only

    output, write = output_writer(output, Kind.LAYERS)
    # checked before the model loads; the model kept to tell the chunks its mesh was drawn in
    options = DrawOptions(**drawing_values(values))
    with phase_bar(), pictures_only():
        if stages.listening():
            stages.begin("read")
            stages.watch(default_renderer())
        loaded = as_model(model, options)
        result = peel(loaded, options=options)
        with stages.timed("write"):
            write(output, result)
    click.echo(
        printable(
            f"{output}: {len(result.depth)} layers of {result.depth.shape[2]}x{result.depth.shape[1]}"
            f"{_chunked(default_renderer().capturer.chunks(loaded))}"
        )
    )
