"""Deforming, splitting meshes: the animation itself, ID silhouettes per frame, the command."""

import subprocess
import sys

import numpy as np
import pytest
import trimesh
from click.testing import CliRunner

from blueprint import Camera, InputError, Model
from blueprint.cli.silhouettes import silhouettes
from blueprint.gpu_silhouettes import GpuSilhouettes, animate_silhouettes
from blueprint.pipeline.media import write_video
from blueprint.scene.camera import fit_camera
from blueprint.silhouette import build_adjacency, classify_edges, draw_segments
from blueprint.silhouette.deform import Animation

SIZE = (192, 144)


def column() -> Model:
    """A closed, smooth column of oval section (so twisting shows), Y up, 320 faces."""
    sphere = trimesh.creation.icosphere(subdivisions=2)
    return Model.from_arrays(sphere.vertices * [1.5, 2.5, 1.0], sphere.faces, up="y")


# -- the animation (GPU-free) ---------------------------------------------------------------------
@pytest.mark.parametrize("kind", ["twist", "wave"])
def test_first_frame_is_the_rest_pose(kind):
    model = column()
    pose = Animation(model, kind, frames=5).pose(0)
    assert pose.topology == 0
    np.testing.assert_array_equal(pose.faces, model.faces)
    if kind == "twist":
        np.testing.assert_allclose(pose.positions, model.positions, atol=1e-6)
    else:  # the wave starts bent already, up and down only
        np.testing.assert_allclose(
            np.delete(pose.positions, 1, axis=1), np.delete(model.positions, 1, axis=1)
        )


def test_twist_keeps_distances_to_the_axis_and_heights():
    model = column()
    pose = Animation(model, "twist", frames=8, split_at=1.0).pose(2)
    radius = np.hypot(model.positions[:, 0], model.positions[:, 2])
    np.testing.assert_allclose(np.hypot(pose.positions[:, 0], pose.positions[:, 2]), radius, atol=1e-5)
    np.testing.assert_allclose(pose.positions[:, 1], model.positions[:, 1], atol=1e-6)
    assert np.abs(pose.positions - model.positions).max() > 0.5


def test_split_changes_topology_not_the_triangle_count():
    model = column()
    anim = Animation(model, "twist", frames=6, split_at=0.5)
    before, after = anim.pose(2), anim.pose(3)
    assert (before.topology, after.topology) == (0, 1)
    assert len(after.faces) == len(model.faces)
    assert len(after.positions) > len(model.positions)
    adjacency = build_adjacency(after.positions, after.faces)
    assert len(np.unique(adjacency.component)) >= 2
    # every vertex of the split pose is where the unsplit animation puts it, moved half the
    # gap along the cut axis, away from the other piece
    last = anim.pose(5)
    whole = Animation(model, "twist", frames=6, split_at=1.0).pose(5).positions[anim.split_source]
    shift = last.positions - whole
    gap = 0.35 * anim.extent
    np.testing.assert_allclose(np.abs(shift[:, anim.cut_axis]), gap / 2, rtol=1e-5)
    np.testing.assert_allclose(np.delete(shift, anim.cut_axis, axis=1), 0.0, atol=1e-6)
    low, high = (last.positions[anim.piece_sign == side][:, anim.cut_axis] for side in (-1, 1))
    assert high.min() - low.max() > 0.1 * anim.extent


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"kind": "melt"}, "unknown animation"),
        ({"frames": 0}, "frames must be"),
        ({"split_at": 2}, "split-at"),
    ],
)
def test_bad_animation_arguments(kwargs, message):
    with pytest.raises(InputError, match=message):
        Animation(column(), **kwargs)


# -- silhouettes per frame ------------------------------------------------------------------------
def cpu_pixels(pose, camera, size) -> np.ndarray:
    edges = classify_edges(
        build_adjacency(pose.positions, pose.faces), camera.view_matrix(), camera.projection_matrix(), *size
    )
    return draw_segments(edges.segments2d[edges.kind != 3], *size) > 0.5


def test_deforming_sequence_needs_only_new_positions(renderer):
    """Each frame the soup gets new corner positions and nothing else, through the split; its
    silhouettes equal those of the same pose uploaded from scratch, and every visible GPU line
    lies on a line of the CPU method, which rebuilds its adjacency every frame."""
    from scipy import ndimage

    model = column()
    anim = Animation(model, "twist", frames=4, split_at=0.6)
    lo, hi = anim.bounds()
    camera = Camera.fit(np.array([lo, hi]), "front", aspect=SIZE[0] / SIZE[1])
    with GpuSilhouettes(renderer) as sil:
        soup = sil.soup(anim.pose(0).corners())
        try:
            for i in range(anim.frames):
                pose = anim.pose(i)
                soup.update(pose.corners())
                edges = sil.render(soup, camera, SIZE)[0]
                fresh = Model.from_arrays(pose.positions, pose.faces)
                np.testing.assert_array_equal(edges, sil.render(fresh, camera, SIZE)[0])
                sil.forget(fresh)
                gpu = edges > 0
                near_cpu = ndimage.binary_dilation(cpu_pixels(pose, camera, SIZE), np.ones((3, 3), bool))
                assert near_cpu[gpu].mean() >= 0.95
                outlines = ndimage.label(gpu, np.ones((3, 3)))[1]
                if pose.topology == 0:
                    assert outlines == 1
            # at the end the two pieces are apart: two outlines
            assert outlines == 2
        finally:
            soup.release()


def test_id_lists_follow_the_split_when_told(renderer):
    model = column()
    # the split at 0.4 falls between frames: where the pieces still touch (gap 0), positions say
    # "one surface" and the lists "two pieces", and both are right
    anim = Animation(model, "wave", frames=3, split_at=0.4)
    camera = fit_camera(model, SIZE, "front")
    with GpuSilhouettes(renderer) as sil:
        first = anim.pose(0)
        soup = sil.soup(first.corners(), topology=(first.faces, len(first.positions)))
        try:
            for i in range(anim.frames):
                pose = anim.pose(i)
                soup.update(pose.corners(), (pose.faces, len(pose.positions)))
                vertex = sil.render(soup, camera, SIZE, layers=2, method="vertex")
                np.testing.assert_array_equal(
                    sil.render(soup, camera, SIZE, layers=2, method="idlist"), vertex
                )
        finally:
            soup.release()


@pytest.mark.parametrize("method", ["gpu-edges", "gpu-idlist"])
def test_animating_an_unwelded_soup_draws_what_the_welded_model_does(renderer, method):
    """An STL is a soup: every face has its own three vertices. The animation welds it, so the
    methods that take their adjacency from a pose's faces see a surface, not separate triangles
    whose every edge would be a border, before the split and after it."""
    model = column()
    corners = model.positions[model.faces].reshape(-1, 3)
    soup = Model.from_arrays(corners, np.arange(len(corners)).reshape(-1, 3), up="y")
    assert len(np.unique(Animation(soup, "twist", frames=4).pose(0).faces)) == len(model.positions)

    def pictures(m: Model) -> list[np.ndarray]:
        frames = animate_silhouettes(
            m, animate="twist", frames=4, split_at=0.6, method=method, size=SIZE, renderer=renderer
        )
        return [image for image, _ in frames]

    for of_soup, of_model in zip(pictures(soup), pictures(model), strict=True):
        np.testing.assert_array_equal(of_soup, of_model)


@pytest.mark.parametrize("method", ["gpu-edges", "gpu-vertex", "gpu-idlist", "cpu"])
def test_animation_api_yields_every_frame(renderer, method):
    frames = list(
        animate_silhouettes(
            column(), animate="twist", frames=3, method=method, size=(64, 48), renderer=renderer
        )
    )
    assert len(frames) == 3
    assert all(image.shape == (48, 64, 3) and image.dtype == np.uint8 for image, _ in frames)
    assert all(ms > 0 for _, ms in frames)


# -- the command ----------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def column_file(tmp_path_factory):
    path = tmp_path_factory.mktemp("models") / "column.stl"
    import trimesh

    model = column()
    trimesh.Trimesh(model.positions, model.faces, process=False).export(path)
    return path


def run_command(*args) -> subprocess.CompletedProcess:
    """The command in its own process: it draws with the default renderer, a second GL context
    that must not become current in the test process (the session renderer's)."""
    return subprocess.run(
        [sys.executable, "-c", "from blueprint.cli.silhouettes import main; main()", *map(str, args)],
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_command_writes_a_video(column_file, tmp_path):
    out = tmp_path / "twist.mp4"
    done = run_command(column_file, "-o", out, "--animate", "twist", "--frames", "4", "--size", 65, 48)
    assert done.returncode == 0, done.stderr
    assert "4 frames of 65x48" in done.stdout
    frames = _read_ffmpeg(out)
    assert len(frames) == 4 and frames.shape[1:3] == (48, 66)
    assert not list(tmp_path.glob(".*.tmp"))


def _read_ffmpeg(path) -> np.ndarray:
    import imageio.v2 as iio

    with iio.get_reader(path, format="FFMPEG") as reader:
        # a comprehension, not list(): the reader's length is infinite until it has read all
        return np.stack([frame for frame in reader])


def test_command_writes_a_still(column_file, tmp_path):
    out = tmp_path / "still.png"
    done = run_command(column_file, "-o", out, "--method", "gpu-idlist", "--layers", 2, "--size", 64, 48)
    assert done.returncode == 0, done.stderr
    from PIL import Image

    assert Image.open(out).size == (64, 48)


def test_command_draws_visible_and_hidden_edges_by_default(renderer, tmp_path):
    """With no --method and no --layers the command draws gpu-edges in 2 layers: the picture of
    ``render_silhouettes`` with those, which has the outline of the box hidden behind the other
    that the visible layer alone lacks."""
    import trimesh
    from PIL import Image

    from blueprint import load_model
    from blueprint.examples import box
    from blueprint.gpu_silhouettes import render_silhouettes

    (p0, f0), (p1, f1) = box((-1, -1, -1), (1, 1, 1)), box((-0.5, -0.5, -3.0), (0.5, 0.5, -2.0))
    path = tmp_path / "boxes.stl"
    trimesh.Trimesh(np.concatenate([p0, p1]), np.concatenate([f0, f1 + len(p0)]), process=False).export(path)
    out = tmp_path / "default.png"
    # Y up, told: the boxes lie one behind the other along Z, seen from the front
    done = run_command(path, "-o", out, "--size", 96, 72, "--view", "front", "--up", "y")
    assert done.returncode == 0, done.stderr
    assert ", gpu-edges, " in done.stdout
    model = load_model(path, up="y")

    def picture(layers: int) -> np.ndarray:
        return render_silhouettes(
            model, method="gpu-edges", layers=layers, size=(96, 72), view="front", renderer=renderer
        )

    np.testing.assert_array_equal(np.asarray(Image.open(out).convert("RGB")), picture(2))
    assert (picture(2) != picture(1)).any(axis=2).sum() > 50


def test_command_error_exit_code(column_file, tmp_path):
    done = run_command(column_file, "-o", tmp_path / "x.png", "--method", "zbuffer")
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "zbuffer" in done.stderr


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["-o", "x.mp4"], "needs --animate"),
        (["-o", "x.png", "--animate", "wave"], "must end in .mp4"),
        (["-o", "x.mp4", "--animate", "wave", "--frames", "0"], "frames must be at least 1"),
        (["-o", "x.png", "--layers", "0"], "layers must be"),
        (["-o", "x.png", "--view", "plan"], "unknown view"),
        (["-o", "nowhere/x.png"], "does not exist"),
    ],
)
def test_command_bad_input_is_one_line(column_file, tmp_path, args, message):
    """Checked before any GL work (so in this process)."""
    args = [a if not a.startswith("x.") else str(tmp_path / a) for a in args]
    result = CliRunner().invoke(silhouettes, [str(column_file), *args], standalone_mode=False)
    assert isinstance(result.exception, InputError)
    assert message in str(result.exception) and "\n" not in str(result.exception)


def test_write_video_pads_odd_sizes(tmp_path):
    frames = (np.full((5, 7, 3), 40 * k, np.uint8) for k in range(3))
    assert write_video(tmp_path / "odd.mp4", frames, fps=10) == tmp_path / "odd.mp4"
    assert _read_ffmpeg(tmp_path / "odd.mp4").shape[1:3] == (6, 8)
