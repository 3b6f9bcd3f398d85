"""Wrist force/torque sensor model: MuJoCo's interaction wrench, noise, low-pass filter, tare.

MuJoCo's ``force``/``torque`` sensors at the site ``ft`` give the wrench the flange exerts on the
tool side, in the sensor frame. The external wrench acting on the tool (contacts) then follows
from Newton's law once the static tool load is tared: ``w_ext ~ -(w_raw - w_tare)``. Only the
tare at one nominal pose is removed; gravity and inertial loads that change with the wrist's
attitude stay in the signal, as on a real sensor.
"""

from __future__ import annotations

import math

import numpy as np

from vgs.config import FTSensorConfig

NOISE_BLOCK = 256


class FTSensor:
    """Noisy, filtered, tared wrist F/T sensor.

    Each sample: ``x = raw + sigma n`` (``n`` standard normal per component), the first-order
    low-pass ``y <- y + alpha (x - y)`` with ``alpha = 1 - exp(-2 pi f_c dt)``, and the tared
    external wrench ``tare - y``. The six components are Python floats (numpy's per-call
    overhead on 6-vectors costs more than the arithmetic; each operation rounds as numpy's
    element-wise version does).

    Args:
        cfg: Sensor noise and filter settings.
        dt: Sample period [s] (the controller period).
        rng: Random generator for the noise.
    """

    def __init__(self, cfg: FTSensorConfig, dt: float, rng: np.random.Generator) -> None:
        if dt <= 0:
            raise ValueError("dt must be > 0")
        self.cfg = cfg
        self.rng = rng
        wc = 2 * math.pi * cfg.cutoff_hz
        self.alpha = 1.0 if cfg.cutoff_hz <= 0 else 1.0 - math.exp(-wc * dt)
        self.sigma = np.array([cfg.force_noise] * 3 + [cfg.torque_noise] * 3)
        self._filtered: list[float] | None = None
        self._tare = (0.0,) * 6
        # Standard normal draws in blocks (one generator call per NOISE_BLOCK samples; the
        # sequence is the same as drawing six values per sample), scaled by sigma.
        self._block = np.zeros((NOISE_BLOCK, 6))
        self._noise: list[list[float]] = []
        self._next = NOISE_BLOCK

    def sample(self, raw: np.ndarray) -> list[float]:
        """Feed one raw reading ``(fx, fy, fz, tx, ty, tz)`` and return the tared external wrench
        in the sensor frame."""
        if self._next == NOISE_BLOCK:
            self.rng.standard_normal(out=self._block)
            self._noise = (self._block * self.sigma).tolist()
            self._next = 0
        noisy = [n + r for n, r in zip(self._noise[self._next], raw.tolist(), strict=True)]
        self._next += 1
        if self._filtered is None:
            self._filtered = noisy
        else:
            alpha = self.alpha
            self._filtered = [y + (x - y) * alpha
                              for x, y in zip(noisy, self._filtered, strict=True)]
        return [t - y for t, y in zip(self._tare, self._filtered, strict=True)]

    def tare(self) -> None:
        """Zero the sensor at the current (filtered) reading."""
        if self._filtered is not None:
            self._tare = tuple(self._filtered)

    def raw_filtered(self) -> np.ndarray:
        """The filtered reading before taring (the wrench the flange exerts on the tool)."""
        return np.zeros(6) if self._filtered is None else np.array(self._filtered)
