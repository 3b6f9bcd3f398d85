"""One episode: reset the cell, look, grasp, assemble, record.

The grasp comes from a *policy* that sees only the heightmap and returns
:class:`GraspCommand` (world x, y, pad heading); the cell's ground truth is read only to fill
the analysis fields of the record.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from vgs import native
from vgs import vecmath as vm
from vgs.assembly.grasp import grasp
from vgs.assembly.record import EpisodeRecord
from vgs.assembly.strategy import AssemblyModule
from vgs.config import ExperimentConfig, PegConfig
from vgs.control.robot import Robot
from vgs.control.transforms import tilt_angle
from vgs.errors import SimulationError
from vgs.perception import MIN_PEG_PIXELS, PEG_PIXEL_HEIGHT, principal_axis
from vgs.sim.camera import Heightmap, RayCastCamera
from vgs.sim.cell import Cell


@dataclass(frozen=True)
class GraspCommand:
    """Where to grasp: world x, y [m] and the heading of the pads' long side [rad]."""

    x: float
    y: float
    yaw: float


Policy = Callable[[Heightmap], GraspCommand]


@dataclass(frozen=True)
class OracleGrasp:
    """A grasp chooser that reads the peg's true centre of mass ``p_world_com`` besides the
    heightmap: ground truth, for analysis only (the ``com-oracle`` reference policy of
    ``vgs evaluate``, which marks where a grasp at the true centre of mass leads). The
    controller never sees it."""

    choose: Callable[[Heightmap, np.ndarray], GraspCommand]


def peg_axis_from_heightmap(hm: Heightmap) -> tuple[np.ndarray, np.ndarray, float]:
    """Centroid (world x, y), unit axis and visible length of the object in the heightmap.

    The principal axis of the object pixels (height > 5 mm) in world coordinates is the peg's
    axis; its extent along the axis is the visible length (:mod:`vgs.perception`).

    Raises:
        SimulationError: If no object is visible.
    """
    rows, cols = np.nonzero(hm.depth > PEG_PIXEL_HEIGHT)
    if rows.size < MIN_PEG_PIXELS:
        raise SimulationError("no object in the heightmap")
    xs, ys = hm.pixel_to_world(rows, cols)
    center, axis, extent = principal_axis(np.stack([xs, ys], axis=1))
    return center, axis, extent + hm.pixel_size


def jaw_misalignment_deg(yaw: float, R_world_peg: np.ndarray) -> float:
    """Angle between the pads' long side and the peg's axis in the table plane [deg].

    With the pads' heading ``u = (cos yaw, sin yaw)`` and the peg's axis ``a`` (third column of
    ``R_world_peg``) projected on the table, ``(a_x, a_y)``,

        misalignment = acos(|u . (a_x, a_y)| / |(a_x, a_y)|),

    folded into [0, 90] deg because the two pads are symmetric. Ground truth for the record
    only (analysis: which grasps hold but cannot assemble); NaN if the axis stands upright.
    """
    ax, ay = float(R_world_peg[0, 2]), float(R_world_peg[1, 2])
    norm = math.hypot(ax, ay)
    if norm < 1e-9:
        return math.nan
    cos = abs(math.cos(yaw) * ax + math.sin(yaw) * ay) / norm
    return math.degrees(math.acos(min(1.0, cos)))


def across_axis_mm(command: GraspCommand, p_world_peg: np.ndarray,
                   R_world_peg: np.ndarray) -> float:
    """Ground truth (analysis only): the commanded grasp point's distance from the peg's axis
    across it, in the table plane [mm]: with the axis ``a`` projected on the table and
    normalised, and ``v = q - p`` from the peg's centre to the grasp point,
    ``1000 |a_x v_y - a_y v_x|``. NaN if the axis stands upright."""
    ax, ay = float(R_world_peg[0, 2]), float(R_world_peg[1, 2])
    n = math.sqrt(ax * ax + ay * ay)
    if n < 1e-9:
        return math.nan
    vx, vy = command.x - float(p_world_peg[0]), command.y - float(p_world_peg[1])
    return 1000.0 * abs(ax * vy - ay * vx) / n


def perceived_grasp_along(hm: Heightmap, command: GraspCommand) -> float | None:
    """The cell's own knowledge of where it grasps: the commanded point's signed distance from
    the middle of the peg the camera perceives, along the pads' long side
    ``u = (cos yaw, sin yaw)``: ``s = (q - c) . u`` [m]. ``None`` when nothing is perceived."""
    try:
        center, _, _ = peg_axis_from_heightmap(hm)
    except SimulationError:
        return None
    cx, cy = center.tolist()
    return (command.x - cx) * math.cos(command.yaw) + (command.y - cy) * math.sin(command.yaw)


def offset_policy(offset: float) -> Policy:
    """Grasp the peg ``offset`` metres from its visible centre along its visible axis."""

    def policy(hm: Heightmap) -> GraspCommand:
        center, axis, _ = peg_axis_from_heightmap(hm)
        p = center + offset * axis
        return GraspCommand(float(p[0]), float(p[1]), math.atan2(axis[1], axis[0]))

    return policy


def center_policy() -> Policy:
    """The heuristic grasp: the centre of the visible peg, pads along its axis."""
    return offset_policy(0.0)


class GraspWatch:
    """Ground truth of the grasp during the assembly, for the record only (never seen by the
    controller): how far the peg turns in the pads, and the largest moment about the pinch
    axis (tool y) that the fingers' contact forces and, while the pads stick, their weld
    (:mod:`vgs.sim.stiction`) exert on the peg, about the TCP.

    Attached to :attr:`vgs.control.robot.Robot.observers` after the grasp; it samples every
    ``every``-th control tick (25 Hz by default, so a peak is the largest sampled moment) and
    stops looking when the robot starts to release the peg. ``turn_deg`` is the largest angle
    between the peg's axis in the tool frame and its axis at the start.

    A contact ``i`` on the peg pushes it with the force ``f_i = C_i^T f_c`` (world frame, from
    its contact frame ``C_i``) at ``p_i``, and with a torsional torque ``t_c n_i`` about its
    normal; its moment about the TCP is ``(p_i - p_tcp) x f_i + t_c n_i``, of which the record
    takes the component along the pinch axis (in C, :func:`vgs.native.watch_sample`, in
    :mod:`vgs.vecmath`'s order of operations).
    """

    def __init__(self, robot: Robot, every: int = 4) -> None:
        self.robot = robot
        self.cell = robot.cell
        self.every = every
        self._n = 0
        d, ids, m = self.cell.data, self.cell.ids, self.cell.model
        finger_bodies = {int(m.geom_bodyid[g]) for g in ids.pad_geoms}
        is_finger = bytes(int(m.geom_bodyid[g]) in finger_bodies for g in range(m.ngeom))
        latch = self.cell.stiction._native if self.cell.stiction is not None else None
        # (turn_deg, peak_moment, the peg's axis in the tool frame at the start), kept by the C
        # sample (vgs.native.watch_sample, the formulas of the class docstring).
        self._out = np.zeros(5)
        self._native = native.watch_new(
            m._address, d._address, (int(ids.peg_body), int(ids.tcp_site), int(ids.peg_geom)),
            is_finger, latch, self._out)

    @property
    def turn_deg(self) -> float:
        """The largest angle between the peg's axis in the tool frame and its axis at the start
        [deg]: ``acos(a . a_0)``, ``a = R_world_tcp^T a_world``."""
        return float(self._out[0])

    @property
    def peak_moment(self) -> float:
        """The largest sampled moment about the pinch axis on the peg [N m]."""
        return float(self._out[1])

    def __call__(self) -> None:
        if self.robot.phase == "release":
            return
        self._n += 1
        if self._n % self.every == 0:
            native.watch_sample(self._native)


class EpisodeRunner:
    """Runs episodes; keeps one compiled cell per peg geometry.

    Args:
        cfg: Experiment configuration.
    """

    def __init__(self, cfg: ExperimentConfig) -> None:
        self.cfg = cfg
        self._cells: dict[tuple[float, float, float, str], tuple[Cell, RayCastCamera]] = {}

    def cell(self, peg: PegConfig) -> tuple[Cell, RayCastCamera]:
        key = (round(peg.mass, 9), round(peg.length, 9), round(peg.com_shift_mm, 9),
               peg.com_marking)
        if key not in self._cells:
            if len(self._cells) > 8:
                self._cells.clear()
            cell_cfg = replace(self.cfg.cell, peg=peg)
            ctrl = self.cfg.controller
            cell = Cell(cell_cfg, ctrl.joint_kp, ctrl.joint_kv)
            self._cells[key] = (cell, RayCastCamera(cell.model, cell_cfg.camera))
        return self._cells[key]

    def observe(self, seed: int, peg: PegConfig | None = None) -> Heightmap:
        """Reset the cell for ``seed`` and return the heightmap the policy sees."""
        cell, cam = self.cell(peg or self.cfg.cell.peg)
        cell.reset(np.random.default_rng(seed))
        return cam.capture(cell.data)

    def run(self, seed: int, policy: Policy | OracleGrasp, peg: PegConfig | None = None,
            trace: bool = False, assemble: bool = True, time_limit: float | None = None
            ) -> tuple[EpisodeRecord, Robot, Heightmap]:
        """Run one whole episode.

        Args:
            seed: Episode seed: sets the peg pose, the hole displacement and the sensor noise.
            policy: Chooses the grasp from the heightmap (an :class:`OracleGrasp` also from
                the peg's true centre of mass).
            peg: Peg of this episode (default: the configured one).
            trace: Keep per-tick signals in ``robot.trace``.
            assemble: Run the assembly after a successful grasp; ``False`` ends the episode
                with the peg held (``failure_reason = "no_assembly"``), for learners whose
                reward is the grasp's alone (the baseline).
            time_limit: Stop the assembly once it has taken longer than this [s]
                (``cutoff:<phase>``; :class:`vgs.assembly.strategy.AssemblyModule`).

        Returns:
            The record, the robot (for its trace) and the heightmap.
        """
        peg = peg or self.cfg.cell.peg
        cell, cam = self.cell(peg)
        rng = np.random.default_rng(seed)
        cell.reset(rng)
        hm = cam.capture(cell.data)
        record = EpisodeRecord(seed=seed, peg_mass=peg.mass, peg_length=peg.length,
                               peg_com_shift_mm=peg.com_shift_mm)
        record.hole_offset_mm = vm.norm((cell.hole_xy - cell.cfg.hole.nominal_xy).tolist()) * 1000
        robot = Robot(cell, self.cfg.controller, np.random.default_rng([seed, 1]), trace=trace)
        try:
            if isinstance(policy, OracleGrasp):
                command = policy.choose(hm, cell.peg_com_world())
            else:
                command = policy(hm)
            p_peg, R_peg = cell.peg_pose()
            record.jaw_misalignment_deg = jaw_misalignment_deg(command.yaw, R_peg)
            record.across_mm = across_axis_mm(command, p_peg, R_peg)
            grasp_along = perceived_grasp_along(hm, command)
            row, col = hm.world_to_pixel(command.x, command.y)
            inside = 0 <= row < hm.depth.shape[0] and 0 <= col < hm.depth.shape[1]
            surface = float(hm.depth[row, col]) if inside else 0.0
            robot.run(0.2)
            robot.arm.tare()  # tool only, before the grasp
            result = grasp(robot, command.x, command.y, command.yaw, surface)
        except SimulationError:
            record.failure_reason = "unstable"
            return record, robot, hm
        record.grasp_success = result.success
        record.grasp_offset = result.offset
        record.grasp_offset_com = result.offset - peg.com_shift_mm / 1000.0
        if not result.success:
            record.failure_reason = "grasp"
            return record, robot, hm
        if not assemble:
            record.failure_reason = "no_assembly"
            return record, robot, hm
        nominal = self.cfg.cell.peg
        hole = self.cfg.cell.hole
        module = AssemblyModule(robot, self.cfg.assembly, nominal, hole.nominal_xy, hole.depth,
                                hole.clearance, time_limit=time_limit, grasp_along=grasp_along)
        watch = GraspWatch(robot)
        robot.observers.append(watch)
        module.run(record)
        robot.observers.remove(watch)
        record.peg_turn_deg = watch.turn_deg
        record.peak_grasp_moment = watch.peak_moment
        self._ground_truth(cell, record)
        return record, robot, hm

    def _ground_truth(self, cell: Cell, record: EpisodeRecord) -> None:
        """Fill the analysis fields from the simulator state (never used by the controller)."""
        p, R = cell.peg_pose()
        if not np.all(np.isfinite(p)):
            record.success = False
            record.failure_reason = "unstable"
            return
        axis = R[:, 2]
        record.final_tilt_deg = math.degrees(tilt_angle(axis, np.array([0.0, 0.0, 1.0])))
        half = 0.5 * cell.cfg.peg.length * axis
        low = min(p + half, p - half, key=lambda v: v[2])
        entrance = cell.hole_position()
        record.insertion_depth_mm = float((entrance[2] - low[2]) * 1000)
        radial = vm.norm((low[:2] - entrance[:2]).tolist())
        inserted = (record.insertion_depth_mm >= 0.9 * self.cfg.assembly.insertion_depth * 1000
                    and radial < cell.cfg.hole.radius)
        if record.success and not inserted:
            record.success = False
            record.failure_reason = "not_inserted"
