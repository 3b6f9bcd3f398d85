"""How deep a touch-down of the search sinks, from the geometry alone (no simulation).

The peg, tilted by the search tilt, touches down with its lowest rim point inside the hole. Its
lower face is a disc of the peg's radius, tilted so that the rim point is its lowest point; it
comes to rest on the hole's edge where the edge lies under the face closest to the rim point
(along the lean), so the rim point sinks ``(a - x_edge) tan(tilt)`` below the surface, where
``a`` is the rim point's position along the lean from the hole's axis and ``x_edge`` the
furthest-forward point of the hole's edge circle that lies under the face disc. If the whole
disc lies over the hole the peg falls in (three-point contact, printed as ``in``).

Prints the sink [mm] on a grid of rim positions (``a`` along the lean, ``s`` sideways, from the
hole's axis) and the area of the rim positions that sink deeper than the drop threshold::

    python benchmarks/touchdown_geometry.py
    python benchmarks/touchdown_geometry.py --threshold 0.3 --tilt-deg 6
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from vgs.config import profile


def sink_mm(a: float, s: float, peg_radius: float, hole_radius: float, tilt: float,
            edge: np.ndarray) -> float:
    """Sink of the lowest rim point [mm] at ``(a, s)`` [mm] from the hole's axis (``a`` along
    the lean); ``inf`` when the face falls in, 0 when the rim point lands on the surface."""
    if a * a + s * s >= hole_radius ** 2:
        return 0.0
    cx, cy = a - peg_radius, s  # the face disc's centre: one radius behind the rim point
    under = (edge[0] - cx) ** 2 + (edge[1] - cy) ** 2 <= peg_radius ** 2
    if not under.any():
        return math.inf
    return float((a - edge[0][under].max()) * math.tan(tilt))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--tilt-deg", type=float, default=None,
                    help="search tilt [deg] (default: the paper profile's)")
    ap.add_argument("--threshold", type=float, default=None,
                    help="drop threshold [mm] (default: the paper profile's)")
    args = ap.parse_args(argv)
    cfg = profile("paper")
    tilt = math.radians(args.tilt_deg if args.tilt_deg is not None
                        else cfg.assembly.search_tilt_deg)
    threshold = (args.threshold if args.threshold is not None
                 else cfg.assembly.drop_threshold * 1000)
    r = 500 * cfg.cell.peg.diameter
    big = r + 500 * cfg.cell.hole.clearance
    th = np.linspace(0.0, 2 * math.pi, 20001)
    edge = np.stack([big * np.cos(th), big * np.sin(th)])
    sides = (0.0, 3.0, 6.0, 9.0, 12.0)
    print(f"peg radius {r:.1f} mm, hole radius {big:.1f} mm, tilt {math.degrees(tilt):.1f} deg")
    print("sink [mm] of the lowest rim point; rows: a along the lean [mm], columns: s sideways")
    print("   a  " + "".join(f"{f's={s:g}':>8s}" for s in sides))
    for a in (-12.0, -9.0, -6.0, -3.0, 0.0, 3.0, 6.0, 9.0, 12.0, 14.0):
        cells = []
        for s in sides:
            d = sink_mm(a, s, r, big, tilt, edge)
            cells.append(f"{'in':>8s}" if math.isinf(d) else f"{d:8.2f}")
        print(f"{a:+5.0f} " + "".join(cells))
    step = 0.25
    grid = np.arange(-big, big, step)
    deep = sum(1 for a in grid for s in grid
               if sink_mm(a, s, r, big, tilt, edge) > threshold) * step * step
    print(f"rim positions sinking deeper than {threshold:g} mm: {deep:.0f} mm^2, "
          f"{deep / (math.pi * big * big):.0%} of the hole's {math.pi * big * big:.0f} mm^2")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
