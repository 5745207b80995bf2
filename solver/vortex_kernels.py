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

    With c = r1 × r2 (|c| = |r0| h) the velocity is
    Γ/(4π) · r0·(r1/|r1| − r2/|r2|) · c / (|r0|² √(h⁴ + r_c⁴)) (the potential's h² for
    √(h⁴ + r_c⁴) when r_c = 0): the segment's own constants (r0, |r0|², Γ/4π, r_c⁴) are
    found once, and a pair costs three square roots and three divisions.
    """
    n = points.shape[0]
    m = starts.shape[0]
    seg = np.empty((m, 7))  # r0, |r0|², Γ/(4π), r_c⁴
    for k in range(m):
        r0x = ends[k, 0] - starts[k, 0]
        r0y = ends[k, 1] - starts[k, 1]
        r0z = ends[k, 2] - starts[k, 2]
        seg[k, 0], seg[k, 1], seg[k, 2] = r0x, r0y, r0z
        seg[k, 3] = r0x * r0x + r0y * r0y + r0z * r0z
        seg[k, 4] = circulation[k] / FOUR_PI
        seg[k, 5] = core[k] ** 4
        seg[k, 6] = COINCIDENCE * COINCIDENCE * seg[k, 3]  # (the coincidence distance)²
    for i in range(n):
        px, py, pz = points[i, 0], points[i, 1], points[i, 2]
        vx = vy = vz = 0.0
        for k in range(m):
            l0sq = seg[k, 3]
            tiny = seg[k, 6]
            r1x, r1y, r1z = px - starts[k, 0], py - starts[k, 1], pz - starts[k, 2]
            r2x, r2y, r2z = px - ends[k, 0], py - ends[k, 1], pz - ends[k, 2]
            s1 = r1x * r1x + r1y * r1y + r1z * r1z
            s2 = r2x * r2x + r2y * r2y + r2z * r2z
            cx = r1y * r2z - r1z * r2y
            cy = r1z * r2x - r1x * r2z
            cz = r1x * r2y - r1y * r2x
            csq = cx * cx + cy * cy + cz * cz  # |r0|² h²
            if l0sq == 0.0 or s1 <= tiny or s2 <= tiny or csq <= tiny * l0sq:
                continue
            i1 = 1.0 / math.sqrt(s1)
            i2 = 1.0 / math.sqrt(s2)
            dot = (seg[k, 0] * (r1x * i1 - r2x * i2) + seg[k, 1] * (r1y * i1 - r2y * i2)
                   + seg[k, 2] * (r1z * i1 - r2z * i2))
            hsq = csq / l0sq
            # the potential 1/h over |c|, or the Vatistas (n = 2) h / √(h⁴ + r_c⁴) over |c|
            root = hsq if seg[k, 5] == 0.0 else math.sqrt(hsq * hsq + seg[k, 5])
            scale = seg[k, 4] * dot / (l0sq * root)
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
