"""Tracking-hole geometry of a bifilar pendulum, and the design helper.

Geometry (hub frame, radial axis e_r = +x, rotor axis +z; Figs. 1 and 5). The support arm's hole
centre O1 lies at R0 from the hub centre, the tuning mass's centre of mass at Rm outward from
its own hole centre O2. With both holes the same shape, arranged point-symmetrically about
the pin, the pin centre stays midway and the tuning mass (which does not rotate relative to the
hub) translates by twice the pin's displacement: its centre of mass runs on a path Γ whose
vertex V (the outermost point, at rest in the centrifugal field) lies at R_v from the hub centre.
Every hole shape here is defined by Γ:

* circle: Γ is a circle of radius r = D − d about (R0 + Rm, 0): the classical bifilar, exactly a
  simple pendulum of length r (Eq. 7, errata 5); R_v = R0 + Rm + r.
* cycloid: the paper's cycloid p(t) = a(t + sin t), a(1 − cos t), vertex radius of curvature 4a,
  opening towards the hub — the tautochrone under uniform gravity.
* epicycloid: a point of a circle of radius b rolling outside a fixed circle of radius a centred on
  the hub, R_v = a + 2b — the tautochrone of the centrifugal field (Denman 1992; errata 6): its
  pin-less tuning order a²/(4b(a+b)) does not depend on amplitude.

The hole curves follow from Γ: the pin-centre path is π = π0 + (Γ − Γ0)/2, the arm's hole is π
offset by d/2 away from the centre of curvature, the tuning mass's hole is that curve reflected
through the pin centre at the vertex. All shapes share the vertex V and the vertex radius of
curvature ρ_v of the circle design, so they have the same small-amplitude order, given by Eq. (7)
including the pins; the design helper sizes ρ_v from Eq. (7) for a target order n.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import astuple, dataclass
from functools import lru_cache
from typing import Any

import numpy as np
from numpy.typing import NDArray

from solver.curves import NurbsCurve, circle, from_function
from studies.analytic import bifilar_order_circular, hole_diameter_for_order
from studies.parameters import ParameterError

SHAPES = ("circle", "cycloid", "epicycloid")
MAX_TANGENT_ANGLE = np.radians(70.0)  # hole curves cover the path up to this tangent angle


@dataclass
class Geometry:
    """Bifilar dimensions (m, kg, kg·m²): arm radius R0, centre-of-mass offset Rm, pin
    diameter d, tuning mass m_b, and per pin mass m_p and polar inertia I_p (two pins)."""

    arm_radius: float
    cm_offset: float
    pin_diameter: float
    tuning_mass: float
    pin_mass: float
    pin_inertia: float

    @classmethod
    def of(cls, p: Any) -> Geometry:
        """The hardware of a parameter set that declares ``arm_radius``, ``cm_offset``,
        ``pin_diameter``, ``tuning_mass``, ``pin_mass`` and ``pin_inertia``."""
        return cls(p.arm_radius, p.cm_offset, p.pin_diameter, p.tuning_mass, p.pin_mass,
                   p.pin_inertia)

    def order_circular(self, hole_diameter: float) -> float:
        """Eq. (7): small-amplitude tuning order of equal circular holes of diameter D."""
        return bifilar_order_circular(1.0, self.arm_radius, self.cm_offset, hole_diameter,
                                      self.pin_diameter, self.tuning_mass, self.pin_mass,
                                      self.pin_inertia)


@dataclass
class Holes:
    """A designed pair of tracking holes and the tuning-mass path they produce.

    ``c1`` is in the hub frame (m, from the hub centre), ``c2`` in the tuning mass's frame (m,
    from its centre of mass in the vertex configuration). ``path(σ)`` gives the centre-of-mass
    path Γ in the hub frame with σ = 0 at the vertex; ``sigma_of_angle(A)`` the path parameter
    where Γ's tangent has turned by A (rad) from the vertex.
    """

    shape: str
    geometry: Geometry
    rho_v: float
    c1: NurbsCurve
    c2: NurbsCurve
    path: Callable[[NDArray], NDArray]
    dpath: Callable[[NDArray], NDArray]
    sigma_of_angle: Callable[[float], float]
    order_linear: float
    hole_diameter: float
    params: dict

    @property
    def vertex(self) -> NDArray:
        return self.path(np.array([0.0]))[0]

    def pin_center(self, sigma: float) -> NDArray:
        g = self.geometry
        pi0 = np.array([g.arm_radius + 0.5 * self.rho_v, 0.0])
        return pi0 + 0.5 * (self.path(np.array([sigma]))[0] - self.vertex)

    def hole_point(self, sigma: NDArray) -> NDArray:
        """Contact point on the arm's hole C1 (hub frame) for path parameter σ."""
        return _offset(self, sigma)


def _unit_left_normal(dp: NDArray) -> NDArray:
    t = dp / np.linalg.norm(dp, axis=-1, keepdims=True)
    return np.stack([-t[..., 1], t[..., 0]], axis=-1)


def _offset(h: Holes, sigma: NDArray) -> NDArray:
    g = h.geometry
    sigma = np.atleast_1d(np.asarray(sigma, dtype=float))
    pi0 = np.array([g.arm_radius + 0.5 * h.rho_v, 0.0])
    pin = pi0 + 0.5 * (h.path(sigma) - h.vertex)
    n = _unit_left_normal(h.dpath(sigma))  # towards the centre of curvature (the hub side)
    return pin - 0.5 * g.pin_diameter * n


def check_geometry(g: Geometry, d_hole: float, tuning_order: float | None = None) -> None:
    """Cross-parameter plausibility of a bifilar; :class:`ParameterError` naming the parameters.

    The pin must be narrower than the arm that carries it and fit in its hole; the hole on the
    support arm (centred at R0) must lie in the arm's outer half, ``D ≤ R0`` (a larger hole
    would cut through the hub); a pin's polar inertia cannot exceed that of a thin tube of the
    same mass and diameter, ``I_p ≤ m_p d²/4``.

    Parameters
    ----------
    g
        The bifilar dimensions.
    d_hole
        Equivalent circular hole diameter D (m), given or sized from ``tuning_order``.
    tuning_order
        The target order D was sized for, if any (named in the message).
    """
    sized = (f" (sized by Eq. 7 for tuning_order = {tuning_order:g})"
             if tuning_order is not None else "")
    if not g.pin_diameter < g.arm_radius:
        raise ParameterError(
            f"pin_diameter = {g.pin_diameter:g} m must be smaller than arm_radius = "
            f"{g.arm_radius:g} m: a pin cannot be wider than the arm that carries it")
    if not d_hole > g.pin_diameter:
        raise ParameterError(f"hole_diameter = {d_hole:g} m{sized} must exceed pin_diameter = "
                             f"{g.pin_diameter:g} m (the pin must fit in the hole)")
    if d_hole > g.arm_radius:
        n_min = g.order_circular(g.arm_radius)
        raise ParameterError(
            f"hole_diameter = {d_hole:g} m{sized} exceeds arm_radius = {g.arm_radius:g} m with "
            f"pin_diameter = {g.pin_diameter:g} m: the tracking hole must lie in the outer half "
            "of the support arm (D ≤ R0), a larger one cuts through the hub"
            + (f"; tuning_order = {tuning_order:g} is unreachable with this arm, need ≥ "
               f"{n_min:.3g}" if tuning_order is not None else ""))
    tube = g.pin_mass * g.pin_diameter**2 / 4.0
    if g.pin_inertia > tube * (1.0 + 1e-12):
        raise ParameterError(
            f"pin_inertia = {g.pin_inertia:g} kg m2 exceeds pin_mass * pin_diameter**2 / 4 = "
            f"{tube:g} kg m2 (pin_mass = {g.pin_mass:g} kg, pin_diameter = "
            f"{g.pin_diameter:g} m), the polar inertia of a thin tube, the most a pin can have")


def design(shape: str, geometry: Geometry, tuning_order: float | None = None,
           hole_diameter: float | None = None) -> Holes:
    """Holes of ``shape`` tuned to ``tuning_order`` (Eq. 7 with pins), or with the circle
    design's ``hole_diameter`` D (m). Raises :class:`ParameterError` for impossible geometry."""
    g = geometry
    if shape not in SHAPES:
        raise ParameterError(f"hole = {shape!r}: must be one of {', '.join(SHAPES)}")
    for name, val in [("arm_radius", g.arm_radius), ("pin_diameter", g.pin_diameter),
                      ("tuning_mass", g.tuning_mass)]:
        if not val > 0:
            raise ParameterError(f"{name} = {val!r}: must be > 0")
    if g.pin_mass < 0 or g.pin_inertia < 0 or g.cm_offset < 0:
        raise ParameterError("pin_mass, pin_inertia and cm_offset must be ≥ 0")
    if (tuning_order is None) == (hole_diameter is None):
        raise ParameterError("give exactly one of hole_diameter and tuning_order")
    if tuning_order is not None:
        if not tuning_order > 0:
            raise ParameterError(f"tuning_order = {tuning_order!r}: must be > 0")
        hole_diameter = hole_diameter_for_order(tuning_order, g.arm_radius, g.cm_offset,
                                                g.pin_diameter, g.tuning_mass, g.pin_mass,
                                                g.pin_inertia)
    d_hole = float(hole_diameter)
    check_geometry(g, d_hole, tuning_order)
    rho = d_hole - g.pin_diameter
    order = g.order_circular(d_hole)
    big_r = g.arm_radius + g.cm_offset
    r_v = big_r + rho
    params: dict = {"vertex_radius": r_v, "vertex_curvature_radius": rho}
    if shape == "circle":
        def path(s):
            return np.stack([big_r + rho * np.cos(s), rho * np.sin(s)], axis=-1)

        def dpath(s):
            return np.stack([-rho * np.sin(s), rho * np.cos(s)], axis=-1)

        def sigma_of_angle(a):
            return a
        c1 = circle(0.5 * d_hole, center=(g.arm_radius, 0.0, 0.0), start_angle=np.pi)
        # O2 sits at R0 + r in the hub frame, the centre of mass at R0 + r + Rm: O2 − cm = −Rm
        c2 = circle(0.5 * d_hole, center=(-g.cm_offset, 0.0, 0.0), start_angle=0.0)
        params["hole_diameter"] = d_hole
    elif shape == "cycloid":
        a = rho / 4.0  # vertex radius of curvature of the cycloid is 4a

        def path(s):
            return np.stack([r_v - a * (1 - np.cos(s)), a * (s + np.sin(s))], axis=-1)

        def dpath(s):
            return np.stack([-a * np.sin(s), a * (1 + np.cos(s))], axis=-1)

        def sigma_of_angle(ang):
            return 2.0 * ang  # the cycloid's tangent turns by t/2
        params["cycloid_a"] = a
        c1, c2 = None, None
        s_max = 2.0 * MAX_TANGENT_ANGLE
    else:
        # The swing's potential is −½Ω²M|Γ + e|², M = m_b + m_p/2: the pins' centres run on
        # half the mass's path, so the field acts as if centred at −e, e = m_p(R0 − Rm)/2M
        # from the hub centre. The tautochrone is the epicycloid about that centre, with the
        # vertex curvature radius ρ of Eq. (7): its small-swing order is Eq. (7)'s exactly.
        shift = g.pin_mass * (g.arm_radius - g.cm_offset) / (
            2.0 * (g.tuning_mass + 0.5 * g.pin_mass))
        r_c = r_v + shift  # the vertex's distance from the field's centre
        n2 = r_c / rho - 1.0  # pin-less order² about that centre (errata 6)
        b = 0.5 * r_c * (1.0 - np.sqrt(n2 / (1.0 + n2)))
        a = r_c - 2.0 * b
        k = (a + b) / b
        # |Γ|² = (a+b)² + b² − 2b(a+b) cos((k−1)φ): the vertex (farthest point) is at
        # (k − 1)φ = π, i.e. φ_v = π b/a, where |Γ| = a + 2b
        phi_v = np.pi * b / a

        def path(s):
            ph = phi_v + s
            x = (a + b) * np.cos(ph) - b * np.cos(k * ph)
            y = (a + b) * np.sin(ph) - b * np.sin(k * ph)
            c, sn = np.cos(phi_v), np.sin(phi_v)  # rotate the vertex onto +x
            return np.stack([c * x + sn * y - shift, -sn * x + c * y], axis=-1)

        def dpath(s):
            ph = phi_v + s
            dx = -(a + b) * np.sin(ph) + b * k * np.sin(k * ph)
            dy = (a + b) * np.cos(ph) - b * k * np.cos(k * ph)
            c, sn = np.cos(phi_v), np.sin(phi_v)
            return np.stack([c * dx + sn * dy, -sn * dx + c * dy], axis=-1)

        def sigma_of_angle(ang):
            return 2.0 * ang / (k + 1.0)  # tangent angle is (k + 1)φ/2 + const
        params.update(epicycloid_a=a, epicycloid_b=b, epicycloid_centre_shift=shift)
        c1, c2 = None, None
        s_max = 2.0 * MAX_TANGENT_ANGLE / (k + 1.0)
    holes = Holes(shape, g, rho, c1, c2, path, dpath, sigma_of_angle, order, d_hole, params)
    if shape != "circle":
        _build_hole_curves(holes, -s_max, s_max)
    return holes


def _check_curvature(h: Holes) -> None:
    """The pin must fit everywhere it rolls: hole radius of curvature > d/2 over the range."""
    eta = np.linspace(0.0, 1.0, 801)
    kappa = np.abs(h.c1.curvature(eta))
    if np.any(kappa * 0.5 * h.geometry.pin_diameter >= 1.0):
        raise ParameterError(
            f"{h.shape} hole: its radius of curvature falls below the pin radius "
            f"({h.geometry.pin_diameter / 2:g} m) within ±{np.degrees(MAX_TANGENT_ANGLE):.0f}° "
            "of the vertex; use a smaller pin or a lower tuning order")


def designed(shape: str, geometry: Geometry, tuning_order: float | None = None,
             hole_diameter: float | None = None) -> Holes:
    """:func:`design`, kept: the same inputs give the same holes object, so that a sweep over
    anything but the hardware designs them once, and validating a parameter set (which
    designs them to check the geometry) leaves them designed for its run."""
    return _designed(shape, tuning_order, hole_diameter, astuple(geometry))


@lru_cache(maxsize=64)
def _designed(shape: str, tuning_order: float | None, hole_diameter: float | None,
              hardware: tuple[float, ...]) -> Holes:
    return design(shape, Geometry(*hardware), tuning_order=tuning_order,
                  hole_diameter=hole_diameter)


def design_from_control_points(points, geometry: Geometry, degree: int = 3,
                               weights=None) -> Holes:
    """Holes for a tuning-mass centre-of-mass path Γ given as a NURBS by its control points.

    ``points`` (n, 2) in the hub frame (m). The outermost point of the curve is its vertex; the
    curve is rotated about the hub centre so that the vertex lies on the bifilar's radial line
    (+x). The vertex must be interior, the curve must turn towards the hub there, and the holes
    built from it must fit the pin. ``geometry.arm_radius`` is replaced by the equivalent hole
    centre R0 = R_v − ρ_v − Rm of the osculating circle design, whose Eq. (7) order is the
    small-amplitude order of this path.
    """
    from scipy.optimize import brentq

    from solver.curves import NurbsCurve

    pts = np.asarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or len(pts) < degree + 1:
        raise ParameterError(f"control points must be an (n, 2) array with n ≥ {degree + 1}")
    if not np.all(np.isfinite(pts)):
        raise ParameterError("control points must be finite numbers")
    if np.any(np.linalg.norm(np.diff(pts, axis=0), axis=1) == 0):
        raise ParameterError("control points must be distinct (repeated points)")
    n = len(pts)
    knots = np.concatenate([np.zeros(degree), np.linspace(0, 1, n - degree + 1), np.ones(degree)])
    try:
        spline = NurbsCurve(degree, knots, pts, weights=weights)
    except ValueError as exc:
        raise ParameterError(f"control points do not make a valid curve: {exc}") from None
    eta = np.linspace(0, 1, 4001)
    p = spline.point(eta)[:, :2]
    iv = int(np.argmax(np.linalg.norm(p, axis=1)))
    if iv in (0, len(eta) - 1):
        raise ParameterError("the path's outermost point (vertex) must lie inside the curve")
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(lambda e: -np.linalg.norm(spline.point(e)[:2]),
                          bounds=(eta[iv - 1], eta[iv + 1]), method="bounded",
                          options={"xatol": 1e-13})
    ev = float(res.x)
    pv = spline.point(ev)[:2]
    ang = np.arctan2(pv[1], pv[0])
    c, s_ = np.cos(-ang), np.sin(-ang)
    rot = np.array([[c, -s_], [s_, c]])
    d1 = spline.derivatives(ev, 1)[1][:2] @ rot.T
    sign = 1.0 if d1[1] > 0 else -1.0  # orient σ so that the vertex tangent is +y

    def path(sg):
        e = np.clip(ev + sign * np.asarray(sg, dtype=float), 0.0, 1.0)
        return spline.point(e)[..., :2] @ rot.T

    def dpath(sg):
        e = np.clip(ev + sign * np.asarray(sg, dtype=float), 0.0, 1.0)
        return sign * spline.derivatives(e, 1)[1][..., :2] @ rot.T

    kappa = float(spline.curvature(ev)) * (-1.0 if sign < 0 else 1.0)
    if not kappa > 0:
        raise ParameterError("the path must curve towards the hub at its vertex")
    rho = 1.0 / kappa
    r_v = float(np.linalg.norm(pv))
    g = geometry
    r0 = r_v - rho - g.cm_offset
    if not r0 > 0:
        raise ParameterError(f"path vertex at {r_v:g} m with radius of curvature {rho:g} m "
                             f"leaves no room for the arm (R0 = {r0:g} m ≤ 0)")
    g = Geometry(r0, g.cm_offset, g.pin_diameter, g.tuning_mass, g.pin_mass, g.pin_inertia)

    def tangent_turn(sg):
        d = dpath(np.array([sg]))[0]
        return np.arctan2(-d[0], d[1])  # angle from the vertex tangent (+y)

    s_lo, s_hi = sorted([-ev * sign, (1.0 - ev) * sign])  # σ range covered by the curve

    def sigma_of_angle(a):
        f = lambda sg: tangent_turn(sg) - a  # noqa: E731
        hi = s_hi if a > 0 else s_lo
        if np.sign(f(hi)) == np.sign(f(0.0)):
            raise ParameterError(f"amplitude {np.degrees(a):g} degree lies beyond the end "
                                 "of the path")
        return brentq(f, 0.0, hi, xtol=1e-14) if a != 0 else 0.0

    d_hole = rho + g.pin_diameter
    holes = Holes("nurbs", g, rho, None, None, path, dpath, sigma_of_angle,
                  g.order_circular(d_hole), d_hole,
                  {"vertex_radius": r_v, "vertex_curvature_radius": rho, "arm_radius": r0})
    _build_hole_curves(holes, s_lo, s_hi)
    return holes


def _build_hole_curves(holes: Holes, s_lo: float, s_hi: float) -> None:
    """Arm hole C1 (offset of the pin path) and mass hole C2 (its reflection) as NURBS."""
    g = holes.geometry
    pi0 = np.array([g.arm_radius + 0.5 * holes.rho_v, 0.0])
    v0 = holes.vertex

    def arm_hole(s):
        return _offset(holes, s)

    def mass_hole(s):  # point reflection through the pin centre, in the mass's frame
        return 2.0 * pi0 - _offset(holes, s) - v0

    holes.c1 = from_function(arm_hole, s_lo, s_hi, n_points=401, degree=5)
    holes.c2 = from_function(mass_hole, s_lo, s_hi, n_points=401, degree=5)
    _check_curvature(holes)
