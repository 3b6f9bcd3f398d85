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

    Each sample ``raw = (fx, fy, fz, tx, ty, tz)`` is filtered and tared, per component::

        y <- y + ((raw + noise) - y) alpha      (y <- raw + noise at the first sample)
        w  = tare - y                           (the tared external wrench, sensor frame)

    with ``alpha = 1 - exp(-2 pi f_c dt)`` (first-order low-pass at ``cutoff_hz``; 1: none) and
    ``noise ~ N(0, sigma^2)`` per component. The sample itself runs in C within the arm's tick
    (:func:`vgs.native.arm_update`, in that order of operations); this object owns the
    sensor's state: the filtered reading, the tare and the noise.

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
        # The state the C sample reads and writes: (sampled yet: 0/1, alpha); the filtered
        # reading y; the tare.
        self.state = np.array([0.0, self.alpha])
        self.filtered = np.zeros(6)
        self.tare_offset = np.zeros(6)
        # Standard normal draws in blocks (one generator call per NOISE_BLOCK samples; the
        # sequence is the same as drawing six values per sample), scaled by sigma per block
        # (numpy's element-wise product rounds once per element, on every CPU).
        self.noise = np.zeros((NOISE_BLOCK, 6))
        self._next = NOISE_BLOCK

    def next_row(self) -> int:
        """The row of :attr:`noise` the next sample adds (a fresh block every ``NOISE_BLOCK``
        samples)."""
        if self._next == NOISE_BLOCK:
            self.rng.standard_normal(out=self.noise)
            self.noise *= self.sigma
            self._next = 0
        row = self._next
        self._next += 1
        return row

    @property
    def sampled(self) -> bool:
        """Whether the sensor has been sampled since it was made."""
        return bool(self.state[0])

    def tare(self) -> None:
        """Zero the sensor at the current (filtered) reading."""
        if self.sampled:
            self.tare_offset[:] = self.filtered
