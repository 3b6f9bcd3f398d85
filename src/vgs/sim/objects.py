"""Table, peg and hole block.

The hole block is a ring of ``segments`` convex wedges (MuJoCo meshes). Each wedge spans
``2 pi / segments`` of the ring; its inner face is the chord whose midpoint lies on the hole radius
``r``, so the inner surface lies between ``r`` and ``r / cos(pi / segments)`` (see
:attr:`vgs.config.HoleConfig.surface_tolerance`). The block's top face is the ``hole_entrance``
plane at z = depth; the hole is through, its bottom is the table.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

from vgs.config import HoleConfig, PegConfig
from vgs.sim.rg2 import CT_GRIPPER, CT_PEG, CT_SCENE

TABLE_HALF = (0.45, 0.6, 0.02)
TABLE_CENTER = (0.40, 0.05)


def add_table(world: mujoco.MjsBody) -> None:
    """A fixed table whose top surface is the plane z = 0 (``condim=6``: a peg lying on it resists
    rolling)."""
    world.add_geom(
        name="table", type=mujoco.mjtGeom.mjGEOM_BOX, size=list(TABLE_HALF),
        pos=[TABLE_CENTER[0], TABLE_CENTER[1], -TABLE_HALF[2]], rgba=[0.55, 0.42, 0.3, 1],
        contype=CT_SCENE, conaffinity=0, condim=6, friction=[0.5, 0.005, 0.0001], group=0,
    )


MARK_LENGTH = 0.010  # the painted heavy end [m]
MARK_THICKNESS = 0.0003  # its coat, so the camera's rays meet it first [m]


def add_peg(world: mujoco.MjsBody, cfg: PegConfig, solref: list[float],
            solimp: list[float]) -> None:
    """A free cylinder; its axis is the body's z axis, its centre of mass the body origin.

    Its contacts with the hole block have ``condim=4`` (sliding and torsional friction); with the
    table ``condim=6`` (the table's), whose rolling friction keeps the lying peg from rolling away
    from a closing finger; the pads' priority decides the pad contacts.

    Sites: ``peg_com`` (centre), ``peg_end_pos`` / ``peg_end_neg`` (centres of the two flat ends).
    """
    peg = world.add_body(name="peg", pos=[0.4, 0.0, cfg.radius])
    peg.add_freejoint(name="peg_free")
    peg.add_geom(
        name="peg", type=mujoco.mjtGeom.mjGEOM_CYLINDER, size=[cfg.radius, cfg.length / 2, 0],
        mass=cfg.mass, rgba=[0.85, 0.2, 0.15, 1], contype=CT_PEG,
        conaffinity=CT_SCENE | CT_GRIPPER, condim=4,
        friction=[cfg.friction, 0.002, 0.0005], solref=solref, solimp=solimp, group=0,
    )
    if cfg.com_shift_mm:
        _shift_centre_of_mass(peg, cfg)
    peg.add_site(name="peg_com", pos=[0, 0, 0], size=[0.003, 0, 0], group=3)
    peg.add_site(name="peg_end_pos", pos=[0, 0, cfg.length / 2], size=[0.003, 0, 0], group=3)
    peg.add_site(name="peg_end_neg", pos=[0, 0, -cfg.length / 2], size=[0.003, 0, 0], group=3)


def peg_inertial(cfg: PegConfig) -> tuple[float, float, float, float]:
    """``(mass, c, I_transverse, I_axial)`` of a peg whose centre of mass lies ``c`` from its
    middle along its axis (body +z, the heavy end), about that centre.

    A body of the peg's material fills the whole cylinder (mass ``m_b``, centre at 0) and an
    insert adds ``m_i`` uniformly over the last quarter ``l_i = L / 4`` (centre at
    ``z_i = 3 L / 8``): ``m_i z_i = m c``, ``m_b = m - m_i``. With ``r`` the radius,
    ``I_axial = m r^2 / 2`` and ``I_transverse = m_b ((3 r^2 + L^2) / 12 + c^2)
    + m_i ((3 r^2 + l_i^2) / 12 + (z_i - c)^2)`` (solid cylinders, parallel axes).
    """
    m, L, r = cfg.mass, cfg.length, cfg.radius
    c = cfg.com_shift_mm / 1000.0
    l_i, z_i = L / 4.0, 3.0 * L / 8.0
    m_i = m * c / z_i
    m_b = m - m_i
    transverse = (m_b * ((3.0 * r * r + L * L) / 12.0 + c * c)
                  + m_i * ((3.0 * r * r + l_i * l_i) / 12.0 + (z_i - c) ** 2))
    return m, c, transverse, 0.5 * m * r * r


def _shift_centre_of_mass(peg: mujoco.MjsBody, cfg: PegConfig) -> None:
    """Give the peg body the inertia of :func:`peg_inertial` (explicit: the geom's uniform
    mass no longer counts) and, with ``com_marking = visible``, paint its heavy end."""
    mass, c, transverse, axial = peg_inertial(cfg)
    peg.explicitinertial = True
    peg.mass = mass
    peg.ipos = [0.0, 0.0, c]
    peg.iquat = [1.0, 0.0, 0.0, 0.0]
    peg.inertia = [transverse, transverse, axial]
    if cfg.com_marking == "visible":
        peg.add_geom(name="peg_mark", type=mujoco.mjtGeom.mjGEOM_CYLINDER,
                     size=[cfg.radius + MARK_THICKNESS, MARK_LENGTH / 2, 0],
                     pos=[0.0, 0.0, cfg.length / 2 - MARK_LENGTH / 2], mass=0.0,
                     rgba=[0.1, 0.25, 0.85, 1], contype=0, conaffinity=0, group=0)


def wedge_vertices(cfg: HoleConfig, k: int) -> np.ndarray:
    """Eight vertices of wedge ``k`` (a convex prism) in the hole frame."""
    n = cfg.segments
    r_in = cfg.radius / math.cos(math.pi / n)
    r_out = cfg.outer_radius / math.cos(math.pi / n)
    verts = []
    for z in (0.0, cfg.depth):
        for angle in (2 * math.pi * k / n, 2 * math.pi * (k + 1) / n):
            c, s = math.cos(angle), math.sin(angle)
            verts.append((r_in * c, r_in * s, z))
            verts.append((r_out * c, r_out * s, z))
    return np.array(verts)


def add_hole(spec: mujoco.MjSpec, world: mujoco.MjsBody, cfg: HoleConfig, solref: list[float],
             solimp: list[float]) -> None:
    """The hole block on a mocap body (so each episode can displace it without recompiling).

    Sites: ``hole_entrance`` (centre of the hole at the top face), ``hole_bottom``.
    """
    block = world.add_body(name="hole", mocap=True, pos=[*cfg.nominal_xy, 0.0])
    for k in range(cfg.segments):
        mesh = spec.add_mesh(name=f"hole_wedge_{k}")
        mesh.uservert = wedge_vertices(cfg, k).reshape(-1).tolist()
        block.add_geom(
            name=f"hole_wedge_{k}", type=mujoco.mjtGeom.mjGEOM_MESH, meshname=f"hole_wedge_{k}",
            rgba=[0.3, 0.45, 0.75, 1], contype=CT_SCENE, conaffinity=0, condim=4,
            friction=[cfg.friction, 0.002, 0.0001], solref=solref, solimp=solimp, group=0,
        )
    block.add_site(name="hole_entrance", pos=[0, 0, cfg.depth], size=[0.003, 0, 0], group=3)
    block.add_site(name="hole_bottom", pos=[0, 0, 0], size=[0.003, 0, 0], group=3)
