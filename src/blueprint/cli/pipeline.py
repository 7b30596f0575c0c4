"""``blueprint pipeline run|check``, ``blueprint ops``, ``blueprint turntable``: a thin shell over
``blueprint.api.files.run_pipeline`` and ``turntable``, the pipeline specs and the ops."""

from __future__ import annotations

import json
from pathlib import Path

import click

from blueprint.cli.options import camera_options, progress_bar
from blueprint.errors import printable


@click.group("pipeline")
def pipeline() -> None:
    """Image-space pipelines declared in TOML files (or presets: blueprint, edges-sobel, ...)."""


@pipeline.command("run")
@click.argument("file")
@click.argument("input", required=False, type=click.Path(path_type=Path))
@click.option(
    "-o", "--output", type=click.Path(path_type=Path), required=True, help="PNG, NPZ or video to write."
)
@camera_options
@click.option(
    "--set", "settings", multiple=True, metavar="NAME=VALUE", help="Override a variable of the file."
)
@click.option("--image", "images", multiple=True, metavar="NAME=PATH", help="Give an image input its file.")
@click.option(
    "--parts",
    "part_sets",
    multiple=True,
    metavar="NAME=PARTS",
    help="A set of parts the file's attributes name (name globs or indices, comma-separated), "
    "e.g. highlight='gear*' with --set highlight=true for the blueprint preset.",
)
@click.option(
    "--dump", multiple=True, metavar="NAME", help="Also write this target beside the output (PNG or NPZ)."
)
@click.option("--max-layers", type=int, default=None, help="Depth layers to peel at most (0: all).")
@click.option("--frames", type=click.IntRange(1), default=None, help="Video input: frames to filter at most.")
def run_command(
    file,
    input,
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
    settings,
    images,
    part_sets,
    dump,
    max_layers,
    frames,
):
    """Run pipeline FILE (a .toml file or a preset name) on INPUT (a model, image or video)."""
    from blueprint.api import default_renderer
    from blueprint.api.files import run_pipeline
    from blueprint.pipeline.run import parse_assignments

    with progress_bar("frames") as progress:
        result = run_pipeline(
            file,
            input,
            output,
            size=tuple(size) if size else None,
            view=view,
            azimuth=azimuth,
            elevation=elevation,
            fov=fov,
            ortho=ortho,
            up=up,
            include=include,
            exclude=exclude,
            set=parse_assignments(settings, "--set"),
            image=parse_assignments(images, "--image"),
            parts=parse_assignments(part_sets, "--parts"),
            dump=tuple(dump),
            max_layers=max_layers,
            frames=frames,
            progress=progress,
        )
    shape = result.output.shape
    layers = f", {result.layers} layers" if result.layer_pixels else ""
    click.echo(
        printable(
            f"{output}: {shape[-2]}x{shape[-3]} {result.format}{layers}, {result.ms:.1f} ms "
            f"on {default_renderer().info['renderer']}"
        )
    )


@pipeline.command("check")
@click.argument("file")
@click.option(
    "--set", "settings", multiple=True, metavar="NAME=VALUE", help="Override a variable of the file."
)
def check_command(file, settings):
    """Validate pipeline FILE without touching the GPU and print its plan."""
    from blueprint.pipeline.graph import plan
    from blueprint.pipeline.run import parse_assignments, parse_value
    from blueprint.pipeline.spec import load_pipeline

    spec = load_pipeline(file)
    bound = spec.bind({k: parse_value(v) for k, v in parse_assignments(settings, "--set").items()})
    pl = plan(bound)
    click.echo(printable(f"{spec.source}: ok: {bound.name}, output {bound.output}"))
    for name, a in bound.attributes.items():
        used = "" if name in pl.attributes else " (unused)"
        click.echo(f"  attribute {name:14s} {a.format:8s} x{a.scale:g}{used}")
    for name, img in bound.images.items():
        click.echo(f"  image     {name:14s} {img.format:8s} x{img.scale:g} {img.file or '(given when run)'}")
    for name, p in bound.passes.items():
        if name in pl.aliases:
            stage = f"skipped: passes {pl.aliases[name]} through"
        elif name not in pl.passes:
            stage = "unused"
        elif p.per_layer:
            stage = "every layer"
        elif name in pl.after:
            stage = "after the peel"
        else:
            stage = "once"
        target = "own per layer" if name in pl.stacked else pl.slots[name].name if name in pl.slots else "-"
        click.echo(
            f"  pass      {name:14s} {p.format:8s} x{p.scale:g} {p.op.name:12s} {stage}; target {target}"
        )
    click.echo(f"  {len(set(pl.slots.values()))} shared targets for {len(pl.slots)} results")


@click.command("ops")
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def ops(as_json):
    """List the image-space operations with their inputs, output and parameters."""
    from blueprint.ops import ChoiceParam
    from blueprint.pipeline.schema import OPERATIONS

    records = []
    for op in OPERATIONS.values():
        params = []
        for p in op.params:
            entry = {"name": p.name, "default": p.default, "doc": p.doc}
            if isinstance(p, ChoiceParam):
                entry["choices"] = list(p.choices)
            elif not isinstance(p.default, bool):
                entry["min"], entry["max"] = p.minimum, p.maximum
            params.append(entry)
        records.append(
            {
                "name": op.name,
                "inputs": dict(op.inputs),
                "stacks": list(getattr(op, "stacks", ())),
                "output": op.output,
                "params": params,
                "doc": op.doc,
                "shader": op.shader,
            }
        )
    if as_json:
        for record in records:
            click.echo(json.dumps(record))
        return
    for r in records:
        inputs = ", ".join(
            f"{k} ({'every layer of ' if k in r['stacks'] else ''}{v})" for k, v in r["inputs"].items()
        )
        click.echo(f"{r['name']}: {r['doc']}")
        click.echo(f"    inputs: {inputs}; output: {r['output']}")
        for p in r["params"]:
            if "choices" in p:
                allowed = " | ".join(p["choices"])
            elif "min" in p:
                lo = "-inf" if p["min"] is None else f"{p['min']:g}"
                hi = "inf" if p["max"] is None else f"{p['max']:g}"
                allowed = f"[{lo}, {hi}]"
            else:
                allowed = "true | false"
            default = str(p["default"]).lower() if isinstance(p["default"], bool) else p["default"]
            click.echo(f"    {p['name']} = {default}  {allowed}  {p['doc']}")


@click.command("turntable")
@click.argument("model", type=click.Path(path_type=Path))
@click.option(
    "-o", "--output", type=click.Path(path_type=Path), required=True, help="Video to write (.mp4, ...)."
)
@click.option(
    "--frames", type=click.IntRange(1, 100000), default=60, show_default=True, help="Frames of one turn."
)
@click.option("--fps", type=float, default=30.0, show_default=True, help="Frames per second.")
@click.option("--size", nargs=2, type=int, default=(640, 480), show_default=True, metavar="W H")
@click.option(
    "--pipeline", "pipeline_file", default="blueprint", show_default=True, help="Preset name or .toml file."
)
@click.option("--elevation", type=float, default=None, help="Degrees above the horizon (default 25).")
@click.option("--azimuth", type=float, default=0.0, show_default=True, help="Degrees of the first frame.")
@click.option("--fov", type=float, default=30.0, show_default=True)
@click.option("--ortho", is_flag=True)
@click.option("--up", type=click.Choice(["y", "z"]), default=None)
@click.option("--set", "settings", multiple=True, metavar="NAME=VALUE", help="Override a pipeline variable.")
@click.option("--crf", type=int, default=18, show_default=True, help="H.264 quality, 0 (lossless) to 51.")
def turntable(
    model, output, frames, fps, size, pipeline_file, elevation, azimuth, fov, ortho, up, settings, crf
):
    """Orbit the camera around MODEL and write a video of a pipeline (the blueprint by default)."""
    from blueprint.api.files import turntable as make_turntable
    from blueprint.pipeline.run import parse_assignments

    with progress_bar("turntable") as progress:
        path = make_turntable(
            model,
            output,
            frames=frames,
            fps=fps,
            size=tuple(size),
            pipeline=pipeline_file,
            elevation=elevation,
            azimuth=azimuth,
            fov=fov,
            ortho=ortho,
            up=up,
            set=parse_assignments(settings, "--set"),
            crf=crf,
            progress=progress,
        )
    click.echo(printable(f"{path}: {frames} frames of {size[0]}x{size[1]} at {fps:g} fps"))
