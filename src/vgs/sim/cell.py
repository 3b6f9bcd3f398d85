"""The assembly cell: UR5 + F/T sensor + RG2, table, peg and hole block, built from a config.

Data flows one way: :class:`vgs.config.CellConfig` -> :func:`build_spec` -> :class:`Cell`
(model, data, named ids, reset). Ground-truth accessors (``peg_pose``, ``hole_position``) exist
for logging and tests; the controller never calls them.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from vgs.config import CellConfig
from vgs.errors import SimulationError
from vgs.sim import objects, rg2, stiction, ur5
from vgs.sim.ids import cell_ids

# A joint configuration with the TCP at (0.42, -0.05, 0.25), tool z down, tool x along world x
# (elbow up, wrist down; solved with the TCP Jacobian, checked in tests/test_kinematics.py).
HOME_Q = np.array([2.7621, -1.746, 1.5998, -1.4246, -1.5708, -1.9503])
# Region of the table where the peg's centre is placed at reset (inside the camera view).
PEG_SPAWN_HALF = 0.08


def contact_params(cfg: CellConfig) -> tuple[list[float], list[float]]:
    """solref and solimp of the peg, pad and hole contacts.

    A time constant of ``sim.contact_timeconst`` (>= 2 time steps, MuJoCo's stability rule) with
    critical damping, and an impedance rising from 0.95 to 0.99 over 0.5 mm of penetration, which
    keeps the penetration under a 10 N press at a few hundredths of a millimetre: far below the
    0.5 mm diametral clearance.
    """
    return [cfg.sim.contact_timeconst, 1.0], [0.95, 0.99, 0.0005, 0.5, 2.0]


def build_spec(cfg: CellConfig) -> mujoco.MjSpec:
    """Build the whole cell as an :class:`mujoco.MjSpec`."""
    spec = mujoco.MjSpec()
    spec.modelname = "vgs_cell"
    opt = spec.option
    opt.timestep = cfg.sim.timestep
    opt.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    opt.impratio = cfg.sim.impratio
    opt.noslip_iterations = cfg.sim.noslip_iterations
    spec.compiler.autolimits = True
    spec.compiler.degree = False  # every angle in vgs is in radians
    spec.visual.global_.offwidth = 640
    spec.visual.global_.offheight = 480
    world = spec.worldbody
    world.add_light(pos=[0.4, 0.0, 1.5], dir=[0, 0, -1], diffuse=[0.8, 0.8, 0.8])
    solref, solimp = contact_params(cfg)
    objects.add_table(world)
    flange = ur5.add_ur5(world)
    rg2.add_rg2(flange, spec, cfg.gripper, solref, solimp)
    objects.add_peg(world, cfg.peg, solref, solimp)
    objects.add_hole(spec, world, cfg.hole, solref, solimp)
    if cfg.gripper.stiction:
        stiction.add_pad_weld(spec, solref, solimp)
    for name in ur5.JOINT_NAMES:
        act = spec.add_actuator(name=name, target=name, trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=1.0, kv=0.0)  # gains are set from the controller config
        act.ctrlrange = [-2 * math.pi, 2 * math.pi]
    return spec


class Cell:
    """A compiled cell with its state.

    Args:
        cfg: Cell configuration.
        arm_kp: Joint servo stiffnesses [N m/rad] (six values).
        arm_kv: Joint servo dampings [N m s/rad] (six values).
    """

    def __init__(self, cfg: CellConfig, arm_kp: tuple[float, ...], arm_kv: tuple[float, ...]):
        self.cfg = cfg
        self.spec = build_spec(cfg)
        self.model = self.spec.compile()
        self.data = mujoco.MjData(self.model)
        self.ids = cell_ids(self.model)
        m = self.model
        for i, a in enumerate(self.ids.arm_act):
            m.actuator_gainprm[a, 0] = arm_kp[i]
            m.actuator_biasprm[a, 1] = -arm_kp[i]
            m.actuator_biasprm[a, 2] = -arm_kv[i]
        self.hole_xy = np.array(cfg.hole.nominal_xy, dtype=float)
        self._badqacc = self.data.warning[mujoco.mjtWarning.mjWARN_BADQACC]
        self._peg_qacc = self.data.qacc[self.ids.peg_dof:self.ids.peg_dof + 1]
        self.stiction = (stiction.PadStiction(m, self.data, self.ids, cfg.gripper,
                                              cfg.peg.radius)
                         if cfg.gripper.stiction else None)

    # -- reset ------------------------------------------------------------------------------

    def reset(self, rng: np.random.Generator) -> None:
        """Put the robot home with the gripper open, the peg at a random pose lying on the table
        inside the camera view, and the hole displaced randomly within a disk of the hole's area
        around its nominal position (paper 3.2)."""
        m, d, ids, cfg = self.model, self.data, self.ids, self.cfg
        mujoco.mj_resetData(m, d)
        d.qpos[ids.arm_qpos] = HOME_Q
        d.ctrl[ids.arm_act] = HOME_Q
        half_stroke = cfg.gripper.stroke / 2
        d.qpos[ids.finger_qpos] = half_stroke
        d.ctrl[ids.finger_act] = half_stroke
        cx, cy = cfg.camera.center_xy
        x = cx + rng.uniform(-PEG_SPAWN_HALF, PEG_SPAWN_HALF)
        y = cy + rng.uniform(-PEG_SPAWN_HALF, PEG_SPAWN_HALF)
        yaw = rng.uniform(-math.pi, math.pi)
        self.set_peg_lying(x, y, yaw)
        if cfg.hole.randomize:
            r = cfg.hole.radius * math.sqrt(rng.uniform())
            phi = rng.uniform(0, 2 * math.pi)
            offset = np.array([r * math.cos(phi), r * math.sin(phi)])
        else:
            offset = np.zeros(2)
        self.hole_xy = np.array(cfg.hole.nominal_xy) + offset
        d.mocap_pos[ids.hole_mocap] = [*self.hole_xy, 0.0]
        mujoco.mj_forward(m, d)

    def set_peg_lying(self, x: float, y: float, yaw: float) -> None:
        """Place the peg lying on the table, its axis horizontal at heading ``yaw``."""
        d, ids = self.data, self.ids
        # Body z (the cylinder axis) horizontal along (cos yaw, sin yaw).
        q_yaw = np.array([math.cos(yaw / 2), 0, 0, math.sin(yaw / 2)])
        q_tilt = np.array([math.cos(math.pi / 4), 0, math.sin(math.pi / 4), 0])
        quat = np.zeros(4)
        mujoco.mju_mulQuat(quat, q_yaw, q_tilt)
        d.qpos[ids.peg_qpos:ids.peg_qpos + 3] = [x, y, self.cfg.peg.radius]
        d.qpos[ids.peg_qpos + 3:ids.peg_qpos + 7] = quat
        d.qvel[ids.peg_dof:ids.peg_dof + 6] = 0

    # -- stepping ---------------------------------------------------------------------------

    def step(self, nstep: int) -> None:
        """Advance the physics ``nstep`` steps; raise :class:`SimulationError` on divergence."""
        mujoco.mj_step(self.model, self.data, nstep)
        if self.stiction is not None:
            self.stiction.update()
        if self._badqacc.number > 0 or not math.isfinite(self._peg_qacc[0]):
            raise SimulationError("physics diverged (bad qacc)")

    # -- ground truth (logging and tests only) ----------------------------------------------

    def peg_pose(self) -> tuple[np.ndarray, np.ndarray]:
        """``(p_world_peg, R_world_peg)``: peg centre and orientation (axis = third column)."""
        b = self.ids.peg_body
        return self.data.xpos[b].copy(), self.data.xmat[b].reshape(3, 3).copy()

    def peg_com_world(self) -> np.ndarray:
        """``p_world_com``: the peg's true centre of mass (the body's inertial frame), ground
        truth for records, tests and the ``com-oracle`` reference policy only."""
        return self.data.xipos[self.ids.peg_body].copy()

    def hole_position(self) -> np.ndarray:
        """Centre of the hole entrance in the world frame."""
        return np.array([*self.hole_xy, self.cfg.hole.depth])

    def finger_opening(self) -> float:
        """Distance between the pads [m] (the RG2's width reading)."""
        return float(self.data.qpos[self.ids.finger_qpos].sum())

    def export_xml(self) -> str:
        """The compiled scene as MJCF text (opens in MuJoCo's own viewer)."""
        return self.spec.to_xml()
