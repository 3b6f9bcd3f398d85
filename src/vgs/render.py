"""Pictures of the cell with MuJoCo's OpenGL renderer, from recorded states.

Rendering never runs inside the simulation's control loop: an episode records its states
(``Trace.qpos``, one copy of ``data.qpos`` per control tick, when a trace is asked for) and
:class:`SceneRenderer` draws them afterwards on its own model, the cell with its scenery
(:mod:`vgs.sim.scenery`: floor, named cameras) and a close-up of the hole
(:data:`HOLE_CAMERA`, on this model only). Training and evaluation never record states.

MuJoCo picks its OpenGL back end from the environment variable ``MUJOCO_GL`` when it is first
imported: ``egl`` (headless, a GPU or Mesa's EGL), ``osmesa`` (software) or ``glfw`` (a
display). Where the user chose none and no display is set (``DISPLAY``, ``WAYLAND_DISPLAY``),
vgs renders with EGL (:func:`headless_default`), also when MuJoCo was imported before vgs.
Without a usable context :class:`GLUnavailableError` says so in one line.
"""

from __future__ import annotations

import os
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

import mujoco
import numpy as np

from vgs.config import CellConfig
from vgs.errors import ConfigError, VGSError
from vgs.sim.cell import build_spec
from vgs.sim.scenery import PERSPECTIVE_CAMERA, PERSPECTIVE_POS, add_scenery, look_at_quat

VIDEO_SUFFIXES = (".mp4", ".gif")
# A close-up of the hole: from the perspective camera's side, HOLE_DISTANCE from the centre of
# the nominal hole's entrance, looking at it; the hole's displacement (within its radius) stays
# in view. Added to the drawing model only, never to the simulated cell.
HOLE_CAMERA = "hole"
HOLE_DISTANCE = 0.24  # [m]
HOLE_FOVY = 32.0  # [deg]: about 0.14 m across at the hole
VIDEO_CAMERAS = (PERSPECTIVE_CAMERA, HOLE_CAMERA)


class GLUnavailableError(VGSError):
    """No OpenGL context could be made for MuJoCo's renderer."""

    def __init__(self, detail: str) -> None:
        backend = os.environ.get("MUJOCO_GL", "")
        where = f"MUJOCO_GL={backend}" if backend else "MUJOCO_GL unset"
        super().__init__(
            f"rendering needs an OpenGL context and none could be made ({where}: {detail}); "
            "headless machines: set MUJOCO_GL=egl (or MUJOCO_GL=osmesa) before starting")


def headless_default() -> None:
    """Render with EGL where the user chose no back end (``MUJOCO_GL`` unset or empty) and no
    display is set: sets ``MUJOCO_GL=egl`` for what imports MuJoCo later (worker processes) and,
    when MuJoCo was imported already (it read the variable then and chose GLFW, which needs a
    display), gives its renderer EGL's context instead."""
    if os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") \
            or sys.platform != "linux" or os.environ.get("MUJOCO_GL", "").strip() not in ("",
                                                                                      "egl"):
        return
    os.environ["MUJOCO_GL"] = "egl"  # (also where vgs's command line set it after the import)
    try:
        from mujoco.rendering.classic import gl_context

        if getattr(gl_context, "_MUJOCO_GL", None) == "":  # imported without a choice
            from mujoco.egl import GLContext

            gl_context.GLContext = GLContext
    except (ImportError, OSError, AttributeError):  # no EGL: open_renderer says so
        pass


def open_renderer(model: mujoco.MjModel, width: int, height: int) -> mujoco.Renderer:
    """A :class:`mujoco.Renderer` for ``model`` (EGL where no display is set and no back end was
    chosen, :func:`headless_default`).

    Raises:
        GLUnavailableError: If no OpenGL context can be made.
    """
    headless_default()
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # GLFW's warnings repeat the failure
            return mujoco.Renderer(model, height=height, width=width)
    except ValueError:
        raise
    except Exception as exc:  # mujoco.FatalError, ImportError of a GL back end, ...
        message = " ".join(str(exc).split())
        raise GLUnavailableError(message[:160]) from exc


def require_gl() -> None:
    """Make and free a tiny OpenGL context (fail early, before a long simulation).

    Raises:
        GLUnavailableError: If no OpenGL context can be made.
    """
    model = mujoco.MjModel.from_xml_string("<mujoco><worldbody/></mujoco>")
    open_renderer(model, 16, 16).close()


def gl_available() -> tuple[bool, str]:
    """Whether MuJoCo's renderer can make a context here, and the reason when it cannot."""
    try:
        require_gl()
    except GLUnavailableError as exc:
        return False, str(exc)
    return True, ""


def render_model(cfg: CellConfig) -> mujoco.MjModel:
    """The cell of ``cfg`` with its scenery, compiled for drawing (never stepped), no shadows.

    Its ``qpos`` and mocap layout are the simulated cell's, so recorded states apply as they
    are.
    """
    spec = build_spec(cfg)
    add_scenery(spec, cfg)
    target = np.array([*cfg.hole.nominal_xy, cfg.hole.depth])
    direction = np.array(PERSPECTIVE_POS) - target
    pos = target + HOLE_DISTANCE * direction / np.linalg.norm(direction)
    spec.worldbody.add_camera(name=HOLE_CAMERA, pos=pos.tolist(),
                              quat=look_at_quat(pos, target).tolist(), fovy=HOLE_FOVY)
    spec.visual.global_.offwidth = 1920
    spec.visual.global_.offheight = 1080
    model = spec.compile()
    model.light_castshadow[:] = 0  # shadows cost 6x the drawing time with Mesa's EGL
    return model


class SceneRenderer:
    """Draws states of the cell of ``cfg`` from one named camera.

    Args:
        cfg: The cell's configuration (the peg of the episode to draw).
        width: Image width [px].
        height: Image height [px].
        camera: Name of a camera of the scenery (``perspective`` or ``overhead``) or
            :data:`HOLE_CAMERA`.

    Raises:
        ConfigError: ``camera`` if no camera has that name, ``video.size`` on a size outside
            16-1920 x 16-1080 px.
        GLUnavailableError: If no OpenGL context can be made.
    """

    def __init__(self, cfg: CellConfig, width: int = 480, height: int = 360,
                 camera: str = PERSPECTIVE_CAMERA) -> None:
        if not (16 <= width <= 1920 and 16 <= height <= 1080):
            raise ConfigError("video.size", f"{width} x {height} px is outside 16-1920 x 16-1080")
        self.model = render_model(cfg)
        if mujoco.mj_name2id(self.model, mujoco.mjtObj.mjOBJ_CAMERA, camera) < 0:
            raise ConfigError("camera", f"no camera named {camera!r}")
        self.camera = camera
        self.data = mujoco.MjData(self.model)
        self._renderer = open_renderer(self.model, width, height)

    def frame(self, qpos: np.ndarray, mocap_pos: np.ndarray | None = None) -> np.ndarray:
        """RGB image (height, width, 3) uint8 of the state ``qpos`` (and mocap positions)."""
        self.data.qpos[:] = qpos
        if mocap_pos is not None:
            self.data.mocap_pos[:] = np.asarray(mocap_pos).reshape(self.data.mocap_pos.shape)
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_comPos(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)  # camera and light poses
        self._renderer.update_scene(self.data, camera=self.camera)
        return self._renderer.render().copy()

    def close(self) -> None:
        """Free the OpenGL context."""
        self._renderer.close()


def annotate(image: np.ndarray, lines: Sequence[str]) -> np.ndarray:
    """``image`` with ``lines`` of text written on a dark band at its top left.

    Args:
        image: RGB uint8 (H, W, 3).
        lines: Text lines, top to bottom.

    Returns:
        A new RGB uint8 image.
    """
    from PIL import Image, ImageDraw, ImageFont

    img = Image.fromarray(image)
    draw = ImageDraw.Draw(img, "RGBA")
    size = max(10, image.shape[0] // 28)
    try:
        font = ImageFont.load_default(size=size)
    except (TypeError, ValueError, OSError):  # Pillow without FreeType: the bitmap font
        font = ImageFont.load_default()
    line_h = size + 4
    width = max((draw.textlength(line, font=font) for line in lines), default=0)
    draw.rectangle([0, 0, int(width) + 12, line_h * len(lines) + 8], fill=(0, 0, 0, 150))
    for i, line in enumerate(lines):
        draw.text((6, 4 + i * line_h), line, fill=(255, 255, 255, 255), font=font)
    return np.asarray(img)


def require_video_writer(path: str | Path) -> None:
    """Check before a long episode that ``path``'s format can be written.

    Raises:
        ConfigError: ``video`` on another suffix than .mp4/.gif, or an .mp4 without imageio
            and imageio-ffmpeg (``pip install 'vgs[video]'``).
    """
    suffix = Path(path).suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        raise ConfigError("video", f"{Path(path).name}: the file must end in .mp4 or .gif")
    if suffix == ".mp4":
        try:
            import imageio.v2  # noqa: F401
            import imageio_ffmpeg

            imageio_ffmpeg.get_ffmpeg_exe()
        except (ImportError, RuntimeError) as exc:
            raise ConfigError("video", f"MP4 needs imageio and imageio-ffmpeg ({exc}); pip "
                                       "install 'vgs[video]', or write a .gif") from None


def write_video(path: str | Path, frames: Sequence[np.ndarray], fps: float) -> Path:
    """Write ``frames`` as an MP4 (H.264, via imageio-ffmpeg) or an animated GIF (Pillow).

    Args:
        path: Output file; its suffix (``.mp4`` or ``.gif``) picks the format.
        frames: RGB uint8 images of one size.
        fps: Frames per second.

    Returns:
        The written file.

    Raises:
        ConfigError: ``video`` on another suffix, no frames or a missing MP4 writer.
    """
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in VIDEO_SUFFIXES:
        raise ConfigError("video", f"{path.name}: the file must end in .mp4 or .gif")
    if not frames:
        raise ConfigError("video", "no frames to write")
    if not fps > 0:
        raise ConfigError("video.fps", f"must be > 0, got {fps}")
    path.parent.mkdir(parents=True, exist_ok=True)
    if suffix == ".gif":
        from PIL import Image

        images = [Image.fromarray(f).quantize(colors=128, method=Image.Quantize.MEDIANCUT,
                                              dither=Image.Dither.NONE) for f in frames]
        images[0].save(path, save_all=True, append_images=images[1:], loop=0,
                       duration=max(20, int(round(1000.0 / fps))), optimize=True)
        return path
    try:
        import imageio.v2 as imageio
    except ImportError as exc:
        raise ConfigError("video", "MP4 needs imageio and imageio-ffmpeg "
                                   "(pip install 'vgs[video]'); .gif needs neither") from exc
    try:
        writer = imageio.get_writer(path, format="FFMPEG", fps=fps, codec="libx264",
                                    quality=7, macro_block_size=8, pixelformat="yuv420p")
    except (ImportError, RuntimeError, ValueError) as exc:
        raise ConfigError("video", f"no MP4 writer ({exc}); pip install 'vgs[video]', or "
                                   "write a .gif") from exc
    with writer:
        for f in frames:
            writer.append_data(f)
    return path


def frame_indices(times: np.ndarray, fps: float, speed: float) -> np.ndarray:
    """Indices of the ticks shown as video frames: one every ``speed / fps`` simulated seconds.

    Args:
        times: Simulated time of each recorded tick [s], increasing.
        fps: Video frames per second.
        speed: Simulated seconds per second of video.

    Returns:
        For each frame, the index of the last tick at or before its time.
    """
    if times.size == 0:
        return np.zeros(0, dtype=int)
    step = speed / fps
    frame_times = times[0] + step * np.arange(int((times[-1] - times[0]) / step) + 1)
    return np.clip(np.searchsorted(times, frame_times + 1e-9, side="right") - 1, 0,
                   times.size - 1)
