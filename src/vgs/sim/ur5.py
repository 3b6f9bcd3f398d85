"""Universal Robots UR5, built in code from its published DH parameters.

Constants (Universal Robots, "DH parameters for calculations of kinematics and dynamics",
UR5 column):

====== ========= ========== ========= ======== ==================================
joint  d [m]     a [m]      alpha     mass kg  centre of mass in DH frame i [m]
====== ========= ========== ========= ======== ==================================
1      0.089159  0          pi/2      3.7      (0, -0.02561, 0.00193)
2      0          -0.425    0         8.393    (0.2125, 0, 0.11336)
3      0          -0.39225  0         2.275    (0.15, 0, 0.0265)
4      0.10915   0          pi/2      1.219    (0, -0.0018, 0.01634)
5      0.09465   0          -pi/2     1.219    (0, 0.0018, 0.01634)
6      0.0823    0          0         0.1879   (0, 0, -0.001159)
====== ========= ========== ========= ======== ==================================

UR publishes no inertia tensors for the CB-series UR5; like ROS-Industrial's ``ur_description`` we
use solid-cylinder approximations (radius, length below) about each link's centre of mass, with
the cylinder axis along the link.

Construction. Standard DH gives ``T_{i-1,i} = Rz(theta_i) Tz(d_i) Tx(a_i) Rx(alpha_i)``. Body ``i``
is placed at the constant transform ``S_i = Tz(d_i) Tx(a_i) Rx(alpha_i)`` in body ``i-1`` and its
hinge rotates about the z axis of frame ``i-1``, i.e. about the axis ``R_i^T e_z`` through the point
``-R_i^T t_i`` in body ``i``'s own frame. Then body ``i``'s frame *is* DH frame ``i``, and the last
body's frame is the tool flange (z along the tool axis), marked by the site ``flange``.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from vgs import vecmath as vm

JOINT_NAMES: tuple[str, ...] = (
    "shoulder_pan_joint",
    "shoulder_lift_joint",
    "elbow_joint",
    "wrist_1_joint",
    "wrist_2_joint",
    "wrist_3_joint",
)
LINK_NAMES: tuple[str, ...] = (
    "shoulder_link",
    "upper_arm_link",
    "forearm_link",
    "wrist_1_link",
    "wrist_2_link",
    "wrist_3_link",
)

DH_D = np.array([0.089159, 0.0, 0.0, 0.10915, 0.09465, 0.0823])
DH_A = np.array([0.0, -0.425, -0.39225, 0.0, 0.0, 0.0])
DH_ALPHA = np.array([math.pi / 2, 0.0, 0.0, math.pi / 2, -math.pi / 2, 0.0])

LINK_MASS = np.array([3.7, 8.393, 2.275, 1.219, 1.219, 0.1879])
LINK_COM = np.array(
    [
        [0.0, -0.02561, 0.00193],
        [0.2125, 0.0, 0.11336],
        [0.15, 0.0, 0.0265],
        [0.0, -0.0018, 0.01634],
        [0.0, 0.0018, 0.01634],
        [0.0, 0.0, -0.001159],
    ]
)
# Cylinder approximations (radius, length, axis) as in ur_description.
_LINK_CYLINDER = (
    (0.06, 0.15, "z"),
    (0.06, 0.425, "x"),
    (0.06, 0.39225, "x"),
    (0.06, 0.12, "z"),
    (0.06, 0.12, "z"),
    (0.0375, 0.0345, "z"),
)
# UR5 joint ranges: +-2 pi on every joint (the elbow is limited to +-pi by its cable routing).
JOINT_RANGE = np.array([[-2 * math.pi, 2 * math.pi]] * 6)
JOINT_RANGE[2] = (-math.pi, math.pi)
# Reflected rotor inertia of the harmonic drives (estimate: size 3/4 joints ~0.4 kg m^2 at the
# output through ratio 101, size 0/1 wrist joints ~0.1 kg m^2) and viscous joint friction.
ARMATURE = np.array([0.4, 0.4, 0.25, 0.1, 0.1, 0.1])
JOINT_DAMPING = np.array([2.0, 2.0, 1.5, 0.5, 0.5, 0.5])
# Peak joint torques of the UR5 (datasheet: size 3 joints 150 N m, size 2 28 N m).
TORQUE_LIMIT = np.array([150.0, 150.0, 150.0, 28.0, 28.0, 28.0])


def cylinder_inertia(mass: float, radius: float, length: float, axis: str) -> np.ndarray:
    """Principal moments of a solid cylinder about its centre.

    ``I_axial = m r^2 / 2`` and ``I_transverse = m (3 r^2 + L^2) / 12``.
    """
    axial = 0.5 * mass * radius**2
    transverse = mass * (3 * radius**2 + length**2) / 12.0
    inertia = np.full(3, transverse)
    inertia["xyz".index(axis)] = axial
    return inertia


def dh_transform(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Standard DH link transform ``Rz(theta) Tz(d) Tx(a) Rx(alpha)`` as a 4x4 matrix."""
    ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [
            [ct, -st * ca, st * sa, a * ct],
            [st, ct * ca, -ct * sa, a * st],
            [0.0, sa, ca, d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


def forward_kinematics(q: np.ndarray) -> np.ndarray:
    """``T_base_flange``: pose of the tool flange in the robot base frame from DH parameters.

    Args:
        q: Six joint angles [rad].

    Returns:
        4x4 homogeneous transform.
    """
    q = np.asarray(q, dtype=float)
    if q.shape != (6,):
        raise ValueError(f"q must have shape (6,), got {q.shape}")
    T = np.eye(4)
    for i in range(6):
        T = T @ dh_transform(q[i], DH_D[i], DH_A[i], DH_ALPHA[i])
    return T


def _static_part(i: int) -> np.ndarray:
    """``S_i = Tz(d_i) Tx(a_i) Rx(alpha_i)``: the constant part of DH link transform ``i``."""
    return dh_transform(0.0, DH_D[i], DH_A[i], DH_ALPHA[i])


def _mat_to_quat(R: np.ndarray) -> np.ndarray:
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.ascontiguousarray(R).reshape(9))
    return quat


def add_ur5(parent: mujoco.MjsBody, base_pos: tuple[float, float, float] = (0.0, 0.0, 0.0)):
    """Add the UR5 to ``parent`` (usually the world body).

    Args:
        parent: Body to mount the robot base on.
        base_pos: Base position in the parent frame [m].

    Returns:
        The wrist-3 body (``wrist_3_link``), whose frame is the DH flange frame.
    """
    base = parent.add_body(name="base_link", pos=list(base_pos))
    base.add_geom(
        type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[0.075, 0.04, 0], pos=[0, 0, 0.04],
        rgba=[0.25, 0.25, 0.28, 1], contype=0, conaffinity=0, group=1, mass=0,
    )
    body = base
    for i in range(6):
        S = _static_part(i)
        R, t = S[:3, :3], S[:3, 3]
        child = body.add_body(name=LINK_NAMES[i], pos=t.tolist(), quat=_mat_to_quat(R).tolist())
        child.add_joint(
            name=JOINT_NAMES[i],
            type=mujoco.mjtJoint.mjJNT_HINGE,
            pos=list(vm.scale(-1.0, vm.mtv(vm.mat3(R), t.tolist()))),
            axis=list(vm.mtv(vm.mat3(R), (0.0, 0.0, 1.0))),
            range=JOINT_RANGE[i].tolist(),
            armature=float(ARMATURE[i]),
            damping=float(JOINT_DAMPING[i]),
            actfrcrange=[-TORQUE_LIMIT[i], TORQUE_LIMIT[i]],
        )
        radius, length, axis = _LINK_CYLINDER[i]
        child.explicitinertial = True
        child.mass = float(LINK_MASS[i])
        child.ipos = LINK_COM[i].tolist()
        child.inertia = cylinder_inertia(LINK_MASS[i], radius, length, axis).tolist()
        # Arm links carry gravity compensation, as the UR controller does for its own links; the
        # tool and the payload do not, so the wrist F/T sensor reads their weight.
        child.gravcomp = 1.0
        _add_link_visual(child, i)
        body = child
    body.add_site(name="flange", pos=[0, 0, 0], size=[0.005, 0, 0], group=3)
    return body


def _add_link_visual(body: mujoco.MjsBody, i: int) -> None:
    """Visual-only capsules along each link (no collision: nothing can touch them)."""
    grey = [0.7, 0.72, 0.75, 1]
    kw = dict(contype=0, conaffinity=0, group=1, mass=0, rgba=grey)
    cap = mujoco.mjtGeom.mjGEOM_CAPSULE
    # The joint sits at -R^T t in this body: draw the link from there to this frame's origin,
    # or a short capsule at the origin when both coincide.
    S = _static_part(i)
    R, t = S[:3, :3], S[:3, 3]
    p_prev = vm.scale(-1.0, vm.mtv(vm.mat3(R), t.tolist()))
    if vm.norm(p_prev) > 1e-6:
        body.add_geom(type=cap, size=[0.045, 0, 0], fromto=[*p_prev, 0, 0, 0], **kw)
    else:
        body.add_geom(type=cap, size=[0.045, 0.03, 0], pos=[0, 0, 0], **kw)
