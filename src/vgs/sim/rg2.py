"""OnRobot RG2 gripper and the wrist force/torque sensor, built in code.

RG2 datasheet values used here: stroke 0-110 mm, gripping force 3-40 N, weight 0.65 kg,
overall length about 0.21 m from the mounting flange to the fingertips. The linkage is modelled
as two prismatic fingers kept symmetric by a joint equality, each driven by a force-limited
position servo: the finger closes until the object pushes back with the set force.

F/T sensor: a 0.30 kg, 37.5 mm body between the flange and the gripper (an FT-300-class sensor).
MuJoCo's ``force`` and ``torque`` sensors at the site ``ft`` report the interaction wrench between
the sensor's tool side and the flange; it contains the weight of gripper and peg, their inertial
loads and every contact force on the tool, as a real wrist sensor does.

Frames: ``tcp`` lies on the tool axis (z) midway between the finger pads; the fingers close along
the tool y axis; the pads' long side lies along the tool x axis.
"""

from __future__ import annotations

import mujoco

from vgs.config import GripperConfig

FT_THICKNESS = 0.0375
FT_MASS = 0.30
HOUSING_MASS = 0.45
HOUSING_HALF = (0.030, 0.045, 0.060)  # box half-sizes of the RG2 housing [m]
FINGER_MASS = 0.10
TCP_OFFSET = 0.195  # flange-side face of the housing to the pad centres, along the tool z [m]
PAD_HALF = (0.011, 0.003, 0.011)  # pad half-sizes: along the peg axis, thickness, height [m]
FINGER_KP = 8000.0  # finger servo stiffness [N/m]; saturates at the force limit within mm
FINGER_KV = 40.0  # finger servo damping [N s/m]



def pad_contact_half_length(cfg: GripperConfig) -> float:
    """Half-length of the pads' collision boxes along the peg axis [m]: a quarter pad length.

    A cylinder pressed on a flat pad touches it along a line of the pad's length L (22 mm) with,
    at rest, uniform pressure p = F / L. Turning it in the pad about the line's midpoint takes
    ``int_{-L/2}^{L/2} mu p |x| dx = mu F L / 4``. MuJoCo resolves a box-on-cylinder line contact
    into two point contacts at the ends of the overlap, each carrying F / 2; with the ends at
    +-L/4 the two points' sliding friction resists exactly ``2 mu (F / 2) (L / 4) = mu F L / 4``
    and their weight is carried at the same place as the pressure's resultant on each half.
    MuJoCo's torsional term then stands only for each point's own contact patch (a rubber pad
    pressed by a 15 mm radius cylinder forms a strip about 3 mm wide; a patch of radius a
    resists spin with about (2/3) mu a): ``gripper.pad_torsional_friction`` = 1 mm, 2 % of the
    line's torsion. Setting it to the line's mu L / 4 would count the same torsion twice.
    """
    return PAD_HALF[0] / 2.0


def pad_condim(cfg: GripperConfig) -> int:
    """Contact dimensionality of the pads: 3 (sliding friction only) by default; 4 with a
    torsional, 6 with a rolling coefficient."""
    if cfg.pad_rolling_friction > 0:
        return 6
    return 4 if cfg.pad_torsional_friction > 0 else 3


def grasp_moment_capacity(cfg: GripperConfig, friction: float | None = None) -> float:
    """Largest static moment about the pinch axis that the two pads hold [N m].

    ``M_max = 2 pads * mu * F * L / 4`` (:func:`pad_contact_half_length`), plus, where a
    torsional coefficient ``mu_t`` is set, its share: each of the four contact points carries
    ``F / 2`` in an elliptic friction cone, so it resists at most
    ``(F / 2) sqrt((mu L / 4)^2 + mu_t^2)`` about the pinch axis. The defaults (RG2 at 40 N,
    mu = 1, L = 22 mm) give 0.44 N m. ``friction`` overrides the pads' sliding coefficient
    (the contact uses the pad's, as the pads have contact priority).
    """
    mu = cfg.pad_friction if friction is None else friction
    lever = pad_contact_half_length(cfg)
    return 4 * (cfg.force / 2) * ((mu * lever) ** 2 + cfg.pad_torsional_friction ** 2) ** 0.5


# Collision bits: 1 static scene (table, hole), 2 peg, 4 gripper.
CT_SCENE, CT_PEG, CT_GRIPPER = 1, 2, 4


def add_rg2(flange: mujoco.MjsBody, spec: mujoco.MjSpec, cfg: GripperConfig,
            solref: list[float], solimp: list[float]) -> None:
    """Add F/T sensor, RG2 housing, fingers, pads, actuators and sites to the flange body."""
    ft = flange.add_body(name="ft_sensor", pos=[0, 0, 0])
    ft.add_site(name="ft", pos=[0, 0, 0], size=[0.004, 0, 0], group=3)
    ft.add_geom(
        type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[0.038, FT_THICKNESS / 2, 0],
        pos=[0, 0, FT_THICKNESS / 2], mass=FT_MASS, rgba=[0.15, 0.15, 0.15, 1],
        contype=0, conaffinity=0, group=1,
    )
    housing = ft.add_body(name="rg2", pos=[0, 0, FT_THICKNESS])
    housing.add_geom(
        type=mujoco.mjtGeom.mjGEOM_BOX, size=list(HOUSING_HALF), pos=[0, 0, HOUSING_HALF[2]],
        mass=HOUSING_MASS, rgba=[0.85, 0.85, 0.85, 1], contype=CT_GRIPPER,
        conaffinity=CT_SCENE, group=1,
    )
    housing.add_site(name="tcp", pos=[0, 0, TCP_OFFSET], size=[0.004, 0, 0], group=3)
    half_stroke = cfg.stroke / 2
    for side, sign in (("left", 1.0), ("right", -1.0)):
        finger = housing.add_body(name=f"finger_{side}", pos=[0, 0, TCP_OFFSET])
        finger.add_joint(
            name=f"finger_{side}_joint", type=mujoco.mjtJoint.mjJNT_SLIDE,
            axis=[0, sign, 0], range=[0.0, half_stroke], damping=2.0, armature=0.01,
        )
        y_pad = PAD_HALF[1]  # finger opening 0 -> pads touch at the tool axis
        link_top = 2 * HOUSING_HALF[2] - TCP_OFFSET
        finger.add_geom(
            name=f"finger_{side}_link", type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[0.009, 0.004, (-link_top - PAD_HALF[2]) / 2],
            pos=[0, sign * (y_pad + 0.004 + PAD_HALF[1]), (link_top - PAD_HALF[2]) / 2],
            mass=FINGER_MASS * 0.8, rgba=[0.3, 0.3, 0.32, 1], contype=CT_GRIPPER,
            conaffinity=CT_SCENE | CT_PEG, group=1,
        )
        # What is seen and weighed: the whole 22 mm pad. What touches: the same pad cut to
        # the length over which its two contact points carry a line contact's torsion (see
        # pad_contact_half_length).
        finger.add_geom(
            name=f"pad_{side}_visual", type=mujoco.mjtGeom.mjGEOM_BOX, size=list(PAD_HALF),
            pos=[0, sign * y_pad, 0], mass=FINGER_MASS * 0.2, rgba=[0.1, 0.1, 0.1, 1],
            contype=0, conaffinity=0, group=1,
        )
        finger.add_geom(
            name=f"pad_{side}", type=mujoco.mjtGeom.mjGEOM_BOX,
            size=[pad_contact_half_length(cfg), PAD_HALF[1], PAD_HALF[2]],
            pos=[0, sign * y_pad, 0], mass=0.0, rgba=[0.1, 0.1, 0.1, 0.0],
            contype=CT_GRIPPER, conaffinity=CT_SCENE | CT_PEG, condim=pad_condim(cfg), group=3,
            friction=[cfg.pad_friction, cfg.pad_torsional_friction, cfg.pad_rolling_friction],
            solref=solref, solimp=solimp, priority=1,
        )
        act = spec.add_actuator(name=f"finger_{side}", target=f"finger_{side}_joint",
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=FINGER_KP, kv=FINGER_KV)
        act.ctrlrange = [0.0, half_stroke]
        act.forcelimited = mujoco.mjtLimited.mjLIMITED_TRUE
        act.forcerange = [-cfg.force, cfg.force]
    eq = spec.add_equality(type=mujoco.mjtEq.mjEQ_JOINT, name1="finger_left_joint",
                           name2="finger_right_joint")
    eq.data[:5] = [0, 1, 0, 0, 0]
    spec.add_sensor(name="ft_force", type=mujoco.mjtSensor.mjSENS_FORCE,
                    objtype=mujoco.mjtObj.mjOBJ_SITE, objname="ft")
    spec.add_sensor(name="ft_torque", type=mujoco.mjtSensor.mjSENS_TORQUE,
                    objtype=mujoco.mjtObj.mjOBJ_SITE, objname="ft")
