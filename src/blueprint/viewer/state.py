"""What the viewer shows, without a window or a GPU: camera navigation, layers, style, selection.

Every key and mouse gesture of the viewer is a method here, so the rules are testable on their
own; ``ViewState.camera`` turns the state into a ``Camera`` for the renderer.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from blueprint.errors import InputError
from blueprint.render.stop import HARD_MAX_LAYERS
from blueprint.scene.camera import VIEWS, Camera, fit_camera
from blueprint.scene.model import Model
from blueprint.viewer.pacing import MOVING_FPS

# Keys 1-7 in this order.
VIEW_KEYS: tuple[str, ...] = ("iso", "front", "back", "left", "right", "top", "bottom")
# Degrees of orbit per pixel of mouse drag; degrees per second of the turntable.
ORBIT_DEG_PER_PX = 0.4
TURNTABLE_DEG_PER_S = 30.0
ZOOM_LIMITS = (0.02, 50.0)
# Elevation stays off the poles while orbiting, so the up vector never flips.
MAX_ORBIT_ELEVATION = 89.0


@dataclass
class Options:
    """Rendering options passed through to ``Renderer.render`` (see there), and how frames are
    drawn while the view moves: ``moving_fps``, the frame rate kept then (see ``pacing``), and
    ``interactive_scale``, 0 for the ladder of qualities, else the one quality of those frames:
    that fraction of the window at supersample 1. ``smooth_contours`` draws the full drawing
    once the view rests with them (a CPU pass and a capture a frame: not the moving ones)."""

    grid: float | None = None
    min_fraction: float = 0.0
    crease_angle: float = 30.0
    line_width: float = 1.0
    supersample: int = 2
    smooth_contours: bool = False
    interactive_scale: float = 0.0
    moving_fps: float = MOVING_FPS

    def __post_init__(self) -> None:
        scale, fps = self.interactive_scale, self.moving_fps
        if scale and not 0.05 <= scale <= 1.0:
            raise InputError(f"interactive-scale must be 0 (automatic) or in [0.05, 1], got {scale}")
        if not 0.1 <= fps <= 1000.0:
            raise InputError(f"moving-fps must be in [0.1, 1000] frames a second, got {fps}")


@dataclass
class ViewState:
    """The viewer's state.

    ``azimuth`` / ``elevation`` (degrees) orbit around the pivot of the last named view;
    ``zoom`` scales the distance (perspective) or view height (orthographic), < 1 is closer;
    ``pan`` moves the target across the view, in fractions of the fitted view height.
    ``max_layers`` is ``None`` for all layers. ``part`` is the selected part index or ``None``.
    """

    styles: tuple[str, ...]
    style: str = "blueprint"
    view: str = "iso"
    azimuth: float = 0.0
    elevation: float = 0.0
    fov: float = 30.0
    ortho: bool = False
    zoom: float = 1.0
    pan: tuple[float, float] = (0.0, 0.0)
    max_layers: int | None = 5
    turntable: bool = False
    help: bool = False
    part: int | None = None
    mask: bool = False
    # the angles the named view (or the command line) started from: at these, with no zoom and
    # no pan, the camera is exactly ``fit_camera``'s -- the same picture as ``blueprint render``
    base_azimuth: float = 0.0
    base_elevation: float = 0.0
    _fits: dict = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def start(
        cls,
        styles: tuple[str, ...],
        style: str = "blueprint",
        view: str = "iso",
        azimuth: float | None = None,
        elevation: float | None = None,
        fov: float = 30.0,
        ortho: bool = False,
        max_layers: int | None = 5,
    ) -> ViewState:
        """The state a viewer opens with (named view, optional angle overrides)."""
        if view not in VIEWS:
            raise InputError(f"unknown view {view!r} (choose {', '.join(VIEWS)})")
        if style not in styles:
            raise InputError(f"unknown style {style!r} (choose {', '.join(styles)})")
        if not 0 < fov < 180:
            raise InputError(f"field of view must be between 0 and 180 degrees, got {fov}")
        if max_layers is not None and not 1 <= max_layers <= HARD_MAX_LAYERS:
            raise InputError(f"max-layers must be between 1 and {HARD_MAX_LAYERS}, got {max_layers}")
        az, el = VIEWS[view]
        az = az if azimuth is None else float(azimuth)
        el = el if elevation is None else float(elevation)
        return cls(
            styles=tuple(styles),
            style=style,
            view=view,
            azimuth=az,
            elevation=el,
            fov=fov,
            ortho=ortho,
            max_layers=max_layers,
            base_azimuth=az,
            base_elevation=el,
        )

    # -- keys ----------------------------------------------------------------------------------
    def more_layers(self, drawn: int) -> None:
        """D: one layer more than the current limit (or than drawn, when showing all)."""
        current = drawn if self.max_layers is None else self.max_layers
        self.max_layers = min(HARD_MAX_LAYERS, max(1, current) + 1)

    def fewer_layers(self, drawn: int) -> None:
        """Shift+D: one layer fewer, at least one."""
        current = drawn if self.max_layers is None else self.max_layers
        self.max_layers = max(1, current - 1)

    def all_layers(self) -> None:
        """A: peel until nothing is left."""
        self.max_layers = None

    def next_style(self) -> None:
        """S: the next style, round the list."""
        i = self.styles.index(self.style) if self.style in self.styles else -1
        self.style = self.styles[(i + 1) % len(self.styles)]

    def set_view(self, name: str) -> None:
        """1-7: a named view, its orbit, zoom and pan reset."""
        if name not in VIEWS:
            raise InputError(f"unknown view {name!r} (choose {', '.join(VIEWS)})")
        self.view = name
        self.azimuth, self.elevation = VIEWS[name]
        self.base_azimuth, self.base_elevation = self.azimuth, self.elevation
        self.zoom = 1.0
        self.pan = (0.0, 0.0)

    def toggle_mask(self) -> None:
        """M: depth masking on / off (it applies while a part is selected)."""
        self.mask = not self.mask

    def toggle_ortho(self) -> None:
        """O: orthographic / perspective."""
        self.ortho = not self.ortho

    # -- mouse ---------------------------------------------------------------------------------
    def orbit(self, dx_px: float, dy_px: float) -> None:
        """Drag: the model turns with the mouse (right: azimuth falls; down: elevation rises)."""
        self.azimuth = (self.azimuth - dx_px * ORBIT_DEG_PER_PX + 180.0) % 360.0 - 180.0
        limit = MAX_ORBIT_ELEVATION
        self.elevation = max(-limit, min(limit, self.elevation + dy_px * ORBIT_DEG_PER_PX))

    def spin(self, seconds: float) -> None:
        """Turntable: turn the azimuth by the time passed."""
        self.azimuth = (self.azimuth + TURNTABLE_DEG_PER_S * seconds + 180.0) % 360.0 - 180.0

    def pan_by(self, dx_px: float, dy_px: float, height_px: int) -> None:
        """Drag with the right button (or Shift): the model follows the mouse."""
        scale = self.zoom / max(1, height_px)
        self.pan = (self.pan[0] - dx_px * scale, self.pan[1] + dy_px * scale)

    def zoom_by(self, steps: float) -> None:
        """Wheel: each step up comes 10% closer."""
        self.zoom = max(ZOOM_LIMITS[0], min(ZOOM_LIMITS[1], self.zoom * 0.9**steps))

    # -- camera --------------------------------------------------------------------------------
    def at_fit(self) -> bool:
        """True while the camera is exactly the fitted named view (nothing orbited, zoomed, panned)."""
        return (
            self.azimuth == self.base_azimuth
            and self.elevation == self.base_elevation
            and self.zoom == 1.0
            and self.pan == (0.0, 0.0)
        )

    def _fit(self, model: Model, aspect: float) -> Camera:
        key = (id(model), self.view, self.base_azimuth, self.base_elevation, self.fov, self.ortho, aspect)
        cam = self._fits.get(key)
        if cam is None:
            if len(self._fits) > 16:
                self._fits.clear()
            # a window's aspect as a size: the camera depends on the ratio alone
            cam = self._fits[key] = fit_camera(
                model,
                (aspect, 1.0),
                self.view,
                azimuth=self.base_azimuth,
                elevation=self.base_elevation,
                fov=self.fov,
                ortho=self.ortho,
            )
        return cam

    def camera(self, model: Model, aspect: float) -> Camera:
        """The camera for a window of ``aspect`` (width / height).

        At the named view it is the fitted camera itself; orbiting keeps that fit's target as the
        pivot and its distance (or view height), zoom scales them, pan moves the target across
        the view. Near and far planes enclose the model's bounding sphere.
        """
        base = self._fit(model, aspect)
        if self.at_fit():
            return base
        lo, hi = model.bounds
        center = (lo + hi) / 2
        radius = max(float(np.linalg.norm(hi - lo)) / 2, 1e-9)
        corners = np.stack(np.meshgrid(*zip(lo, hi, strict=True), indexing="ij"), -1).reshape(-1, 3)
        # a fit on the box corners gives the orientation for these angles (and handles the
        # model's up axis) at almost no cost
        turned = fit_camera(
            corners,
            (aspect, 1.0),
            "iso",
            azimuth=self.azimuth,
            elevation=self.elevation,
            fov=self.fov,
            ortho=self.ortho,
            up=model.up,
        )
        back = np.asarray(turned.eye) - np.asarray(turned.target)
        back /= np.linalg.norm(back)
        up = np.asarray(turned.up, np.float64)
        right = np.cross(up, back)
        pivot = np.asarray(base.target, np.float64)
        fit_distance = float(np.linalg.norm(np.asarray(base.eye) - pivot))
        unit = base.height if self.ortho else 2 * fit_distance * math.tan(math.radians(self.fov) / 2)
        target = pivot + (right * self.pan[0] + up * self.pan[1]) * unit
        if self.ortho:
            height = base.height * self.zoom
            distance = 2 * radius + float(np.linalg.norm(target - center))
        else:
            height = base.height
            distance = fit_distance * self.zoom
        eye = target + back * distance
        depth = float(np.dot(eye - center, back))
        pad = radius * 1.02
        near = max(depth - pad, radius * 1e-3)
        far = max(depth + pad, near * 2)
        return Camera(
            eye=tuple(float(v) for v in eye),
            target=tuple(float(v) for v in target),
            up=tuple(float(v) for v in up),
            near=near,
            far=far,
            aspect=aspect,
            fov=self.fov,
            ortho=self.ortho,
            height=float(height),
            name=self.view,
        )
