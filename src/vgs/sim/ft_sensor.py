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
        self.filtered: list[float] | None = None
        self.tare_offset = [0.0] * 6
        # Standard normal draws in blocks (one generator call per NOISE_BLOCK samples; the
        # sequence is the same as drawing six values per sample), scaled by sigma per block
        # (numpy's element-wise product rounds once per element, on every CPU).
        self._block = np.zeros((NOISE_BLOCK, 6))
        self._rows: list[list[float]] = []
        self._next = NOISE_BLOCK

    def sample(self, raw: np.ndarray) -> tuple[float, float, float, float, float, float]:
        """Feed one raw reading ``(fx, fy, fz, tx, ty, tz)`` and return the tared external wrench
        in the sensor frame: ``y = y + alpha ((raw + noise) - y)``, ``w = tare - y`` (plain
        floats)."""
        if self._next == NOISE_BLOCK:
            self.rng.standard_normal(out=self._block)
            self._block *= self.sigma
            self._rows = self._block.tolist()
            self._next = 0
        noise = self._rows[self._next]
        self._next += 1
        r = raw.tolist()
        noisy = [noise[0] + r[0], noise[1] + r[1], noise[2] + r[2], noise[3] + r[3],
                 noise[4] + r[4], noise[5] + r[5]]
        y = self.filtered
        if y is None:
            y = self.filtered = noisy
        else:
            a = self.alpha
            for i in range(6):
                y[i] += (noisy[i] - y[i]) * a
        t = self.tare_offset
        return (t[0] - y[0], t[1] - y[1], t[2] - y[2], t[3] - y[3], t[4] - y[4], t[5] - y[5])

    def tare(self) -> None:
        """Zero the sensor at the current (filtered) reading."""
        if self.filtered is not None:
            self.tare_offset = list(self.filtered)

    def raw_filtered(self) -> np.ndarray:
        """The filtered reading before taring (the wrench the flange exerts on the tool)."""
        return np.zeros(6) if self.filtered is None else np.array(self.filtered)
