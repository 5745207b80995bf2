"""Induced velocity of straight vortex segments (Biot–Savart), compiled.

A segment from A to B with circulation Γ (right-handed about A → B) induces at a point P, with
r1 = P − A, r2 = P − B, r0 = B − A and h the distance of P from the segment's line,

    v = Γ/(4π) · (cos θ1 − cos θ2) / h · ê,    (cos θ1 − cos θ2) = r0 · (r1/|r1| − r2/|r2|) / |r0|,
    ê = (r1 × r2) / |r1 × r2|,  |r1 × r2| = |r0| h,

(Katz & Plotkin, *Low-Speed Aerodynamics*, 2nd ed.). A rotor's tip vortices have viscous
cores: the Vatistas profile with n = 2 (Vatistas, Kozel & Mih, Exp. Fluids 11, 1991) replaces the
potential 1/h by h / √(h⁴ + r_c⁴), so the swirl peaks at 2^{−1/2} of the potential value at
h = r_c and vanishes on the axis. With r_c = 0 the segment is potential; a point on its line
(h = 0) gets no velocity from it.

The kernel loops over points and segments: a wake of a few thousand segments seen by a few
hundred lifting-line sections is the rotor's size, and the loop keeps no n × m temporaries.
"""

from __future__ import annotations

import math

import numpy as np

from solver.jit import njit

FOUR_PI = 4.0 * math.pi
# Below this fraction of the segment's length a distance is a coincidence (the point on the
# segment's line, or at an end): the potential velocity there is taken as zero.
COINCIDENCE = 1e-12


@njit(cache=True)
def segment_velocities(points, starts, ends, circulation, core, out):  # pragma: no cover
    """Add to ``out`` (n, 3) the velocity that the segments (m) induce at ``points`` (n, 3).

    ``starts``, ``ends`` (m, 3), ``circulation`` (m,) (m²/s), ``core`` (m,) Vatistas core
    radii r_c (m; 0 for a potential segment).
    """
    n = points.shape[0]
    m = starts.shape[0]
    for i in range(n):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        vx = vy = vz = 0.0
        for k in range(m):
            ax, ay, az = starts[k, 0], starts[k, 1], starts[k, 2]
            bx, by, bz = ends[k, 0], ends[k, 1], ends[k, 2]
            r0x, r0y, r0z = bx - ax, by - ay, bz - az
            r1x, r1y, r1z = px - ax, py - ay, pz - az
            r2x, r2y, r2z = px - bx, py - by, pz - bz
            l0 = math.sqrt(r0x * r0x + r0y * r0y + r0z * r0z)
            l1 = math.sqrt(r1x * r1x + r1y * r1y + r1z * r1z)
            l2 = math.sqrt(r2x * r2x + r2y * r2y + r2z * r2z)
            cx = r1y * r2z - r1z * r2y
            cy = r1z * r2x - r1x * r2z
            cz = r1x * r2y - r1y * r2x
            cross = math.sqrt(cx * cx + cy * cy + cz * cz)  # |r0| h
            tiny = COINCIDENCE * l0
            if l0 == 0.0 or l1 <= tiny or l2 <= tiny or cross <= tiny * l0:
                continue
            h = cross / l0
            cos_diff = (r0x * (r1x / l1 - r2x / l2) + r0y * (r1y / l1 - r2y / l2)
                        + r0z * (r1z / l1 - r2z / l2)) / l0
            rc = core[k]
            # the potential 1/h, or the Vatistas (n = 2) h / √(h⁴ + r_c⁴)
            profile = 1.0 / h if rc == 0.0 else h / math.sqrt(h**4 + rc**4)
            scale = circulation[k] / FOUR_PI * cos_diff * profile / cross
            vx += scale * cx
            vy += scale * cy
            vz += scale * cz
        out[i, 0] += vx
        out[i, 1] += vy
        out[i, 2] += vz


def induced_velocity(points, starts, ends, circulation, core=0.0) -> np.ndarray:
    """Velocity (m/s) that straight vortex segments induce at points.

    Parameters
    ----------
    points
        (n, 3) field points (m).
    starts, ends
        (m, 3) segment ends (m); the circulation turns right-handed about start → end.
    circulation
        (m,) or scalar circulation Γ (m² s⁻¹).
    core
        (m,) or scalar Vatistas core radius r_c ≥ 0 (m); 0 for potential segments.

    Returns
    -------
    ndarray (n, 3)
    """
    p = np.ascontiguousarray(np.atleast_2d(points), dtype=float)
    a = np.ascontiguousarray(np.atleast_2d(starts), dtype=float)
    b = np.ascontiguousarray(np.atleast_2d(ends), dtype=float)
    if p.shape[-1] != 3 or a.shape != b.shape or a.shape[-1] != 3:
        raise ValueError(f"points {p.shape}, starts {a.shape} and ends {b.shape} must be "
                         "(n, 3), (m, 3) and (m, 3) arrays of coordinates")
    m = a.shape[0]
    g = np.ascontiguousarray(np.broadcast_to(np.asarray(circulation, dtype=float), (m,)))
    rc = np.ascontiguousarray(np.broadcast_to(np.asarray(core, dtype=float), (m,)))
    if not (np.all(np.isfinite(p)) and np.all(np.isfinite(a)) and np.all(np.isfinite(b))
            and np.all(np.isfinite(g))):
        raise ValueError("vortex segments and points must be finite")
    if np.any(rc < 0.0) or not np.all(np.isfinite(rc)):
        raise ValueError(f"core radius = {rc.min()!r} m must be finite and ≥ 0")
    out = np.zeros_like(p)
    segment_velocities(p, a, b, g, rc, out)
    return out
