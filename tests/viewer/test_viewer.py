"""``blueprint view`` in a real window under Xvfb, driven by xdotool.

The viewer runs as a subprocess with ``BLUEPRINT_VIEWER_DUMP`` set, so it writes every frame it
presents (PNG) and its state (``frames.jsonl``); the checks read those. Needs the Debian packages
``xvfb`` and ``xdotool`` (skipped where they are missing).
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import trimesh
from helpers import ROOT
from PIL import Image
from scan_helpers import noisy_sphere

import blueprint
from blueprint.cli import STYLE_NAMES
from blueprint.scene.camera import VIEWS
from blueprint.viewer.overlay import BACKDROP, LINE_HEIGHT
from blueprint.viewer.state import ViewState

GEARBOX = ROOT / "src" / "blueprint" / "data" / "gearbox.glb"
ENTRY = "from blueprint.cli.view import main; main()"
SIZE = (320, 240)
HIGHLIGHT = np.round(np.array(blueprint.STYLES["paper"].highlight[:3]) * 255)
TIMEOUT = 30.0


def _env(**changes) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    env.update({k: v for k, v in changes.items() if v is not None})
    return env


@pytest.fixture(scope="module")
def xdisplay():
    """A fresh Xvfb on a display number it picks itself (-displayfd)."""
    missing = [tool for tool in ("Xvfb", "xdotool") if shutil.which(tool) is None]
    if missing:
        pytest.skip(f"{' and '.join(missing)} not installed (Debian packages xvfb and xdotool)")
    read, write = os.pipe()
    server = subprocess.Popen(
        ["Xvfb", "-displayfd", str(write), "-screen", "0", "800x600x24", "-nolisten", "tcp"],
        pass_fds=(write,),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    os.close(write)
    try:
        with os.fdopen(read) as fh:
            number = fh.readline().strip()
        if not number:
            pytest.skip("Xvfb did not start")
        yield f":{number}"
    finally:
        server.terminate()
        server.wait(10)


class Session:
    """A running viewer: its frames, and xdotool to type and click into its window."""

    def __init__(self, display: str, folder: Path, *args: str) -> None:
        self.display = display
        self.dump = folder / "dump"
        self.proc = subprocess.Popen(
            [sys.executable, "-c", ENTRY, *args],
            env=_env(DISPLAY=display, BLUEPRINT_VIEWER_DUMP=str(self.dump)),
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.seen = 0
        first = self.wait_for(lambda r: True)
        self.window = self._xdotool("search", "--name", "^blueprint view").split()[0]
        self._xdotool("mousemove", "--window", self.window, "1", str(SIZE[1] - 1))
        self.first = first

    def _xdotool(self, *args: str) -> str:
        run = subprocess.run(
            ["xdotool", *args], env=_env(DISPLAY=self.display), capture_output=True, text=True, timeout=10
        )
        assert run.returncode == 0, f"xdotool {' '.join(args)}: {run.stderr}"
        return run.stdout

    def records(self) -> list[dict]:
        path = self.dump / "frames.jsonl"
        if not path.exists():
            return []
        return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]

    def wait_for(self, predicate, timeout: float = TIMEOUT) -> dict:
        """The first frame after the ones already seen that satisfies ``predicate``."""
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            for record in self.records()[self.seen :]:
                self.seen = record["n"]
                if predicate(record):
                    return record
            if self.proc.poll() is not None:
                raise AssertionError(f"viewer exited with {self.proc.returncode}: {self.proc.stderr.read()}")
            time.sleep(0.05)
        self.proc.kill()
        _, err = self.proc.communicate()
        raise AssertionError(f"no such frame within {timeout} s; last: {self.records()[-1:]}; stderr: {err}")

    def settle(self, quiet: float = 0.8) -> dict:
        """Wait until no frame has come for ``quiet`` seconds; the last frame."""
        count = len(self.records())
        last_change = time.monotonic()
        while time.monotonic() - last_change < quiet:
            time.sleep(0.05)
            now = len(self.records())
            if now != count:
                count, last_change = now, time.monotonic()
        self.seen = count
        return self.records()[-1]

    def key(self, name: str) -> None:
        self._xdotool("key", name)

    def click(self, x: int, y: int) -> None:
        self._xdotool("mousemove", "--window", self.window, str(x), str(y), "click", "1")

    def drag(self, points: list[tuple[int, int]]) -> None:
        x, y = points[0]
        args = ["mousemove", "--window", self.window, str(x), str(y), "mousedown", "1"]
        for x, y in points[1:]:
            args += ["mousemove", "--window", self.window, str(x), str(y)]
        self._xdotool(*args, "mouseup", "1")

    def image(self, record: dict) -> np.ndarray:
        """The frame's pixels below the heads-up band."""
        picture = np.asarray(Image.open(self.dump / record["file"]))
        return picture[record["hud_height"] :]

    def quit(self) -> None:
        """Esc: the viewer exits with code 0."""
        self.key("Escape")
        assert self.proc.wait(15) == 0

    def __enter__(self) -> Session:
        return self

    def __exit__(self, *exc) -> None:
        if self.proc.poll() is None:
            self.proc.kill()
            self.proc.wait()


def _rested_camera(model, record: dict):
    """The camera of a frame drawn once the view rests, orbited from the iso view to its
    azimuth and elevation (the paper style's frames, which the tests compare)."""
    state = ViewState.start(STYLE_NAMES, "paper", azimuth=record["azimuth"], elevation=record["elevation"])
    state.base_azimuth, state.base_elevation = VIEWS["iso"]
    return state.camera(model, SIZE[0] / SIZE[1])


def _paper_pixels(image: np.ndarray, paper) -> int:
    return int(np.count_nonzero((image != np.asarray(paper, np.uint8)).any(axis=-1)))


def _highlight_pixels(image: np.ndarray) -> int:
    return int(np.count_nonzero((np.abs(image.astype(int) - HIGHLIGHT) < 40).all(axis=-1)))


def _stack(parts: np.ndarray, x: int, y: int) -> list[int]:
    """Distinct parts at a pixel, front first, from (L, H, W) part IDs."""
    found: list[int] = []
    for part in parts[:, y, x].tolist():
        if part >= 0 and part not in found:
            found.append(part)
    return found


def _pick_spot(parts: np.ndarray, hud: int) -> tuple[list[int], tuple[int, int]]:
    """A pixel well inside a part of layer 0 (below the heads-up band) with another part behind
    it, and the parts there front first."""
    from scipy.ndimage import binary_erosion

    front = parts[0]
    ids, counts = np.unique(front[front >= 0], return_counts=True)
    for index in ids[np.argsort(-counts)]:
        inner = binary_erosion(front == index, iterations=4)
        inner[: hud + 4] = False
        for y, x in zip(*np.nonzero(inner), strict=True):
            stack = _stack(parts, int(x), int(y))
            if len(stack) >= 2:
                return stack, (int(x), int(y))
    raise AssertionError("no part large enough to click with another behind it")


def test_keys_mouse_and_escape_under_xvfb(xdisplay, tmp_path, renderer):
    model_path = tmp_path / "gearbox.glb"
    shutil.copy(GEARBOX, model_path)
    model = blueprint.load_model(model_path)
    size_args = ["--size", str(SIZE[0]), str(SIZE[1]), "--supersample", "1", "--max-layers", "1"]
    with Session(xdisplay, tmp_path, str(model_path), *size_args) as viewer:
        first = viewer.first
        assert first["quality"] == "full" and first["style"] == "blueprint" and first["layers"] == 1
        assert "fps" in first["hud"][0] and "2,144 triangles" in first["hud"][0]
        assert first["renderer"] in first["hud"][0] and "blueprint" in first["hud"][0]
        hud = first["hud_height"]
        one_layer = viewer.image(first)
        # the same renderer as `blueprint render`: identical pixels below the heads-up band
        expected = blueprint.render(model, size=SIZE, max_layers=1, supersample=1, renderer=renderer)
        np.testing.assert_array_equal(one_layer, expected[hud:, :, :3])
        blue = (0x12, 0x45, 0x7A)
        assert tuple(one_layer[-1, 0]) == blue

        # D: one layer more -> hidden lines appear; Shift+D: back to exactly the first picture
        viewer.key("d")
        two = viewer.wait_for(lambda r: r["max_layers"] == 2)
        assert two["layers"] == 2 and two["quality"] == "full"
        assert _paper_pixels(viewer.image(two), blue) > _paper_pixels(one_layer, blue) + 100
        viewer.key("shift+d")
        back = viewer.wait_for(lambda r: r["max_layers"] == 1)
        np.testing.assert_array_equal(viewer.image(back), one_layer)
        viewer.key("a")
        every = viewer.wait_for(lambda r: r["max_layers"] is None)
        assert every["layers"] > 2

        # S: the next style, white paper
        viewer.key("s")
        paper = viewer.wait_for(lambda r: r["style"] == "paper")
        assert tuple(viewer.image(paper)[-1, 0]) == (255, 255, 255)
        # and round: no paper (the backdrop shows through), wire-frame, blueprint, paper again
        viewer.key("s")
        clear = viewer.wait_for(lambda r: r["style"] == "transparent")
        assert tuple(viewer.image(clear)[-1, 0]) == BACKDROP
        for style in ("wireframe", "blueprint", "paper"):
            viewer.key("s")
            viewer.wait_for(lambda r, style=style: r["style"] == style)

        # 2: the front view, exactly as `blueprint render --view front --style paper`
        viewer.key("2")
        front = viewer.wait_for(lambda r: r["view"] == "front")
        layers = front["max_layers"]
        expected = blueprint.render(
            model, size=SIZE, view="front", style="paper", max_layers=layers, supersample=1, renderer=renderer
        )
        np.testing.assert_array_equal(viewer.image(front), expected[hud:, :, :3])
        assert (front["azimuth"], front["elevation"]) == VIEWS["front"]

        # a click on a part: its name in the heads-up lines, its edges in the highlight colour
        peeled = blueprint.peel(model, size=SIZE, view="front", max_layers=12, renderer=renderer)
        stack, (x, y) = _pick_spot(peeled.part, hud)
        name = model.part_names[stack[0]]
        assert _highlight_pixels(viewer.image(front)) == 0
        viewer.click(x, y)
        picked = viewer.wait_for(lambda r: r["part"] is not None)
        assert picked["part"] == name and picked["part_index"] == stack[0]
        assert any(name in line for line in picked["hud"][1:])
        assert _highlight_pixels(viewer.image(picked)) > 50
        # the same spot again: the part behind it
        viewer.click(x, y)
        behind = viewer.wait_for(lambda r: r["part_index"] != stack[0])
        assert behind["part_index"] == stack[1] and model.part_names[stack[1]] in behind["hud"][1]
        # M: depth masking on the picked part
        viewer.key("m")
        masked = viewer.wait_for(lambda r: r["mask"])
        assert masked["revealed"] is not None and "depth mask" in masked["hud"][1]
        viewer.key("m")
        viewer.wait_for(lambda r: not r["mask"])

        # P twice: two screenshots beside the model, never overwritten
        viewer.key("p")
        viewer.key("p")
        shots = [tmp_path / "gearbox-1.png", tmp_path / "gearbox-2.png"]
        end = time.monotonic() + TIMEOUT
        while not all(p.exists() for p in shots) and time.monotonic() < end:
            time.sleep(0.05)
        for shot in shots:
            assert Image.open(shot).size == SIZE

        # a drag orbits; a still frame at full quality follows, then nothing is redrawn
        viewer.drag([(160, 150), (180, 150), (210, 160), (240, 170)])
        moved = viewer.wait_for(lambda r: r["azimuth"] != front["azimuth"])
        assert moved["view"] == "front" and "orbited" in moved["hud"][0]
        still = viewer.settle()
        assert still["quality"] == "full" and still["azimuth"] != front["azimuth"]
        time.sleep(0.7)
        assert len(viewer.records()) == still["n"], "frames were drawn with nothing changed"

        # wheel: zoom in; O: orthographic; H: the help box
        viewer._xdotool("mousemove", "--window", viewer.window, "160", "120", "click", "4")
        assert viewer.wait_for(lambda r: r["zoom"] < 1.0)["zoom"] == pytest.approx(0.9)
        viewer.key("o")
        viewer.wait_for(lambda r: r["ortho"])
        plain = viewer.settle()
        viewer.key("h")
        helped = viewer.wait_for(lambda r: r["help"])
        assert helped["ortho"] and (viewer.image(helped) != viewer.image(plain)).any()

        # T: the turntable turns in moving frames until T again; then one full frame
        viewer.key("t")
        spin = [viewer.wait_for(lambda r: r["turntable"]) for _ in range(3)]
        assert len({r["azimuth"] for r in spin}) == 3 and spin[-1]["quality"] == "moving"
        assert f"| moving: {spin[-1]['step']} |" in spin[-1]["hud"][0]
        viewer.key("t")
        stopped = viewer.wait_for(lambda r: not r["turntable"] and r["quality"] == "full")
        assert "moving" not in stopped["hud"][0]

        # Esc: exit code 0
        viewer.quit()


def test_moving_frames_walk_down_the_ladder_then_the_full_drawing_follows(xdisplay, tmp_path, renderer):
    """Asked for 1000 fps, every frame is far too slow: the turntable's frames go down the
    ladder at once (each step unmeasured, taken at half the cost of the one above it) to its
    last, and stay there; once the turntable stops, the full drawing of that view follows, the
    pixels of ``render``."""
    model_path = tmp_path / "gearbox.glb"
    shutil.copy(GEARBOX, model_path)
    model = blueprint.load_model(model_path)
    args = ["--size", str(SIZE[0]), str(SIZE[1]), "--moving-fps", "1000", "--style", "paper"]
    with Session(xdisplay, tmp_path, str(model_path), *args) as viewer:
        assert viewer.first["quality"] == "full" and viewer.first["render_size"] == list(SIZE)
        viewer.key("t")
        spin = [viewer.wait_for(lambda r: r["turntable"]) for _ in range(8)]
        # the first moving frame is the full drawing: the still frame before it uploaded the
        # model, which is no measure of a frame
        steps = [("full", 1.0, 2)] + [("1/4 size, 1 layer", 0.25, 1)] * 7
        assert [(r["step"], r["scale"], r["supersample"]) for r in spin] == steps
        for record in spin:
            assert record["quality"] == "moving"
            assert record["render_size"] == [
                round(SIZE[0] * record["scale"]),
                round(SIZE[1] * record["scale"]),
            ]
            assert f"| moving: {record['step']} |" in record["hud"][0]
        assert [r["layers"] for r in spin[1:]] == [1] * 7
        # a smaller drawing is scaled up to the whole window
        assert viewer.image(spin[-1]).shape[:2] == (SIZE[1] - spin[-1]["hud_height"], SIZE[0])
        viewer.key("t")
        still = viewer.wait_for(lambda r: r["quality"] == "full")
        assert not still["turntable"] and still["render_size"] == list(SIZE) and still["supersample"] == 2
        assert "moving" not in still["hud"][0]
        camera = _rested_camera(model, still)
        expected = blueprint.render(
            model, camera=camera, size=SIZE, style="paper", max_layers=5, renderer=renderer
        )
        hud = still["hud_height"]
        np.testing.assert_array_equal(viewer.image(still), expected[hud:, :, :3])
        # the frame after the still one: none, nothing changed
        assert viewer.settle()["n"] == still["n"]
        viewer.quit()


PRESENT_BOTH_WAYS = """
import sys
import numpy as np
from blueprint.viewer.present import Presenter
from blueprint.viewer.window import Window

window = Window((320, 240), "present")
size = window.size()
picture = np.random.default_rng(7).integers(0, 256, (size[1], size[0], 4), dtype=np.uint8)
picture[..., 3] = 255
presenter = Presenter(window)
shown = {}
for opaque in (True, False):
    for show_help in (False, True):
        presenter.show(picture, opaque)
        presenter.draw(size, ["a heads-up line", "and a second one"], show_help)
        shown[f"{'copied' if opaque else 'drawn'}_{'help' if show_help else 'plain'}"] = presenter.read(size)
window.close()
np.savez(sys.argv[1], picture=picture, **shown)
"""


def test_an_opaque_drawing_is_copied_to_the_window_as_the_pass_draws_it(xdisplay, tmp_path):
    out = tmp_path / "shown.npz"
    run = subprocess.run(
        [sys.executable, "-c", PRESENT_BOTH_WAYS, str(out)],
        env=_env(DISPLAY=xdisplay),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 0, run.stderr
    shown = np.load(out)
    picture = shown["picture"][..., :3]
    band = 2 * LINE_HEIGHT
    for way in ("plain", "help"):
        copied, drawn = shown[f"copied_{way}"].astype(int), shown[f"drawn_{way}"].astype(int)
        # the overlay blended by the fixed function, not by the pass's mix: a level apart at most
        assert np.abs(copied - drawn).max() <= 1
        assert (copied[:band] != picture[:band]).any(), "no heads-up lines over the copy"
    np.testing.assert_array_equal(shown["copied_plain"][band:], picture[band:])
    np.testing.assert_array_equal(shown["drawn_plain"][band:], picture[band:])
    assert (shown["copied_help"][band:] != picture[band:]).any(), "no help box over the copy"


@pytest.mark.parametrize("display", [None, ":97531"])
def test_no_display_says_use_render_and_exits_2(display, tmp_path):
    shutil.copy(GEARBOX, tmp_path / "gearbox.glb")
    run = subprocess.run(
        [sys.executable, "-c", ENTRY, str(tmp_path / "gearbox.glb")],
        env=_env(DISPLAY=display),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert run.returncode == 2
    lines = run.stderr.strip().splitlines()
    assert len(lines) == 1 and "blueprint render" in lines[0], run.stderr
    assert run.stdout == ""


@pytest.mark.parametrize("flag", ["--smooth-contours", None])
def test_still_drawing_has_the_contour_lines(xdisplay, tmp_path, renderer, flag):
    """``--smooth-contours``: the drawing shown once the view rests is ``render``'s with them,
    pixel for pixel (the moving frames leave them out). Without the flag none, though a
    picture of this scan would draw them: the pass would hold the window each time it rests."""
    sphere = noisy_sphere(0.006)
    model_path = tmp_path / "scan.stl"
    trimesh.Trimesh(sphere.positions, sphere.faces, process=False).export(model_path)
    model = blueprint.load_model(model_path)
    args = ["--size", str(SIZE[0]), str(SIZE[1]), "--style", "paper", *([flag] if flag else [])]
    with Session(xdisplay, tmp_path, str(model_path), *args) as viewer:
        still = viewer.first
        assert still["quality"] == "full"
        camera = _rested_camera(model, still)
        options = dict(camera=camera, size=SIZE, style="paper", max_layers=5, renderer=renderer)
        lined = blueprint.render(model, smooth_contours=True, **options)
        plain = blueprint.render(model, smooth_contours=False, **options)
        assert not np.array_equal(lined, plain)
        assert np.array_equal(blueprint.render(model, **options), lined)
        hud = still["hud_height"]
        expected = lined if flag else plain
        np.testing.assert_array_equal(viewer.image(still), expected[hud:, :, :3])
        viewer.quit()
