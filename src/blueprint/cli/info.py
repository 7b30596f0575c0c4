"""``blueprint info`` (the OpenGL renderer, or a model's parts) and ``blueprint bench`` (timings)."""

from __future__ import annotations

import json
from pathlib import Path

import click

from blueprint.errors import printable


@click.command()
@click.argument("model", required=False, type=click.Path(path_type=Path))
@click.option("--json", "as_json", is_flag=True, help="Print JSON.")
def info(model, as_json):
    """Without MODEL: the OpenGL renderer, the ways it draws and the EGL devices (for --gpus
    and BLUEPRINT_GL_DEVICE). With MODEL: its parts, triangles, bounds, length unit (the
    file's, or assumed) and size."""
    if model is None:
        from blueprint.api.renderer import Renderer
        from blueprint.gpu.context import egl_devices

        with Renderer() as r:
            data = dict(r.info)
            data["image_passes"] = "compute shaders" if r.use_compute else "fragment passes"
            data.update(r.capture_table.describe())
            snap = r.depth_snap_px()
            if r.capture_table.exact_depth:
                data["depth"] = f"exact planes (the driver's depths come from snapped corners: {snap:.2g} px)"
            else:
                data["depth"] = f"as rasterised (coincident faces {snap:.2g} px apart)"
        data["egl_devices"] = egl_devices()
        if as_json:
            click.echo(json.dumps(data))
        else:
            click.echo(
                f"renderer: {data['renderer']}\nvendor: {data['vendor']}\nOpenGL: {data['version']}\n"
                f"image passes: {data['image_passes']}\nk-buffer: {data['kbuffer']}\n"
                f"A-buffer: {data['abuffer']}\ndepth: {data['depth']}"
            )
            for device in data["egl_devices"]:
                kind = "GPU" if device["gpu"] else "software"
                click.echo(f"EGL device {device['index']}: {device['renderer']} ({kind})")
        return
    from blueprint.scene.headers import pictures_only
    from blueprint.scene.instanced_parts import environment_of
    from blueprint.scene.loader import load_model
    from blueprint.scene.units import ASSUMED_UNIT, UNITS_MM

    # every part, environment meshes marked: the names to give --include and --exclude; read,
    # not drawn, so weighed no more than a picture
    with pictures_only():
        loaded = load_model(model, include="*")
    environment = environment_of(loaded)
    counts = loaded.part_triangle_counts()
    lo, hi = loaded.bounds
    unit = loaded.unit or ASSUMED_UNIT
    size = hi - lo
    if as_json:
        click.echo(
            json.dumps(
                {
                    "file": str(model),
                    "triangles": loaded.triangle_count,
                    "up": loaded.up,
                    "up_reason": loaded.up_reason,
                    "bounds": [lo.tolist(), hi.tolist()],
                    "unit": unit,
                    "unit_assumed": loaded.unit is None,
                    "unit_reason": loaded.unit_reason,
                    "size": size.tolist(),
                    "size_mm": (size * UNITS_MM[unit]).tolist(),
                    "parts": [
                        {"index": i, "name": n, "triangles": int(c), "environment": bool(e)}
                        for i, (n, c, e) in enumerate(
                            zip(loaded.part_names, counts, environment, strict=True)
                        )
                    ],
                }
            )
        )
        return
    click.echo(
        printable(
            f"{model}: {loaded.triangle_count} triangles, {len(loaded.part_names)} parts, "
            f"up {loaded.up} ({loaded.up_reason})"
        )
    )
    click.echo(f"bounds: [{lo[0]:.6g}, {lo[1]:.6g}, {lo[2]:.6g}] - [{hi[0]:.6g}, {hi[1]:.6g}, {hi[2]:.6g}]")
    if loaded.unit is None:
        click.echo(f"unit: {unit}, assumed ({loaded.unit_reason}; render --units sets it)")
    else:
        click.echo(f"unit: {unit}, from the file ({loaded.unit_reason})")
    sizes = " x ".join(f"{v:.6g}" for v in size)
    in_mm = "" if unit == "mm" else " = " + " x ".join(f"{v:.6g}" for v in size * UNITS_MM[unit]) + " mm"
    click.echo(f"size: {sizes} {unit}{in_mm}")
    for i, (name, count, around) in enumerate(zip(loaded.part_names, counts, environment, strict=True)):
        note = "  (environment: left out unless --include names it)" if around else ""
        click.echo(printable(f"  {i:4d}  {count:9d}  {name}{note}"))


@click.command()
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
