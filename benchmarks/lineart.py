"""Seconds from a model file to a PNG drawn by Blender's Line Art, on this machine.

The peer that ``vector.py`` is measured against, run side by side: one Blender process a run
(``blender -b --factory-startup``) imports the model, aims a camera from the same 3/4 view
as ours (azimuth 45°, elevation 35.26°, 30° field of view, fitted to the model's box), lets a
scene Line Art object find the edges of occlusion levels 0 (black) to 4 (blue, from the first
modifier's cache) and Workbench renders 512 x 512 to PNG (EEVEE compiles its shaders for
seconds on a software rasteriser). Prints one JSON object per model, medians of ``--runs``
runs: ``seconds`` and ``cpu_seconds``, from the process's start to the PNG written (wall, and
CPU time of every thread); ``phases`` inside Blender (``start``: its Python reached,
``import``, ``render``); ``warm_seconds`` and ``warm_cpu_seconds``, a second render in the
same process with the camera turned by a degree, so that Line Art computes again; and
``process_seconds`` and ``process_cpu_seconds``, the whole process, warm frame and exit
included.

    python benchmarks/lineart.py [--models-dir ../shared/models] [--runs 3] [--keep DIR]

Needs ``blender`` (3.x or later: the Grease Pencil Line Art modifier) on the PATH or as
``--blender``; where Blender cannot open a GL context without a display, ``--xvfb`` runs it
under ``xvfb-run``. Look at the PNGs it keeps: the lines must be there, visible and hidden.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
MODELS = (
    "trimesh/featuretype.STL",
    "common-3d-test-models/stanford-bunny.obj",
    "glTF-Sample-Models/2CylinderEngine.glb",
)

# Runs inside Blender: arguments after "--" are the model, the PNG, the size, the levels and
# the launcher's time.time() when it started the process.
SCRIPT = r'''
import json, math, sys, time
import bpy
from mathutils import Vector

t0 = time.perf_counter()
model, png, width, height, last_level, launched = sys.argv[sys.argv.index("--") + 1 :]
width, height, last_level, launched = int(width), int(height), int(last_level), float(launched)
# since the process began: wall seconds from the launcher's clock, CPU seconds of every thread
marks = {"start": time.time() - launched, "start_cpu": time.process_time()}

for ob in list(bpy.data.objects):
    bpy.data.objects.remove(ob, do_unlink=True)
suffix = model.lower().rsplit(".", 1)[-1]
if suffix == "stl":
    bpy.ops.import_mesh.stl(filepath=model)
elif suffix == "obj":
    bpy.ops.wm.obj_import(filepath=model)
elif suffix in ("glb", "gltf"):
    import numpy

    if not hasattr(numpy, "bool"):  # Blender 3.4's importer still names it; NumPy 1.24 dropped it
        numpy.bool = bool
    bpy.ops.import_scene.gltf(filepath=model)
else:
    raise SystemExit(f"no importer for {model}")
scene = bpy.context.scene
meshes = [ob for ob in scene.objects if ob.type == "MESH"]
marks["import"] = time.perf_counter() - t0

# the hidden lines must show: Workbench draws the meshes in a colour of alpha 0, as
# transparent surfaces, which write no depth to hide the strokes behind them
clear = bpy.data.materials.new("clear")
clear.diffuse_color = (1.0, 1.0, 1.0, 0.0)
for ob in meshes:
    ob.data.materials.clear()
    ob.data.materials.append(clear)

bpy.context.view_layer.update()  # the imported hierarchy's world matrices
corners = [ob.matrix_world @ Vector(c) for ob in meshes for c in ob.bound_box]
lo = Vector([min(c[i] for c in corners) for i in range(3)])
hi = Vector([max(c[i] for c in corners) for i in range(3)])

cam_data = bpy.data.cameras.new("camera")
cam_data.angle_y = math.radians(30.0)
cam_data.sensor_fit = "VERTICAL"
camera = bpy.data.objects.new("camera", cam_data)
scene.collection.objects.link(camera)
scene.camera = camera


def aim(azimuth):
    """Our fit: look from (azimuth, 35.26 degrees), Z up, back off until the box fits."""
    a, e = math.radians(azimuth), math.atan(1 / math.sqrt(2))
    front, right, up = Vector((0, -1, 0)), Vector((1, 0, 0)), Vector((0, 0, 1))
    z = (math.cos(e) * (math.cos(a) * front + math.sin(a) * right) + math.sin(e) * up).normalized()
    x = up.cross(z).normalized()
    y = z.cross(x)
    centre = (lo + hi) / 2
    rel = [c - centre for c in corners]
    px, py, pz = [r.dot(x) for r in rel], [r.dot(y) for r in rel], [r.dot(z) for r in rel]
    centre = centre + x * (max(px) + min(px)) / 2 + y * (max(py) + min(py)) / 2
    mx, my = (max(px) - min(px)) / 2, (max(py) - min(py)) / 2
    tan = math.tan(math.radians(15.0)) * 0.9
    distance = max(pz) + max(mx, my) / tan
    extent = (hi - lo).length
    cam_data.clip_start = max(distance - max(pz) - extent, distance * 1e-3)
    cam_data.clip_end = distance + extent * 2
    camera.location = centre + z * distance
    camera.rotation_euler = (z).to_track_quat("Z", "Y").to_euler()


aim(45.0)

gp = bpy.data.grease_pencils.new("lineart")
gp.stroke_thickness_space = "SCREENSPACE"  # pixels, whatever the model's size
layer = gp.layers.new("lines")
layer.frames.new(scene.frame_current)
lines = bpy.data.objects.new("lineart", gp)
scene.collection.objects.link(lines)
for name, colour, first, last, thickness in (
    ("visible", (0.0, 0.0, 0.0, 1.0), 0, 0, 2),
    ("hidden", (0.0, 0.45, 1.0, 1.0), 1, last_level, 1),
):
    material = bpy.data.materials.new(name)
    bpy.data.materials.create_gpencil_data(material)
    material.grease_pencil.color = colour
    gp.materials.append(material)
    modifier = lines.grease_pencil_modifiers.new(name, "GP_LINEART")
    modifier.source_type = "SCENE"
    modifier.target_layer = "lines"
    modifier.target_material = material
    modifier.thickness = thickness
    modifier.use_multiple_levels = first != last
    modifier.level_start = first
    modifier.level_end = last
    # the second modifier reads the first one's scene, as Line Art's own set-up does
    modifier.use_cache = name == "hidden"

scene.render.engine = "BLENDER_WORKBENCH"
scene.display.shading.light = "FLAT"
scene.display.shading.color_type = "MATERIAL"
scene.render.resolution_x, scene.render.resolution_y = width, height
scene.render.resolution_percentage = 100
scene.render.film_transparent = False
scene.view_settings.view_transform = "Standard"
world = scene.world or bpy.data.worlds.new("world")
scene.world = world
world.use_nodes = False
world.color = (1.0, 1.0, 1.0)
scene.render.image_settings.file_format = "PNG"

t = time.perf_counter()
scene.render.filepath = png
bpy.ops.render.render(write_still=True)
marks["render"] = time.perf_counter() - t
marks["png"], marks["png_cpu"] = time.time() - launched, time.process_time()

# the camera turned by a degree: Line Art finds every line again
aim(46.0)
t, cpu = time.perf_counter(), time.process_time()
scene.render.filepath = png.replace(".png", "_warm.png")
bpy.ops.render.render(write_still=True)
marks["warm"], marks["warm_cpu"] = time.perf_counter() - t, time.process_time() - cpu
drawn = lines.evaluated_get(bpy.context.evaluated_depsgraph_get()).data
marks["strokes"] = sum(len(frame.strokes) for lay in drawn.layers for frame in lay.frames)
marks["blender"] = bpy.app.version_string
print("LINEART " + json.dumps(marks), flush=True)
'''


def blender_version(blender: str) -> str:
    out = subprocess.run([blender, "--version"], capture_output=True, text=True, check=True).stdout
    return out.splitlines()[0].strip()


def process_environment(pycache: Path, source: Path | None = None, **extra: str) -> dict[str, str]:
    """This environment as an installed package runs in: bytecode kept in ``pycache`` (an
    environment without bytecode compiles every module of the package at every start);
    ``source``: a source tree of the package put first on the path."""
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONDONTWRITEBYTECODE", "PYTHONPYCACHEPREFIX")}
    env["PYTHONPYCACHEPREFIX"] = str(pycache)
    if source is not None:
        env["PYTHONPATH"] = os.pathsep.join(p for p in (str(source), env.get("PYTHONPATH")) if p)
    return {**env, **extra}


def run_process(command: list[str], env=None) -> tuple[subprocess.CompletedProcess, float, float]:
    """Run a command: its result, wall seconds and CPU seconds (user and system, every thread)."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    done = subprocess.run(command, capture_output=True, text=True, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return done, wall, cpu


class LineArt:
    """Blender Line Art, file to PNG, one process a run (also used by ``vector.py --lineart``)."""

    def __init__(self, blender: str = "blender", xvfb: bool = False, size=(512, 512), levels: int = 4):
        found = shutil.which(blender)
        if found is None:
            raise RuntimeError(f"{blender} not found")
        self.size, self.levels = tuple(size), levels
        self.env = dict(os.environ)
        binary = Path(found).resolve()
        if not any(binary.parent.glob("*/python")):
            # a distribution's Blender runs on the system Python, which it looks for on the
            # PATH: launched from another Python (pyenv, a venv) it would take that one's
            # standard library, without the system's numpy that its glTF importer needs
            self.env["PYTHONHOME"] = str(binary.parents[1])
        self.version = blender_version(found)
        self.scratch = tempfile.TemporaryDirectory()
        script = Path(self.scratch.name) / "lineart_run.py"
        script.write_text(SCRIPT)
        self.prefix = (["xvfb-run", "-a"] if xvfb else []) + [
            found,
            "-b",
            "--factory-startup",
            "-noaudio",
            "--python-exit-code",
            "1",
            "--python",
            str(script),
            "--",
        ]

    def run(self, model: Path, png: Path) -> dict:
        """One process: seconds from its start to the PNG written (wall, and CPU of all its
        threads), the phases inside it, and the warm frame after; the process's own totals
        (``process``, ``process_cpu``) also count the warm frame and Blender's exit."""
        args = [str(model), str(png), *map(str, self.size), str(self.levels), repr(time.time())]
        done, wall, cpu = run_process(self.prefix + args, self.env)
        found = [line for line in done.stdout.splitlines() if line.startswith("LINEART ")]
        if done.returncode != 0 or not found:
            tail = (done.stdout + done.stderr)[-2000:]
            raise RuntimeError(f"blender failed ({done.returncode}):\n{tail}")
        marks = json.loads(found[-1][len("LINEART ") :])
        return {**marks, "process": wall, "process_cpu": cpu}

    @staticmethod
    def summary(runs: list[dict]) -> dict:
        """Medians over runs (of each figure on its own)."""

        def median(key: str) -> float:
            return round(statistics.median(r[key] for r in runs), 3)

        return {
            "seconds": median("png"),
            "runs": [round(r["png"], 3) for r in runs],
            "cpu_seconds": median("png_cpu"),
            "warm_seconds": median("warm"),
            "warm_cpu_seconds": median("warm_cpu"),
            "phases": {k: median(k) for k in ("start", "start_cpu", "import", "render")},
            "process_seconds": median("process"),
            "process_cpu_seconds": median("process_cpu"),
            "strokes": runs[len(runs) // 2]["strokes"],
        }


def find_model(models_dir: Path, name: str) -> Path | None:
    path = models_dir / name
    if not path.exists():  # a flat folder of models
        path = models_dir / Path(name).name
    return path if path.exists() else None


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--models-dir", type=Path, default=ROOT.parent / "shared" / "models")
    parser.add_argument("--size", nargs=2, type=int, default=[512, 512])
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--blender", default=os.environ.get("BLENDER", "blender"))
    parser.add_argument("--xvfb", action="store_true", help="Run Blender under xvfb-run.")
    parser.add_argument("--keep", type=Path, default=None, help="Folder to keep the PNGs in.")
    parser.add_argument("models", nargs="*", help="Model files (default: the three of vector.py).")
    args = parser.parse_args()
    try:
        lineart = LineArt(args.blender, args.xvfb, args.size)
    except (RuntimeError, subprocess.CalledProcessError) as error:
        print(json.dumps({"skipped": str(error)}))
        sys.exit(1)
    paths = [Path(m) for m in args.models] or [find_model(args.models_dir, n) for n in MODELS]
    with tempfile.TemporaryDirectory() as scratch:
        out_dir = args.keep or Path(scratch)
        out_dir.mkdir(parents=True, exist_ok=True)
        for path in paths:
            if path is None or not path.exists():
                print(json.dumps({"model": str(path), "skipped": "not found"}))
                continue
            runs = [lineart.run(path, out_dir / f"{path.stem}_lineart.png") for _ in range(max(args.runs, 1))]
            print(
                json.dumps(
                    {
                        "renderer": f"{lineart.version} Line Art",
                        "model": path.name,
                        "width": args.size[0],
                        "height": args.size[1],
                        "levels": [0, lineart.levels],
                        **LineArt.summary(runs),
                    }
                ),
                flush=True,
            )


if __name__ == "__main__":
    main()
