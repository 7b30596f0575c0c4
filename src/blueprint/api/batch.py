"""Batch drawing on Dask: many model files, several views and formats each, one task per input,
spread over worker processes that each hold their own OpenGL context (on their own EGL device
where the host has several GPUs), with a manifest and outputs that a rerun does not redo."""

from __future__ import annotations

import contextlib
import glob
import json
import os
import time
import traceback
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from blueprint.api.draw import Drawing, draw, to_model
from blueprint.api.renderer import Renderer
from blueprint.errors import BlueprintError, InputError, printable
from blueprint.export.files import atomic_write
from blueprint.scene.formats import FORMATS
from blueprint.scene.headers import pictures_only

__all__ = ["MANIFEST", "MODEL_SUFFIXES", "batch", "choose_devices", "collect_inputs", "outputs_for"]

#: The file each batch writes into its output folder.
MANIFEST = "manifest.json"

#: Suffixes a folder given as input is searched for (any case).
MODEL_SUFFIXES = tuple(f".{suffix}" for suffix in FORMATS.common_suffixes())

#: The Dask resource each drawing worker holds one of: a task needs one, so a worker draws one
#: input at a time, on its own device.
RESOURCE = "GPU"


def collect_inputs(inputs: Iterable[str | os.PathLike]) -> list[Path]:
    """Model files from files, folders (searched recursively for ``MODEL_SUFFIXES``) and glob
    patterns, in order, each once.

    Raises ``InputError`` for a path or pattern that names nothing.
    """
    found: dict[Path, None] = {}
    for given in inputs:
        text = os.fspath(given)
        path = Path(text)
        if path.is_dir():
            matches = sorted(p for p in path.rglob("*") if p.suffix.lower() in MODEL_SUFFIXES and p.is_file())
            if not matches:
                raise InputError(f"{printable(text)}: no model files in this folder")
        elif path.exists():
            matches = [path]
        elif glob.has_magic(text):
            matches = sorted(Path(p) for p in glob.glob(text, recursive=True) if Path(p).is_file())
            if not matches:
                raise InputError(f"{printable(text)}: no files match this pattern")
        else:
            raise InputError(f"{printable(text)}: no such file or folder")
        found.update(dict.fromkeys(matches))
    if not found:
        raise InputError("give at least one model file, folder or pattern")
    return list(found)


def _root(paths: Sequence[Path]) -> Path:
    parents = [p.resolve().parent for p in paths]
    return Path(os.path.commonpath(parents)) if parents else Path(".")


def outputs_for(
    path: Path, root: Path, outdir: Path, views: Sequence[str], formats: Sequence[str]
) -> list[Path]:
    """The files a batch writes for ``path``: ``OUTDIR/<folder below root>/<stem>.<view>.<format>``,
    so that models of one name in different folders do not overwrite each other."""
    below = path.resolve().parent.relative_to(root)
    return [outdir / below / f"{path.stem}.{view}.{fmt}" for view in views for fmt in formats]


def _up_to_date(path: Path, outputs: Sequence[Path]) -> bool:
    try:
        made = path.stat().st_mtime
        return all(out.stat().st_mtime > made for out in outputs)
    except OSError:
        return False


def choose_devices(gpus: str | int | Sequence[int] | None) -> list[int] | None:
    """The EGL device indices ``gpus`` names: ``"all"`` (every GPU device, or every EGL device
    where none is a GPU, as with llvmpipe alone), a count ``N`` (the first N of those), or
    indices (``"0,2"``, ``[0, 2]``; ``"2,"`` is device 2 alone). None: the driver's default.

    Raises ``InputError`` for a device that does not exist or a count beyond the host's.
    """
    from blueprint.gpu.context import egl_devices

    if gpus is None:
        return None
    devices = egl_devices()
    usable = [d["index"] for d in devices if d["gpu"]] or [
        d["index"] for d in devices if not str(d["renderer"]).startswith("unusable")
    ]
    if isinstance(gpus, str):
        text = gpus.strip().lower()
        if text == "all":
            if not usable:
                raise InputError("--gpus all: this machine has no usable EGL device (see 'blueprint info')")
            return usable
        try:
            gpus = [int(part) for part in text.split(",") if part.strip()] if "," in text else int(text)
        except ValueError:
            raise InputError(f"--gpus {text!r}: give all, a count N, or device indices like 0,2") from None
    if isinstance(gpus, int):
        if gpus < 1 or gpus > len(usable):
            raise InputError(
                f"--gpus {gpus}: this machine has {len(usable)} usable EGL devices (see 'blueprint info')"
            )
        return usable[:gpus]
    chosen = [int(g) for g in gpus]
    if not chosen:
        raise InputError("--gpus: give at least one device index")
    known = {d["index"] for d in devices}
    for index in chosen:
        if index not in known:
            raise InputError(
                f"--gpus: EGL device {index} does not exist ({len(known)} here: see 'blueprint info')"
            )
    if len(set(chosen)) != len(chosen):
        raise InputError(f"--gpus: device indices repeat in {','.join(map(str, chosen))}")
    return chosen


# One per worker process: its device (set by the client before the first task) and the
# renderer that owns its context, created on the first task.
_worker: dict[str, object] = {"device": None, "renderer": None}


def _set_device(device: int | None) -> int | None:
    _worker["device"] = device
    return device


def _renderer() -> Renderer:
    if _worker["renderer"] is None:
        from blueprint.gpu.context import create_context

        _worker["renderer"] = Renderer(create_context(device=_worker["device"]))
    return _worker["renderer"]


def draw_input(path: str, outputs: list[str], views: list[str], options: dict) -> dict:
    """Draw one model file into its outputs (a task of the batch, run in a worker): one
    drawing per view, saved in every format; outputs newer than the input are kept.

    Returns the manifest record: ``input``, ``outputs``, ``layers`` per view, ``ms``, and
    ``error`` (one line) where the input could not be drawn; never raises for a bad input.
    """
    start = time.perf_counter()
    record: dict = {"input": path, "outputs": [], "layers": {}, "ms": 0.0, "error": None}
    try:
        renderer = _renderer()
        record["device"] = _worker["device"]
        record["renderer"] = renderer.info["renderer"]
        # weighed as a picture's where no output is a vector drawing
        with pictures_only() if all(Path(p).suffix == ".png" for p in outputs) else contextlib.nullcontext():
            model = to_model(path)
        made = os.stat(path).st_mtime
        per_view = len(outputs) // len(views)
        for k, view in enumerate(views):
            mine = [Path(p) for p in outputs[k * per_view : (k + 1) * per_view]]
            todo = [p for p in mine if not (p.exists() and p.stat().st_mtime > made)]
            if todo:
                raster = any(p.suffix == ".png" for p in todo)
                drawing: Drawing = draw(model, view=view, vector=not raster, renderer=renderer, **options)
                for out in todo:
                    out.parent.mkdir(parents=True, exist_ok=True)
                    drawing.save(out)
                record["layers"][view] = drawing.layers
            record["outputs"].extend(str(p) for p in mine)
    except BlueprintError as exc:
        record["error"] = _about(path, str(exc))
    except Exception as exc:  # one broken file never stops the batch: its error is its record
        last = traceback.extract_tb(exc.__traceback__)[-1]
        where = f"{Path(last.filename).name}:{last.lineno}"
        record["error"] = _about(path, f"{type(exc).__name__}: {exc} (at {where})")
    record["ms"] = round((time.perf_counter() - start) * 1e3, 2)
    return record


def _about(path: str, message: str) -> str:
    """``message`` as one line that names the input."""
    return printable(message if message.startswith(path) else f"{path}: {message}")


def _check_outputs(views: Sequence[str], formats: Sequence[str]) -> tuple[list[str], list[str]]:
    import blueprint.api.files  # noqa: F401 - registers the vector and video writers
    from blueprint.export.writers import WRITERS, Kind
    from blueprint.scene.camera import VIEWS

    views = [v.strip() for v in views if v.strip()]
    formats = [f.strip().lower().lstrip(".") for f in formats if f.strip()]
    if not views or not formats:
        raise InputError("give at least one view (--views) and one format (--formats)")
    for view in views:
        if view not in VIEWS and view != "plan":
            raise InputError(f"unknown view {view!r} (choose {', '.join([*VIEWS, 'plan'])})")
    allowed = WRITERS.suffixes(Kind.IMAGE, Kind.DRAWING)
    for fmt in formats:
        if f".{fmt}" not in allowed:
            raise InputError(f"unknown format {fmt!r} (choose {', '.join(s.lstrip('.') for s in allowed)})")
    return list(dict.fromkeys(views)), list(dict.fromkeys(formats))


def _local_cluster(workers: int, devices: list[int] | None):
    import logging

    from dask.distributed import Client, LocalCluster

    cluster = LocalCluster(
        n_workers=workers,
        threads_per_worker=1,
        processes=True,
        resources={RESOURCE: 1},
        dashboard_address=None,
        silence_logs=logging.ERROR,
    )
    client = Client(cluster)
    addresses = sorted(client.scheduler_info()["workers"])
    for k, address in enumerate(addresses):
        # more workers than devices share them, round robin
        device = None if devices is None else devices[k % len(devices)]
        client.run(_set_device, device, workers=[address])
    return cluster, client


def batch(
    inputs: Iterable[str | os.PathLike],
    outdir: str | os.PathLike,
    *,
    views: Sequence[str] = ("iso",),
    formats: Sequence[str] = ("png",),
    workers: int | None = None,
    scheduler: str | None = None,
    gpus: str | int | Sequence[int] | None = None,
    size: tuple[int, int] = (1024, 1024),
    style: str = "blueprint",
    max_layers: int | None = 8,
    progress: Callable[[int, int], None] | None = None,
) -> dict:
    """Draw every input in every view and format into ``outdir`` on Dask, and write
    ``outdir/manifest.json``.

    Parameters
    ----------
    inputs : iterable of str or PathLike
        Model files, folders (searched recursively) and glob patterns.
    outdir : str or PathLike
        Where the drawings go: ``<stem>.<view>.<format>``, in the inputs' folders below their
        common one.
    views : sequence of str
        Named views (``iso``, ``top``, ... or ``plan``).
    formats : sequence of str
        ``png``, ``svg``, ``pdf``, ``dxf``.
    workers : int, optional
        Worker processes of the local cluster, each with its own OpenGL context (default: one
        per chosen GPU, else 1). More workers than devices share them.
    scheduler : str, optional
        The address of a running Dask scheduler to use instead of a local cluster; its workers
        choose their EGL device by ``BLUEPRINT_GL_DEVICE``.
    gpus : "all", int or sequence of int, optional
        EGL devices for the local cluster's workers, one worker each (see ``choose_devices``).
    size, style, max_layers
        As ``draw`` takes them.
    progress : callable, optional
        Called as ``progress(done, total)`` as inputs finish.

    Returns
    -------
    dict
        The manifest: ``inputs`` (a record per input: ``input``, ``outputs``, ``layers`` per
        view, ``ms``, ``error``, and ``skipped`` where its outputs were newer than it),
        ``drawn``, ``skipped``, ``failed``, ``workers``, ``devices``, ``seconds``.

    Raises
    ------
    InputError
        Bad arguments (no inputs, unknown views or formats, devices that do not exist).
    """
    start = time.perf_counter()
    paths = collect_inputs(inputs)
    views, formats = _check_outputs(views, formats)
    _check_workers(workers, scheduler, gpus)
    outdir = _output_folder(outdir)
    devices = choose_devices(gpus)
    count = workers or (len(devices) if devices else 1)
    options = dict(size=tuple(int(v) for v in size), style=style, max_layers=max_layers)
    records, todo = _records_kept(paths, outdir, views, formats)
    if progress is not None:
        progress(len(records), len(paths))
    if todo:
        cluster, client = _client(scheduler, count, devices)
        try:
            _draw_all(client, todo, views, options, records, progress, len(paths))
            count = len(client.scheduler_info()["workers"]) or count
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    ordered = [records[str(p)] for p in paths]
    manifest = {
        "inputs": ordered,
        "views": views,
        "formats": formats,
        "drawn": sum(1 for r in ordered if not r.get("error") and not r.get("skipped")),
        "skipped": sum(1 for r in ordered if r.get("skipped")),
        "failed": sum(1 for r in ordered if r.get("error")),
        "workers": count if todo else 0,
        "devices": devices,
        "seconds": round(time.perf_counter() - start, 3),
    }
    text = json.dumps(manifest, indent=1)
    atomic_write(outdir / MANIFEST, lambda tmp: tmp.write_text(text, encoding="utf-8"))
    return manifest


def _check_workers(workers: int | None, scheduler: str | None, gpus) -> None:
    """Workers of a local cluster, or a running scheduler's own: not both."""
    if workers is not None and workers < 1:
        raise InputError(f"--workers must be at least 1, got {workers}")
    if scheduler is not None and (gpus is not None or workers is not None):
        raise InputError(
            "--scheduler uses the cluster's own workers: leave out --workers and --gpus "
            "(start workers with BLUEPRINT_GL_DEVICE=N and --resources GPU=1 to place them)"
        )


def _output_folder(outdir: str | os.PathLike) -> Path:
    outdir = Path(outdir)
    if outdir.exists() and not outdir.is_dir():
        raise InputError(f"{printable(str(outdir))}: not a folder")
    outdir.mkdir(parents=True, exist_ok=True)
    return outdir


def _records_kept(
    paths: list[Path], outdir: Path, views: list[str], formats: list[str]
) -> tuple[dict[str, dict], list[tuple[Path, list[Path]]]]:
    """The records an earlier manifest holds of inputs whose outputs are newer than they
    (marked ``skipped``), by input, and the (input, outputs) still to draw."""
    root = _root(paths)
    previous = _previous_records(outdir / MANIFEST)
    records: dict[str, dict] = {}
    todo = []
    for path in paths:
        outputs = outputs_for(path, root, outdir, views, formats)
        if _up_to_date(path, outputs) and str(path) in previous:
            records[str(path)] = {**previous[str(path)], "skipped": True}
        else:
            todo.append((path, outputs))
    return records, todo


def _draw_all(client, todo, views: list[str], options: dict, records: dict, progress, total: int) -> None:
    """Each input of ``todo`` drawn by a task on ``client``'s workers, its record put in
    ``records`` as it finishes (``progress(done, total)`` told)."""
    from dask.distributed import as_completed

    needs = _resources(client)
    futures = {
        client.submit(
            draw_input,
            str(path),
            [str(p) for p in outputs],
            views,
            options,
            key=f"blueprint-{k}-{path.name}",
            resources=needs,
            pure=False,
        ): str(path)
        for k, (path, outputs) in enumerate(todo)
    }
    for future in as_completed(futures):
        path = futures[future]
        try:
            records[path] = future.result()
        except Exception as exc:  # a worker lost for good: its inputs are reported, not redrawn
            records[path] = {"input": path, "outputs": [], "layers": {}, "ms": None}
            records[path]["error"] = printable(f"worker lost: {type(exc).__name__}: {exc}")
        if progress is not None:
            progress(len(records), total)


def _client(scheduler: str | None, workers: int, devices: list[int] | None):
    from dask.distributed import Client

    if scheduler is None:
        return _local_cluster(workers, devices)
    try:
        return None, Client(scheduler, timeout=10)
    except (OSError, TimeoutError) as exc:
        raise InputError(f"--scheduler {printable(scheduler)}: cannot connect ({exc})") from None


def _resources(client) -> dict | None:
    """Tasks need a drawing resource where the cluster's workers declare one (they do on a
    local cluster; an existing cluster's workers may not)."""
    workers = client.scheduler_info()["workers"].values()
    return {RESOURCE: 1} if any(RESOURCE in w.get("resources", {}) for w in workers) else None


def _previous_records(path: Path) -> dict[str, dict]:
    """The successful records of an earlier manifest, by input: what a rerun keeps."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
        return {r["input"]: r for r in data["inputs"] if not r.get("error")}
    except (OSError, ValueError, KeyError, TypeError):
        return {}
