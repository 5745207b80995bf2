"""Small models and elements shared by several test modules (written once, here).

* :class:`Lag` — a first-order element declared outside ``solver/``: τ ẋ + x = X(q) with X the
  global x coordinate of a body's reference point, pushing back on it with −k x along x.
* :class:`AddedMass` — an element with acceleration-dependent force (apparent mass along a
  body-fixed direction), declared outside ``solver/``.
* :func:`rod_pendulum` — a slender rod hinged at one end, with an extra element attached.
* :func:`rodrigues` — a rotation matrix independent of :mod:`solver.rotations`.
* :func:`rolling_disc` — a disc rolling without slip inside a circular track.
* :func:`pendulum`, :func:`pendulum_period` — a slender rod pendulum and its exact period.
* :func:`oscillator` — a point mass on a spring and damper.
* :func:`feedback_oscillator` — a disc on a revolute with delayed feedback damping.
* :func:`heavy_top` — the heavy top of Brüls, Cardona & Arnold (2012).
* :func:`zero_crossings`, :func:`fitted_roots` — zeros of a spline through samples, roots of
  the one-step recurrence fitted to a free response.
* :func:`period_from_crossings` — a period from same-direction zero crossings.
* :func:`collar_on_cycloid` — a collar sliding on a hanging cycloid.
* :func:`hub_rolling_disc` — a disc rolling in a hole of a spinning hub, with rolling
  resistance (a bifilar pin in miniature: curve joint, rolling, damper and a driver).
* :func:`fd4`, :func:`dense` — fourth-order central differences, triplets to a dense matrix.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.special import ellipk

from solver.bodies import PointMass, RigidBody, ground, spinning
from solver.curve_joints import ArcLength, CurveSliding, Rolling
from solver.curves import circle, cycloid
from solver.element import Element, ElementSet
from solver.forces import AppliedLoad, Gravity, RelativeRotation, Spring
from solver.joints import Revolute, Spherical
from solver.model import Model
from solver.state import FIRST, StateBlock

G = 9.81  # m/s²


def rodrigues(axis, angle):
    """Rotation of ``angle`` (rad) about ``axis`` (Rodrigues; independent of solver.rotations)."""
    n = np.asarray(axis, dtype=float)
    n = n / np.linalg.norm(n)
    k = np.array([[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]])
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


@dataclass(eq=False)
class Lag(Element):
    """τ ẋ + x = X (X: global x of ``body``'s reference point, a rigid body's centre of mass
    or a point mass); force −k x along global x on it. τ (s), k = ``gain`` (N/m)."""

    name: str
    body: Element
    tau: float
    gain: float

    def states(self) -> list[StateBlock]:
        return [StateBlock(self, FIRST, 1, initial=0.0, mass=np.array([[self.tau]]), units="m",
                           long_name="lagged horizontal position")]


class LagSet(ElementSet):
    """All lags at once: f_x = X − x on the state rows, −k x on the bodies' x rows."""

    nonconservative = True

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        self.ix = np.array([system.offset[e] for e in elements])
        self.iq = np.array([system.offset[e.body] for e in elements])
        self.k = np.array([e.gain for e in elements])
        self.force_idx = np.concatenate([self.ix, self.iq])
        self.fq_rows = np.concatenate([self.ix, self.ix, self.iq])
        self.fq_cols = np.concatenate([self.iq, self.ix, self.ix])
        j = len(elements)
        self._dq = np.concatenate([np.ones(j), -np.ones(j), -self.k])

    def force(self, q, v, t):
        x = q[self.ix]
        return np.concatenate([q[self.iq] - x, -self.k * x])

    def force_jacobians(self, q, v, t):
        return self._dq, np.zeros(0)


Lag.set_class = LagSet


@dataclass(eq=False)
class AddedMass(Element):
    """Apparent mass m_a (kg) along the body-fixed director d_k of a rigid body, at its centre:
    f = −m_a d_k (d_k·ẍ), the reaction of a fluid that is accelerated with the body's normal
    motion (a flat plate's added mass). Needs the accelerations: ``uses_acceleration``."""

    name: str
    body: Element
    mass: float
    director: int = 2  # k: 1, 2 or 3


class AddedMassSet(ElementSet):
    nonconservative = True
    uses_acceleration = True

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        o = np.array([system.offset[e.body] for e in elements])
        self.ix = o[:, None] + np.arange(3)  # centre (J, 3)
        self.idk = o[:, None] + 3 * np.array([e.director for e in elements])[:, None] \
            + np.arange(3)  # d_k (J, 3)
        self.m = np.array([e.mass for e in elements])
        self.force_idx = self.ix.ravel()
        rows = np.repeat(self.ix, 3, axis=1).ravel()
        self.fq_rows, self.fq_cols = rows, np.tile(self.idk, (1, 3)).ravel()
        self.fa_rows, self.fa_cols = rows, np.tile(self.ix, (1, 3)).ravel()

    def force(self, q, v, t, a):
        d, acc = q[self.idk], a[self.ix]
        return (-self.m[:, None] * d * np.einsum("ij,ij->i", d, acc)[:, None]).ravel()

    def force_jacobians(self, q, v, t, a):
        d, acc = q[self.idk], a[self.ix]
        da = np.einsum("ij,ij->i", d, acc)
        jq = -self.m[:, None, None] * (da[:, None, None] * np.eye(3) + d[:, :, None]
                                       * acc[:, None, :])
        return jq.ravel(), np.zeros(0)

    def acceleration_jacobian(self, q, v, t, a):
        d = q[self.idk]
        return (-self.m[:, None, None] * d[:, :, None] * d[:, None, :]).ravel()


AddedMass.set_class = AddedMassSet


def rod_pendulum(mass, length, theta0, extra, g=G):
    """A uniform slender rod (``mass`` kg, ``length`` m; axis d1) hinged at the origin about z,
    started ``theta0`` rad from hanging down, under gravity −g y, with ``extra(rod)`` (an
    element built on the rod) added. Returns (model, rod)."""
    j_cm = mass * length**2 / 12.0
    ground_ = ground()
    c = np.array([0.5 * length * np.sin(theta0), -0.5 * length * np.cos(theta0), 0.0])
    rod = RigidBody("rod", mass, inertia=(0.0, j_cm, j_cm), position=c,
                    orientation=rodrigues((0, 0, 1), theta0 - np.pi / 2))
    model = Model()
    model.add(ground_, rod, Revolute("pivot", ground_, rod, point=(0, 0, 0), axis=(0, 0, 1)),
              Gravity((0.0, -g, 0.0)), extra(rod))
    return model, rod


def rolling_disc(theta0, R=1.0, r=0.25, m=3.0, gravity=True):
    """A uniform disc (radius r, mass m) rolling inside a circular track (radius R) carried by
    ground, started θ0 (rad) up the track.

    A massless link slides on the track with the Frenet triad (t, n, b) locked to it; the disc
    centre is at contact + r n (n = inward normal), revolute to the link about z; rolling
    ṡ + r (ω_disc − ω_link)·z = 0 (side +1). Gravity −G along y.

    Returns (model, joint, arc, roll, link, disc).
    """
    g0 = ground()
    track = circle(R, start_angle=0.5 * np.pi)  # lowest point at η = 1/2
    contact = R * np.array([np.sin(theta0), -np.cos(theta0), 0.0])
    frame = rodrigues((0.0, 0.0, 1.0), theta0)  # columns t, n, b at the contact
    centre = contact + r * frame[:, 1]
    link = RigidBody("link", 0.0, position=contact, orientation=frame)
    ip = 0.5 * m * r * r
    disc = RigidBody("disc", m, inertia=(0.5 * ip, 0.5 * ip, ip), position=centre,
                     orientation=frame)
    j = CurveSliding("slide", g0, track, link, rotation=True)
    arc = ArcLength(j)
    roll = Rolling("roll", arc, disc, link, r, side=1)
    model = Model()
    model.add(g0, link, disc, j, Revolute("rev", link, disc, point=centre, axis=(0.0, 0.0, 1.0)),
              arc, roll)
    if gravity:
        model.add(Gravity((0.0, -G, 0.0)))
    return model, j, arc, roll, link, disc


def pendulum(theta0, m=1.0, length=1.0):
    """Slender rod (m, L) on a revolute about z at its end, released from rest at θ0 from −y."""
    g0 = ground()
    c = np.array([np.sin(theta0), -np.cos(theta0), 0.0]) * length / 2
    rod = RigidBody("rod", m, inertia=(m * length**2 / 12, 0.0, m * length**2 / 12),
                    position=c, orientation=rodrigues((0, 0, 1), theta0))
    mod = Model()
    mod.add(g0, rod, Revolute("pin", g0, rod, point=(0, 0, 0), axis=(0, 0, 1)),
            Gravity((0, -G, 0)))
    return mod


def pendulum_period(theta0, m=1.0, length=1.0):
    """T = 4 K(k) / ω0 with k = sin(θ0/2), ω0² = m g L/2 / (m L²/3) (K of parameter k²)."""
    w0 = np.sqrt(m * G * length / 2 / (m * length**2 / 3))
    return 4.0 * ellipk(np.sin(theta0 / 2) ** 2) / w0


def oscillator(m=1.0, k=1.0, c=0.0, v0=1.0):
    """Point mass on a spring (and damper) to ground at its initial position, no gravity."""
    p = PointMass("m", m, velocity=(v0, 0.0, 0.0))
    mod = Model()
    mod.add(p, Spring("s", None, p, point=(0, 0, 0), stiffness=k, damping=c))
    return mod


def feedback_oscillator(moment: float, feedback: bool, spin: float = 0.0):
    """Disc on a revolute, J φ̈ + c φ̇ + k φ = M cos Ωt (τ = 2π/Ω = 1 s), ω0 = 0.27 Ω and 1 %
    damping (a rotor's lag mode), with the delayed feedback tuned for damping ratio 0.5 at ω0
    (a = bω0 sin ω0τ / (1 − cos ω0τ), b = ζ J ω0: no stiffness change at ω0)."""
    jz, tau = 1.0, 1.0
    w0 = 0.27 * 2 * np.pi / tau
    k, c = jz * w0**2, 2 * 0.01 * jz * w0
    b = 0.5 * jz * w0 if feedback else 0.0
    th = w0 * tau
    a = b * w0 * np.sin(th) / (1 - np.cos(th))
    n = np.array([0.0, 0.0, 1.0])
    g0 = ground()
    disc = RigidBody("disc", 1.0, inertia=(0.5, 0.5, jz), angular_velocity=spin * n)
    mod = Model()
    mod.add(g0, disc, Revolute("pin", g0, disc, point=(0, 0, 0), axis=n),
            RelativeRotation("lag", None, disc, axis=n, stiffness=k, damping=c,
                             delay=tau, delayed_stiffness=a, delayed_damping=b))
    if moment:
        mod.add(AppliedLoad("m", disc, moment=lambda t: (0.0, 0.0,
                                                         moment * np.cos(2 * np.pi * t / tau))))
    return mod, (jz, c, k, a, b, tau)


def fd4(f, q, i, h):
    """Fourth-order central difference of f along coordinate i (error O(h⁴) + eps/h)."""
    e = np.zeros_like(q)
    e[i] = h
    return (-f(q + 2 * e) + 8 * f(q + e) - 8 * f(q - e) + f(q - 2 * e)) / (12 * h)


def dense(vals, rows, cols, shape):
    """The dense matrix of ``shape`` with the triplets ``vals`` summed at (rows, cols)."""
    a = np.zeros(shape)
    np.add.at(a, (rows, cols), vals)
    return a


# heavy top of Brüls, Cardona & Arnold (2012): mass, inertia, centre of mass, spin, gravity
TOP_M = 15.0
TOP_J = np.diag([0.234375, 0.46875, 0.234375])
TOP_X = np.array([0.0, 1.0, 0.0])
TOP_W = np.array([0.0, 150.0, -4.61538])
TOP_G = np.array([0.0, 0.0, -9.81])


def heavy_top():
    """Brüls, Cardona & Arnold (2012): body frame = global frame at t = 0, so the body angular
    velocity equals the global one; centre-of-mass velocity ω × x."""
    g0 = ground()
    top = RigidBody("top", TOP_M, inertia=np.diag(TOP_J), position=TOP_X,
                    velocity=np.cross(TOP_W, TOP_X), angular_velocity=TOP_W)
    mod = Model()
    mod.add(g0, top, Spherical("tip", g0, top, point=(0, 0, 0)), Gravity(TOP_G))
    return mod, top


def zero_crossings(t, y, t_min=0.0):
    """Zeros of the C² cubic spline through (t, y) (interpolation error O(h⁴))."""
    r = CubicSpline(t, y).roots(extrapolate=False)
    return r[r > t_min]


def fitted_roots(seqs, order):
    """Roots of the linear recurrence x_{n+p} = Σ c_k x_{n+p-k} fitted (least squares) to the
    position and velocity sequences: the eigenvalues of the one-step amplification matrix
    (Cayley–Hamilton), measured from the simulated free response only."""
    rows, rhs = [], []
    for s in seqs:
        for n in range(len(s) - order):
            rows.append(s[n : n + order][::-1])
            rhs.append(s[n + order])
    coef = np.linalg.lstsq(np.array(rows), np.array(rhs), rcond=None)[0]
    return np.roots(np.concatenate([[1.0], -coef]))


def period_from_crossings(t, x):
    """Period of an oscillation x(t) about zero: the mean of the least-squares slopes of its
    upward and of its downward crossing times (each located on the spline through the samples,
    error O(h⁴)) against their index. Same-direction crossings are one period apart, so an
    oscillation that is not symmetric about zero gives no bias."""
    tc = zero_crossings(t, x)
    return float(np.mean([np.polyfit(np.arange(len(tc[k::2])), tc[k::2], 1)[0]
                          for k in (0, 1)]))


def collar_on_cycloid(theta0, a=0.25, mass=2.0, inertia=0.02, g=G):
    """A collar (mass, polar inertia) sliding on the hanging cycloid of constant ``a`` (lowest
    point (0, −2a), :func:`solver.curves.cycloid`) under gravity −g along y, turning with the
    curve's tangent, released at rest with the tangent θ0 (rad) from the horizontal (cycloid
    parameter t = 2θ0). Returns the model."""
    g0 = ground()
    t = 2.0 * theta0
    pos = np.array([a * (t + np.sin(t)), -a * (1.0 + np.cos(t)), 0.0])
    collar = RigidBody("collar", mass, inertia=(0.5 * inertia, 0.5 * inertia, inertia),
                       position=pos, orientation=rodrigues((0.0, 0.0, 1.0), theta0))
    joint = CurveSliding("slide", g0, cycloid(a), collar, rotation=True)
    model = Model()
    model.add(g0, collar, joint, ArcLength(joint), Gravity((0.0, -g, 0.0)))
    return model


def hub_rolling_disc(theta0, omega=27.0, arm=0.4, R=0.05, r=0.015, m=1.0, damping=0.0):
    """A bifilar pin in miniature: a disc (radius r, mass m) rolling inside a circular hole
    (radius R) of a hub spun at a prescribed Ω (rad/s) about z, the hole's centre ``arm`` (m)
    from the axis, with rolling resistance ``damping`` (N·m·s/rad, torque per relative angular
    rate between the disc and its contact link). No gravity: the centrifugal field swings the
    disc about the hole's outermost point.

    A massless link slides on the hole with the Frenet triad (t, n, b) locked to it; the disc
    centre is at contact + r n, revolute to the link about z; rolling ṡ + r (ω_disc − ω_link)·z
    = 0. Released at rest relative to the hub with the contact θ0 (rad) round the hole from
    its outermost point (every body moving with the hub: v = Ω ẑ × x, ω = Ω ẑ, so the rolling
    and sliding relations hold at t = 0).

    Returns (model, hub, disc).
    """
    z = np.array([0.0, 0.0, 1.0])
    w = omega * z
    hub = spinning("hub", omega)
    centre = np.array([arm, 0.0, 0.0])
    hole = circle(R, center=centre, start_angle=np.pi)  # seam innermost, outermost at η = 1/2
    contact = centre + R * np.array([np.cos(theta0), np.sin(theta0), 0.0])
    frame = rodrigues(z, theta0 + 0.5 * np.pi)  # columns t (counter-clockwise), n (inward), z
    disc_c = contact + r * frame[:, 1]
    link = RigidBody("link", 0.0, position=contact, orientation=frame,
                     velocity=np.cross(w, contact), angular_velocity=w)
    ip = 0.5 * m * r * r
    disc = RigidBody("disc", m, inertia=(0.5 * ip, 0.5 * ip, ip), position=disc_c,
                     orientation=frame, velocity=np.cross(w, disc_c), angular_velocity=w)
    j = CurveSliding("slide", hub, hole, link, rotation=True)
    arc = ArcLength(j)
    model = Model()
    model.add(hub, link, disc, j, Revolute("rev", link, disc, point=disc_c, axis=z), arc,
              Rolling("roll", arc, disc, link, r, side=1))
    if damping > 0.0:
        model.add(RelativeRotation("rolling_resistance", link, disc, axis=z, damping=damping))
    return model, hub, disc
