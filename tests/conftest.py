"""Test session set-up: MuJoCo renders headless (``MUJOCO_GL=egl``) where no display is set.

MuJoCo reads ``MUJOCO_GL`` when it is first imported, so this runs before the test modules
import it. Where EGL is missing too, the rendering tests skip with the reason.
"""

from __future__ import annotations

import os

if "MUJOCO_GL" not in os.environ and not (os.environ.get("DISPLAY")
                                          or os.environ.get("WAYLAND_DISPLAY")):
    os.environ["MUJOCO_GL"] = "egl"
