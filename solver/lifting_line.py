"""Lifting-line aerodynamics on a beam or a body: Peters finite-state airfoil sections.

A :class:`LiftingLine` puts aerodynamic sections along a support — a :class:`~solver.beams.Beam`
(arc length s) or a rigid or prescribed body (sections along its local d1 axis, s = local d1
coordinate) — at the Gauss points of each element (split at the ends of the aerodynamic span
and at the tip-loss station). Each section reads the support's motion (positions, directors,
their rates and accelerations interpolated with the beam's shape functions), computes its
airloads and gives them back as consistent nodal loads (∫ N_a · load ds), so that the work the
air does is the work the integrators book.

Section frame and kinematics. With d1, d2, d3 the support's section directors (d1 along the
span, d2 chordwise towards the leading edge, d3 up: the convention of :mod:`studies.uh60a`),
the zero-lift line is turned by θ − α0 (``pitch`` minus ``zero_lift_angle``) about d1, nose up:
e_c = cos(θ − α0) d2 + sin(θ − α0) d3 (towards the leading edge), e_n = −sin(θ − α0) d2 +
cos(θ − α0) d3, e_s = d1. A chordwise point at ξ (m, towards the leading edge) from the
reference line is P(ξ) = x + ξ e_c, with the quarter chord at ξ_qc (``quarter_chord``), the
mid-chord at ξ_qc − b/2 and the three-quarter chord at ξ_qc − b (b = c/2, the semichord).
The air velocity relative to P is W(ξ) = V∞ + v_w + v_i(x) − Ṗ(ξ), with V∞ the free stream
(:class:`~solver.air.FlightCondition`), v_w a prescribed wind at the section (a function of
time: :class:`~solver.section_wind.PeriodicWind`, e.g. a rotor's vortex wake, if given) and
v_i = −λ Ω R ẑ the induced velocity of the rotor inflow model at the section
(:class:`~solver.inflow.DynamicInflow`, if given). Its chordwise
speed is u = −W(mid)·e_c and its normal components w(ξ) = W(ξ)·e_n: w0 at the mid-chord,
w34 at the three-quarter chord, and w1 = b ė_c·e_n (b times the nose-up pitch rate), so that
w(x) = w0 + w1 x/b along the chord (x aft of the mid-chord).

Peters, Karunamoorthy & Cao (1995): the wake's induced flow λ0 = ½ bᵀλ follows
A λ̇ + (u/b) λ = c ẇ34 (:func:`solver.airfoil.peters_matrices`). The forcing is a rate, ẇ34,
which the solver's first-order states cannot take (their right-hand sides are functions of
(q, v, x, t)); the states used here are μ = λ − A⁻¹c w34, for which the same equations read

    A μ̇ = −(u/b) (μ + A⁻¹c w34),      λ0 = ½ bᵀμ + κ w34,   κ = ½ bᵀA⁻¹c,

identical to Peters' for any motion, including a varying u (κ → ½ as N grows: 0.4872 at
N = 4, 0.49995 at N = 8; 1 − κ is the model's lift fraction right after a step in w34, Wagner's
½). In steady flow μ = −A⁻¹c w34, so λ = 0 and the lift is the full quasi-steady lift.
Loads per unit span:

* circulatory (at the quarter chord), Kutta–Joukowski with the bound circulation
  Γ = a b (w34 − λ0) (a the lift slope, 2π for thin-airfoil theory): F = ρ Γ (u e_n + (w34 −
  λ0) e_c), normal to the effective relative velocity — its forward tilt is the leading-edge
  suction; with a rotor inflow in W it is the induced drag. Zero outboard of ``lift_end``
  (tip loss).
* profile drag (at the quarter chord): ½ ρ c c_d0 |W⊥| W⊥, W⊥ the part of W(ξ_qc) normal to
  the span.
* apparent mass (Theodorsen's non-circulatory terms in Peters' form): L_nc = π ρ b² ẇ0 along
  e_n at the mid-chord and M_nc = −π ρ b² (½ u w1 + (b/8) ẇ1) about e_s (nose up), with ẇ0,
  ẇ1 the rates of w0, w1 along the motion; they hold the support's accelerations (the set
  ``uses_acceleration``). The rate of the induced velocity is left out of ẇ0 (inflow states
  evolve on the rotor's time scale, ≥ 10 times slower than a section's chord crossing).

A force F at P(ξ) does virtual work F·(δx + ξ δe_c): generalized forces F on x, ξ cos F on d2
and ξ sin F on d3 (exact for directors); a moment m e_s acts as director forces ½ m e_s × d_i.
With ``inflow``, each section adds its share of the rotor's load to the inflow states:
W(ξ, η) (F·ẑ) ds / (ρ Ω² R⁴) (:meth:`~solver.inflow.DynamicInflow.load_weights`).

Jacobians: the airloads of a section are one compiled kernel
(:func:`solver.aero_kernels.section_loads`, numba) that runs on real numbers (the forces and
the ``airloads`` details, from the same call) and on complex numbers; its derivatives by every
local input (12 coordinates, 12 rates, 12 accelerations, the section's states and the inflow
states) come from complex steps, one input at a time in one compiled loop
(:func:`~solver.aero_kernels.local_jacobian`) — exact to roundoff, from the one formula. The
Newton matrix needs only their sum weighted by its scheme (∂/∂q + γ/(βh) ∂/∂q̇ + …): one
complex step moves a coordinate, its rate and its acceleration together and gives that sum
at a third of the evaluations (:meth:`LiftingLineSet.force_tangent`). The
inflow shapes and load weights, which depend on the section's position only, are evaluated by
the inflow model in NumPy at the real positions and at the three stepped ones, and passed in.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from solver import aero_kernels
from solver.air import FlightCondition
from solver.airfoil import DEFAULT_STATES, peters_matrices
from solver.beams import Beam, lagrange
from solver.bodies import PrescribedBody, RigidBody
from solver.element import Element, ElementSet
from solver.state import FIRST, StateBlock

Array = NDArray[np.float64]
Profile = float | Callable[[Array], ArrayLike]
STARTS = ("steady", "rest")
COMPLEX_STEP = 1e-30
# decay rate of the wake states uses √(u² + u_floor²): finite in reversed or stopped flow
FLOOR_FRACTION = 1e-3


@dataclass(eq=False)
class LiftingLine(Element):
    """Aerodynamic sections along a beam or a body.

    Parameters
    ----------
    name
        Unique name.
    support
        The :class:`~solver.beams.Beam` (sections at arc length s) or the rigid or prescribed
        body (sections on its local d1 axis, s the local coordinate, m) that carries the line.
    flight
        Free stream and air density.
    chord
        Chord c (m) > 0: a number or a function of s (array → array).
    span
        (s0, s1): the aerodynamic extent (m); default the whole beam (required for a body).
    lift_slope
        Lift-curve slope a (1/rad), in (0, 10]; 2π is thin-airfoil theory.
    zero_lift_angle
        α0 (rad), |α0| ≤ 0.2: the zero-lift line is turned by −α0 from the chord.
    drag
        Profile drag coefficient c_d0, in [0, 0.1].
    pitch
        Angle θ (rad) of the chord line from the support's d2 about d1, nose up (the
        aerodynamic twist where it differs from the beam's section frames), |θ| ≤ π/2.
    quarter_chord
        Chordwise position of the quarter chord from the support's reference line (m,
        positive towards the leading edge).
    lift_end
        Arc length (m) beyond which the circulatory lift is zero (tip loss: B R minus the
        support's root radius); default none.
    wake_states
        Peters states N per section (1…10; 0: quasi-steady, the wake's lag left out).
    inflow
        Rotor inflow model whose induced velocity the sections see and whose states they
        drive; ``None``: only the free stream.
    wind
        A prescribed velocity (m/s) at each section, a function of time (e.g.
        :class:`~solver.section_wind.PeriodicWind`: called with t, returns (n_sections, 3)),
        added to the free stream; ``None``: none.
    points
        Gauss points (sections) per segment, 1…8.
    start
        ``"steady"``: the wake states start at their steady value for the initial motion;
        ``"rest"``: at zero (an impulsive start: Wagner's problem).
    """

    name: str
    support: Beam | RigidBody | PrescribedBody
    flight: FlightCondition
    chord: Profile
    span: tuple[float, float] | None = None
    lift_slope: Profile = 2.0 * math.pi
    zero_lift_angle: Profile = 0.0
    drag: Profile = 0.0
    pitch: Profile = 0.0
    quarter_chord: Profile = 0.0
    lift_end: float | None = None
    wake_states: int = DEFAULT_STATES
    inflow: object | None = None
    wind: Callable[[float], Array] | None = None
    points: int = 4
    start: str = "steady"
    sections: dict = field(init=False, repr=False)

    def __post_init__(self) -> None:
        owner = f"lifting line {self.name!r}"
        sup = self.support
        if not isinstance(sup, Beam | RigidBody | PrescribedBody):
            raise TypeError(f"{owner}: support must be a Beam, RigidBody or PrescribedBody")
        if not isinstance(self.flight, FlightCondition):
            raise TypeError(f"{owner}: flight must be a FlightCondition")
        if not (isinstance(self.wake_states, int | np.integer) and 0 <= self.wake_states <= 10):
            raise ValueError(f"{owner}: wake_states = {self.wake_states!r} must be an integer "
                             "in 0…10")
        if not (isinstance(self.points, int | np.integer) and 1 <= self.points <= 8):
            raise ValueError(f"{owner}: points = {self.points!r} must be an integer in 1…8")
        if self.start not in STARTS:
            raise ValueError(f"{owner}: start = {self.start!r} must be one of {STARTS}")
        if self.inflow is not None:
            from solver.inflow import DynamicInflow
            if not isinstance(self.inflow, DynamicInflow):
                raise TypeError(f"{owner}: inflow must be a DynamicInflow or None")
        if isinstance(sup, Beam):
            s0, s1 = (0.0, sup.length) if self.span is None else map(float, self.span)
            if not (0.0 <= s0 < s1 <= sup.length * (1 + 1e-12)):
                raise ValueError(f"{owner}: span = {self.span!r} must satisfy 0 ≤ s0 < s1 ≤ "
                                 f"{sup.length:.6g} m (the beam's length)")
            ends = sup.element_ends
        else:
            if self.span is None:
                raise ValueError(f"{owner}: give span = (s0, s1) along the body's d1 axis")
            s0, s1 = map(float, self.span)
            if not (math.isfinite(s0) and math.isfinite(s1) and s0 < s1):
                raise ValueError(f"{owner}: span = {self.span!r} must have s0 < s1")
            ends = np.array([s0, s1])
        cuts = [s0, s1]
        if self.lift_end is not None:
            le = float(self.lift_end)
            if not (s0 < le <= s1):
                raise ValueError(f"{owner}: lift_end = {le!r} m must be in ({s0:.6g}, "
                                 f"{s1:.6g}] (the span)")
            cuts.append(le)
        self.sections = _quadrature(ends, np.array(cuts), s0, s1, self.points)
        if self.wind is not None:
            w = np.asarray(self.wind(0.0))
            if w.shape != (self.n_sections, 3):
                raise ValueError(f"{owner}: wind(t) gives shape {w.shape}, must be "
                                 f"({self.n_sections}, 3) (one velocity per section)")
        s = self.sections["s"]
        for key, lo, hi, unit in (("chord", 1e-6, 100.0, "m"), ("lift_slope", 1e-9, 10.0, "1/rad"),
                                  ("zero_lift_angle", -0.2, 0.2, "rad"), ("drag", 0.0, 0.1, "1"),
                                  ("pitch", -math.pi / 2, math.pi / 2, "rad"),
                                  ("quarter_chord", -100.0, 100.0, "m")):
            vals = _profile(getattr(self, key), s, f"{owner}: {key}")
            if np.any(vals < lo) or np.any(vals > hi):
                raise ValueError(f"{owner}: {key} = {vals.min():.6g}…{vals.max():.6g} {unit} "
                                 f"must be in [{lo:g}, {hi:g}]")
            self.sections[key] = vals
        le = np.inf if self.lift_end is None else float(self.lift_end)
        self.sections["lifting"] = (s < le).astype(float)

    @property
    def n_sections(self) -> int:
        return len(self.sections["s"])

    def states(self) -> list[StateBlock]:
        n = self.wake_states
        if n == 0:
            return []
        a, _, _ = peters_matrices(n)
        return [StateBlock(self, FIRST, n * self.n_sections,
                           mass=np.kron(np.eye(self.n_sections), a), units="m/s",
                           long_name=f"Peters wake states μ = λ − A⁻¹c w34 of {self.name}")]


def _profile(value: Profile, s: Array, what: str) -> Array:
    out = np.asarray(value(s) if callable(value) else np.full(len(s), float(value)), dtype=float)
    out = np.broadcast_to(out, s.shape).astype(float) if out.ndim == 0 else out
    if out.shape != s.shape or not np.all(np.isfinite(out)):
        raise ValueError(f"{what} must give finite values of shape {s.shape}")
    return out


def _quadrature(ends: Array, cuts: Array, s0: float, s1: float, points: int) -> dict:
    """Gauss points of every element part inside [s0, s1], split at ``cuts``: element index,
    arc length s and weight ds (m)."""
    xg, wg = np.polynomial.legendre.leggauss(points)
    tol = 1e-12 * max(1.0, abs(ends[-1] - ends[0]))
    el, s, w = [], [], []
    for e in range(len(ends) - 1):
        a, b = max(ends[e], s0), min(ends[e + 1], s1)
        if b - a <= tol:
            continue
        inner = np.sort(cuts[(cuts > a + tol) & (cuts < b - tol)])
        edges = np.concatenate([[a], inner, [b]])
        for lo, hi in itertools.pairwise(edges):
            s.append(0.5 * (lo + hi) + 0.5 * (hi - lo) * xg)
            w.append(0.5 * (hi - lo) * wg)
            el.append(np.full(points, e))
    return {"element": np.concatenate(el), "s": np.concatenate(s), "ds": np.concatenate(w)}


class LiftingLineSet(ElementSet):
    """All lifting lines of a model (sections of every line evaluated together)."""

    nonconservative = True
    uses_acceleration = True

    def __init__(self, elements, system) -> None:
        super().__init__(elements, system)
        self.system = system
        flights = {(e.flight.density, *e.flight.air_velocity) for e in elements}
        if len(flights) > 1:
            raise ValueError("all lifting lines of a model must share one flight condition")
        inflows = {id(e.inflow): e.inflow for e in elements}
        if len(inflows) > 1:
            raise ValueError("lifting lines of one model must share one inflow model (or none)")
        counts = {e.wake_states for e in elements}
        if len(counts) > 1:
            raise ValueError("lifting lines of one model must have the same number of states")
        self.inflow = next(iter(inflows.values()))
        self.n = counts.pop()
        f = elements[0].flight
        self.rho, self.vinf = f.density, f.air_velocity
        idx, smat, props, sidx = [], [], {}, []
        for e in elements:
            i48, s12 = _support_map(e, system)
            idx.append(i48)
            smat.append(s12)
            for k in ("s", "ds", "chord", "lift_slope", "zero_lift_angle", "drag", "pitch",
                      "quarter_chord", "lifting"):
                props.setdefault(k, []).append(e.sections[k])
            if self.n:
                o = system.offset[e]
                sidx.append(o + np.arange(e.n_sections * self.n).reshape(-1, self.n))
        self.idx48 = np.concatenate(idx)  # (K, 48)
        self.S = np.concatenate(smat)  # (K, 12, 48)
        # S by its nonzeros (count, row, column, value per section; 48 of 576 on a beam)
        nnz = np.count_nonzero(self.S, axis=(1, 2))
        nz = np.zeros((3, len(nnz), max(int(nnz.max()), 1)))
        for j, sj in enumerate(self.S):
            r, c = np.nonzero(sj)
            nz[:, j, : len(r)] = r, c, sj[r, c]
        self._nz = (nnz.astype(np.int64), nz[0].astype(np.int64), nz[1].astype(np.int64),
                    np.ascontiguousarray(nz[2]))
        p = {k: np.concatenate(v) for k, v in props.items()}
        self.line_of = np.concatenate([np.full(e.n_sections, j) for j, e in enumerate(elements)])
        k = len(self.idx48)
        self.K = k
        self.ds = p["ds"]
        self.b = 0.5 * p["chord"]
        ang = p["pitch"] - p["zero_lift_angle"]
        self.cos_t, self.sin_t = np.cos(ang), np.sin(ang)
        self.a_lift = p["lift_slope"] * p["lifting"]
        self.cd0 = p["drag"]
        self.xq = p["quarter_chord"]
        self.s = p["s"]
        self.state_idx = (np.concatenate(sidx) if self.n else np.zeros((k, 0), dtype=np.int64))
        if self.n:
            a, bv, c = peters_matrices(self.n)
            self.pb = 0.5 * bv  # λ0 = ½ bᵀμ + κ w34
            self.ainv_c = np.linalg.solve(a, c)
            self.kappa = float(self.pb @ self.ainv_c)
        else:
            self.pb = self.ainv_c = np.zeros(0)
            self.kappa = 0.0
        if self.inflow is not None:
            infl = self.inflow
            self.n_i = infl.n_states
            self.inflow_idx = system.offset[infl] + np.arange(self.n_i)
            self.omega_r = infl.omega * infl.radius
            self.load_scale = 1.0 / (self.rho * infl.omega**2 * infl.radius**4)
            self.load_factors = infl.load_factors
            ref = max(float(np.sqrt(self.vinf @ self.vinf)), self.omega_r, 1.0)
        else:
            self.n_i = 0
            self.inflow_idx = np.zeros(0, dtype=np.int64)
            self.omega_r = self.load_scale = 0.0
            ref = max(float(np.sqrt(self.vinf @ self.vinf)), 1.0)
        self.u_floor2 = (FLOOR_FRACTION * ref) ** 2
        self.vinf = np.ascontiguousarray(self.vinf, dtype=float)
        # the air at each section: the free stream, plus the lines' prescribed winds
        self.air_steady = np.ascontiguousarray(np.broadcast_to(self.vinf, (k, 3)))
        first = np.cumsum([0] + [e.n_sections for e in elements])
        self.winds = [(slice(first[j], first[j + 1]), e.wind)
                      for j, e in enumerate(elements) if e.wind is not None]
        # the sections' constants in the compiled kernel's layout (aero_kernels.N_PROPS)
        self.props = np.ascontiguousarray(np.column_stack(
            [self.b, self.cos_t, self.sin_t, self.xq, self.a_lift, self.cd0, self.ds]))
        # global indices of each section's outputs/inputs: 48 support coordinates, its own
        # states, the inflow states
        self.loc_idx = np.concatenate([self.idx48, self.state_idx,
                                       np.broadcast_to(self.inflow_idx, (k, self.n_i))], axis=1)
        m = self.loc_idx.shape[1]
        self.force_idx = self.loc_idx.ravel()
        self.fq_rows = np.repeat(self.loc_idx, m, axis=1).ravel()
        self.fq_cols = np.tile(self.loc_idx, (1, m)).ravel()
        self.fv_rows = np.repeat(self.loc_idx, 48, axis=1).ravel()
        self.fv_cols = np.tile(self.idx48, (1, m)).ravel()
        self.fa_rows, self.fa_cols = self.fv_rows, self.fv_cols
        self._cache: tuple | None = None

    # ------------------------------------------------------------------ set-up
    def initialize(self, q0: Array) -> None:
        """Wake states at their steady value μ = −A⁻¹c w34 for the initial motion (``steady``)
        or zero (``rest``)."""
        if not self.n:
            return
        v0 = self.system.initial_velocity_guess()
        out = self.airloads(q0, v0, np.zeros_like(q0), 0.0)
        for j, e in enumerate(self.elements):
            if e.start != "steady":
                continue
            sel = self.line_of == j
            q0[self.state_idx[sel]] = -out["w34"][sel, None] * self.ainv_c[None, :]

    # ------------------------------------------------------------------ the kernel
    def _inputs(self, q: Array, v: Array, a: Array):
        # the section's coordinates, rates and accelerations from its support's nodes
        x, xd, xa = np.empty((self.K, 12)), np.empty((self.K, 12)), np.empty((self.K, 12))
        aero_kernels.section_inputs(q, v, a, self.idx48, *self._nz, x, xd, xa)
        mu = q[self.state_idx]
        al = np.empty((self.K, self.n_i))
        al[:] = q[self.inflow_idx]  # the same inflow states at every section
        return x, xd, xa, mu, al

    def _inflow_terms(self, pos):
        """Inflow shapes Φ (λ = Φ·α) and load weights W (K, n_i) at section positions pos
        (K, 3), real or complex; empty without an inflow."""
        if not self.n_i:
            return (np.zeros((len(pos), 0), dtype=pos.dtype),) * 2
        phi = np.ascontiguousarray(self.inflow.shape(*self.inflow.disk_coordinates(pos)))
        return phi, phi * self.load_factors  # = inflow.load_weights, one shape evaluation

    def air(self, t: float) -> Array:
        """The air's velocity at each section at time ``t`` (K, 3) (m/s): the free stream plus
        the lines' winds."""
        if not self.winds:
            return self.air_steady
        out = self.air_steady.copy()
        for sel, wind in self.winds:
            out[sel] += wind(t)
        return out

    def _constants(self, t: float):
        return (self.props, self.rho, self.air(t), self.omega_r, self.load_scale, self.u_floor2,
                self.kappa, self.pb, self.ainv_c)

    def _kernel(self, x, xd, xa, mu, al, t):
        """Airloads of every section (:func:`solver.aero_kernels.section_loads`) for their local
        coordinates x, rates xd, accelerations xa (K, 12), wake states mu (K, N) and inflow
        states al (K, n_i). Returns g (K, 12) the generalized force per unit span on (x, d1,
        d2, d3), the wake-state rates (K, N), the inflow forcing (K, n_i) and the details
        (K, 19; :data:`solver.aero_kernels.DETAIL_COLUMNS`), at time t (s)."""
        k = self.K
        phi, wts = self._inflow_terms(x[:, 0:3])
        g, det = np.empty((k, 12)), np.empty((k, aero_kernels.DETAILS))
        rates, forcing = np.empty((k, self.n)), np.empty((k, self.n_i))
        aero_kernels.airloads(x, xd, xa, mu, al, phi, wts, *self._constants(t), g, rates,
                              forcing, det)
        return g, rates, forcing, det

    # ------------------------------------------------------------------ terms
    def force(self, q, v, t, a):
        g, rates, forcing, _ = self._kernel(*self._inputs(q, v, a), t)
        out = np.empty((self.K, 48 + self.n + self.n_i))
        aero_kernels.support_forces(g, self.ds, *self._nz, out)  # Sᵀ g ds per section
        out[:, 48 : 48 + self.n], out[:, 48 + self.n :] = rates, forcing
        return out.ravel()

    def _local_jacobian(self, q, v, a, t):
        """∂(g, rates, forcing)/∂(x, μ, α | ẋ | ẍ) of every section by complex steps of the
        compiled section kernel, (K, 12 + n + ni, 36 + n + ni). Cached for the current
        (q, v, a, t)."""
        key = (q.tobytes(), v.tobytes(), a.tobytes(), t if self.winds else None)
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1]
        jac = self._derivatives(q, v, a, t, 1.0, np.ones(self.K), 1.0, False)
        self._cache = (key, jac)
        return jac

    def _derivatives(self, q, v, a, t, wq: float, wv: Array, wa: float, combined: bool):
        """:func:`solver.aero_kernels.local_jacobian` at (q, v, a, t), steps weighted by
        ``wq``, ``wv`` (per section) and ``wa``; all derivatives, or with ``combined`` their
        weighted sum by the coordinates, rates and accelerations together."""
        x, xd, xa, mu, al = self._inputs(q, v, a)
        k, n, ni = self.K, self.n, self.n_i
        phi, wts = self._inflow_terms(x[:, 0:3])
        # Φ and W at the positions stepped by i h wq along x, y, z: all the Jacobian needs of
        # them
        pos = np.repeat(x[None, :, 0:3].astype(complex), 3, axis=0)  # (3, K, 3)
        for c in range(3):
            pos[c, :, c] += 1j * (COMPLEX_STEP * wq)
        pp, wp = (z.reshape(3, k, ni) for z in self._inflow_terms(pos.reshape(3 * k, 3)))
        jac = np.empty((k, 12 + n + ni, (12 if combined else 36) + n + ni))  # (K, out, in)
        aero_kernels.local_jacobian(x, xd, xa, mu, al, phi, wts, pp, wp, *self._constants(t),
                                    COMPLEX_STEP, float(wq), np.ascontiguousarray(wv, float),
                                    float(wa), combined, jac)
        return jac

    def _expand(self, jac: Array, c0: int, nraw: int) -> Array:
        """Global blocks of the local Jacobian's columns c0…c0+11 (+ ``nraw`` state columns):
        rows and the 12 columns mapped through Sᵀ ds and S
        (:func:`solver.aero_kernels.expand_jacobian`); (K, 48 + n + ni, 48 + nraw)."""
        out = np.empty((self.K, 48 + self.n + self.n_i, 48 + nraw))
        aero_kernels.expand_jacobian(jac, c0, nraw, self.ds, *self._nz, out)
        return out

    def force_jacobians(self, q, v, t, a):
        jac = self._local_jacobian(q, v, a, t)
        n, ni = self.n, self.n_i
        dq = self._expand(jac, 0, n + ni)
        dv = self._expand(jac, 12 + n + ni, 0)
        return dq.ravel(), dv.ravel()

    def acceleration_jacobian(self, q, v, t, a):
        jac = self._local_jacobian(q, v, a, t)
        return self._expand(jac, 24 + self.n + self.n_i, 0).ravel()

    def force_tangent(self, q, v, t, a, wq, wv, wa):
        # the section's 12 inputs are S times its support's coordinates, S times their rates
        # and S times their accelerations: with one velocity weight per section the three
        # local Jacobians sum before the map to the 48 support columns (one complex step
        # along the three at once), and ∂f/∂v, ∂f/∂a (inside the ∂f/∂q pattern) cost no
        # global blocks of their own
        w48 = wv[self.idx48]
        wk = w48[:, 0]
        if not np.all(w48 == wk[:, None]):
            return None
        tan = self._derivatives(q, v, a, t, wq, wk, wa, True)
        return self._expand(tan, 0, self.n + self.n_i).ravel()

    # ------------------------------------------------------------------ outputs
    def airloads(self, q: Array, v: Array, a: Array, t: float = 0.0) -> dict[str, Array]:
        """At time ``t`` (s; it matters only with a prescribed wind), per section: ``force``
        (N/m, global, total), ``circulatory`` (N/m), ``lift`` (ρΓu, N/m), ``u``, ``w0``,
        ``w34``, ``lam0`` (m/s), ``apparent_lift`` (N/m), ``apparent_moment`` (N·m/m),
        ``position`` (m), ``air`` (m/s), ``s``, ``ds`` (m), ``line`` (the line's index)."""
        *_, det = self._kernel(*self._inputs(q, v, a), t)
        out = {name: det[:, i] if w == 1 else det[:, i : i + w]
               for name, (i, w) in aero_kernels.DETAIL_COLUMNS.items()}
        out.update(s=self.s, ds=self.ds, line=self.line_of)
        return out


def _support_map(line: LiftingLine, system) -> tuple[NDArray[np.int64], Array]:
    """Per section: the 48 global coordinates it reads and the map S (12 × 48) from them to
    its (x, d1, d2, d3)."""
    sec = line.sections
    k = len(sec["s"])
    sup = line.support
    o = system.offset[sup]
    smat = np.zeros((k, 12, 48))
    if isinstance(sup, Beam):
        e = sec["element"]
        s0, s1 = sup.element_ends[e], sup.element_ends[e + 1]
        xi = -1.0 + 2.0 * (sec["s"] - s0) / (s1 - s0)
        n, _ = lagrange(xi)  # (K, 4)
        idx = o + 36 * e[:, None] + np.arange(48)[None, :]
        for a in range(4):
            smat[:, :, 12 * a : 12 * a + 12] = n[:, a, None, None] * np.eye(12)
        # ξ linear in the arc length inside an element (its inner nodes sit at equal arc
        # lengths); the Gauss weights ds are arc lengths already
        return idx, smat
    # a body: x(s) = x + s d1, directors unchanged; the other 36 columns repeat its indices
    idx = o + np.tile(np.arange(12), 4)[None, :].repeat(k, axis=0)
    smat[:, :, :12] = np.eye(12)
    smat[:, 0:3, 3:6] = sec["s"][:, None, None] * np.eye(3)
    return idx, smat


LiftingLine.set_class = LiftingLineSet
