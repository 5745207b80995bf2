"""Finite-state rotor inflow as a first-order solver element: Peters–He and Pitt–Peters.

A rotor disk of radius R turning at Ω about the +z axis of the model (:mod:`solver.air`: ψ = 0
along +x, downstream; ψ = 90° along +y, the advancing side) induces a velocity −λ Ω R ẑ at a
point (r̄, ψ) of the disk. The dimensionless inflow λ (positive down, through the disk) is a
sum of radial shape functions times harmonics of the azimuth whose coefficients are states:

* **Peters–He** (Peters & He, J. Aircraft 32(2), 1995; Peters, Boyd & He, JAHS 34(4), 1989)::

      λ(r̄, ψ) = Σ_r Σ_j φ_j^r(r̄) [α_j^r cos rψ + β_j^r sin rψ],   r = 0…M,  j = r+1, r+3, … ≤ P+1

  with φ_j^r polynomials in r̄ (powers q = r, r+2, …, j−1). The states are ordered: all cosine
  states α first, by harmonic r then j (α_1^0, α_3^0, …, α_2^1, α_4^1, …, α_{M+1}^M, …), then
  all sine states β in the same order (β_2^1, …). With M = P = 1: (α_1^0, α_2^1, β_2^1).
* **Pitt–Peters** (Pitt & Peters, Vertica 5, 1981): λ = λ0 + r̄ (λs sin ψ + λc cos ψ),
  states (λ0, λs, λc).

Both obey, in seconds, (K/Ω) α̇ = F − V L⁻¹ α. The forcing F is the projection of the blade
loads on the states; other elements (a lifting line) add it to the state rows through
:meth:`DynamicInflow.load_weights`. The element's own set adds f = −V L⁻¹ α, where the wake
skew X = tan(χ/2) enters L and the mass-flow parameters enter V = diag(V_T, V_m, V_m, …):

    μ = in-plane free stream / ΩR,     λ_f = −V∞·ẑ / ΩR (free stream down through the disk),
    λ = λ_f + λ_m,   V_T = √(μ² + λ²),   V_m = [μ² + λ (λ + λ_m)] / V_T,
    χ = atan(μ/λ),   X = tan(χ/2) = μ / (V_T + λ).

V_T is the total flow through the disk (momentum theory: C_T = 2 λ_m V_T) and multiplies the
thrust state; V_m is the linearization of that mass flow, which acts on the perturbation states
(in hover V_m = 2λ). λ_m is the momentum (thrust-weighted) inflow: λ0 for Pitt–Peters, √3 α_1^0
for Peters–He, the projection of λ on the uniform-pressure mode — with several m = 0 states it
differs from the disk-area average returned by :meth:`DynamicInflow.mean_inflow`.

**Forcing normalization.** A lifting line with sections k (load per unit span along +z, N/m,
times quadrature weight along the blade, m) forms T_k = L_k w_k / (ρ Ω² R⁴) and adds
F = Σ_k W_k T_k with W = :meth:`~DynamicInflow.load_weights` at the sections. For Peters–He
this is the ½τ of the state equation (τ_j^0 = (1/2π) Σ_q ∫ L_q/(ρΩ²R³) φ_j^0 dr̄, τ_j^r with
1/π and cos rψ or sin rψ); for Pitt–Peters it is (C_T, C_s, C_c) with C_T the thrust
coefficient and C_s, C_c the moments of the load about the disk axes weighted by r̄ sin ψ and
r̄ cos ψ: positive when more load sits on the advancing side (ψ = 90°) and at the rear (ψ = 0).
With these signs more load on one side of the disk gives more inflow there, and the Pitt–Peters
L matrix has the same structure as the lowest Peters–He member. (MBDyn and Pitt & Peters write
the moments as roll and pitch moments C_l = −C_s, C_m = −C_c, hence their negative M22, M33,
L22, L33.)

**Pitt–Peters matrices** (after the sign change above)::

    M = diag(128/(75π), 16/(45π), 16/(45π)),
    L = [[1/2,          0,            −(15π/64) X ],
         [0,            2 (1 + X²),    0          ],
         [(15π/64) X,   0,             2 (1 − X²) ]].

The lowest Peters–He member in the same variables (λ0 = √3 α_1^0, λc = √(15/2) α_2^1,
forcing C_T, C_c) reads M = diag(8/(3π), 16/(45π), 16/(45π)), L = [[9/16, −(3π/8) X],
[(3π/8) X, (75/32)(1 − X²)]], L_s = (75/32)(1 + X²): 9/8 of momentum theory in hover and a
skew gradient λc/λ0 = (2π/3) X against Pitt–Peters' (15π/32) X.

**Validity.** Both models assume a wake convected down through the disk (λ > 0, χ < 90°,
X < 1). For λ < 0 with μ > 0 (X > 1: wind up through the disk, windmill states) the formulas
are still evaluated but L loses its definiteness (Pitt–Peters: det L = 1 − X² + (15π/64)² X²
turns negative at X ≈ 1.5) and the states may diverge. In axial flow (μ = 0) X = 0 whatever
the sign of λ. With no flow at all (hover, zero states) V = 0 and f = 0: start a hovering
rotor with ``initial_thrust``.

Every function a lifting line calls with section coordinates (:meth:`~DynamicInflow.shape`,
:meth:`~DynamicInflow.load_weights`, :meth:`~DynamicInflow.disk_coordinates`) is a polynomial
in the Cartesian disk coordinates ξ = r̄ cos ψ, η = r̄ sin ψ and therefore complex-step safe.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import brentq

from solver import aero_kernels
from solver.air import FlightCondition
from solver.element import EMPTY_F, Element, ElementSet
from solver.state import FIRST, StateBlock

Array = NDArray[np.float64]
PETERS_HE, PITT_PETERS = "peters-he", "pitt-peters"
MODELS = (PETERS_HE, PITT_PETERS)
MAX_HARMONICS = 16  # highest Peters–He harmonic accepted (M)
MAX_POWER = 32  # highest Peters–He radial power accepted (P)
MAX_THRUST_COEFFICIENT = 0.1  # |initial_thrust| bound (helicopter rotors: C_T ≈ 0.005–0.01)
_PP_SKEW = 15.0 * math.pi / 64.0  # Pitt–Peters coupling of λ0 and λc per unit X


# ---------------------------------------------------------------------- Peters–He algebra
def double_factorial(n: int) -> int:
    """n!! for n ≥ −1 (0!! = (−1)!! = 1)."""
    if n < -1:
        raise ValueError(f"double factorial of n = {n!r}: n must be ≥ −1")
    out = 1
    while n > 1:
        out *= n
        n -= 2
    return out


def _h(n: int, m: int) -> float:
    """H_n^m = (n+m−1)!! (n−m−1)!! / [(n+m)!! (n−m)!!] (n > m ≥ 0)."""
    df = double_factorial
    return df(n + m - 1) * df(n - m - 1) / (df(n + m) * df(n - m))


def peters_he_states(harmonics: int, power: int) -> list[tuple[str, int, int]]:
    """The Peters–He states in element order: ``("c", r, j)`` for α_j^r, ``("s", r, j)`` for
    β_j^r; cosine states first (r = 0…M, j = r+1, r+3, … ≤ P+1), then sine states (r ≥ 1)."""
    cos = [("c", r, j) for r in range(harmonics + 1) for j in range(r + 1, power + 2, 2)]
    sin = [("s", r, j) for (_, r, j) in cos if r >= 1]
    return cos + sin


def peters_he_shape_coefficients(r: int, j: int) -> Array:
    """Coefficients c_k of φ_j^r(r̄) = r̄^r Σ_k c_k r̄^{2k}, k = 0…(j−1−r)/2 (dimensionless).

    φ_j^r = √((2j+1) H_j^r) Σ_{q=r,r+2,…}^{j−1} r̄^q (−1)^{(q−r)/2} (j+q)!! /
    [(q−r)!! (q+r)!! (j−q−1)!!]: the Legendre function P̄_j^r(ν)/ν, ν = √(1 − r̄²), written
    in r̄, so that the inflow shapes are orthogonal with weight ν on the disk.
    """
    if not (r >= 0 and j > r and (j - r) % 2 == 1):
        raise ValueError(f"Peters–He state (r, j) = ({r}, {j}) needs j = r+1, r+3, …")
    df = double_factorial
    norm = math.sqrt((2 * j + 1) * _h(j, r))
    return np.array([norm * (-1) ** ((q - r) // 2) * df(j + q)
                     / (df(q - r) * df(q + r) * df(j - q - 1)) for q in range(r, j, 2)])


def _gamma(r: int, j: int, m: int, n: int) -> float:
    """Γ_{jn}^{rm}: coupling of the inflow state (r, j) (row) with the pressure state (m, n)."""
    hh = math.sqrt(_h(n, m) * _h(j, r))
    if (r + m) % 2 == 0:
        return ((-1) ** ((n + j - 2 * r) // 2) * 2.0 * math.sqrt((2 * n + 1) * (2 * j + 1))
                / (hh * (n + j) * (n + j + 2) * ((n - j) ** 2 - 1)))
    if abs(j - n) == 1:
        return math.copysign(math.pi, r - m) / (2.0 * hh * math.sqrt((2 * n + 1) * (2 * j + 1)))
    return 0.0


def _peters_he_l_polynomial(states: list[tuple[str, int, int]]) -> Array:
    """Coefficients L_p (p = 0…2M) of L(X) = Σ_p X^p L_p, block diagonal (L^c, L^s).

    Row (r, j), column (m, n), l = min(r, m):
    L^c = X^m Γ for r = 0, [X^{|m−r|} + (−1)^l X^{m+r}] Γ for r ≥ 1;
    L^s = [X^{|m−r|} − (−1)^l X^{m+r}] Γ.
    """
    n = len(states)
    top = max([r for (_, r, _) in states] + [0])
    lp = np.zeros((2 * top + 1, n, n))
    for a, (ka, r, j) in enumerate(states):
        for b, (kb, m, nn) in enumerate(states):
            if ka != kb:
                continue  # cosine and sine states do not couple
            g = _gamma(r, j, m, nn)
            if g == 0.0:
                continue
            if ka == "c" and r == 0:
                lp[m, a, b] += g
                continue
            sign = (-1) ** min(r, m) * (1 if ka == "c" else -1)
            lp[abs(m - r), a, b] += g
            lp[m + r, a, b] += sign * g
    return lp


def peters_he_matrices(harmonics: int, power: int, skew: float
                       ) -> tuple[Array, Array, Array, list[tuple[str, int, int]]]:
    """The Peters–He matrices at wake skew X = tan(χ/2).

    Parameters
    ----------
    harmonics, power
        M (highest harmonic) and P (highest radial power, P ≥ M).
    skew
        X = tan(χ/2) (dimensionless; 0 in hover or axial flight).

    Returns
    -------
    K, Lc, Ls, states
        K (diagonal, all states, dimensionless: the apparent mass (2/π) H_j^r, in rotor time
        Ωt), L^c (cosine states), L^s (sine states), and the state list of
        :func:`peters_he_states` (cosine states, then sine states).
    """
    states = peters_he_states(harmonics, power)
    lp = _peters_he_l_polynomial(states)
    big = sum(skew**p * lp[p] for p in range(len(lp)))
    nc = sum(1 for s in states if s[0] == "c")
    k = np.diag([2.0 / math.pi * _h(j, r) for (_, r, j) in states])
    return k, big[:nc, :nc], big[nc:, nc:], states


# ---------------------------------------------------------------------- the element
class InflowParameters(NamedTuple):
    """Flow through the disk for given states (all dimensionless, on ΩR; χ in rad)."""

    mu: float  # in-plane free stream μ
    lambda_f: float  # free stream down through the disk λ_f
    lambda_m: float  # momentum (thrust-weighted) induced inflow λ_m
    lambda_total: float  # λ = λ_f + λ_m
    v_t: float  # V_T, total mass-flow parameter
    v_m: float  # V_m, mass-flow parameter of the perturbation states
    chi: float  # wake skew angle χ (0: axial, π/2: edgewise)
    skew: float  # X = tan(χ/2)


@dataclass(eq=False)
class DynamicInflow(Element):
    """Finite-state induced inflow of one rotor (Peters–He or Pitt–Peters).

    Parameters
    ----------
    name
        Element name.
    flight
        Free stream (model axes, m/s) and air density (kg/m³).
    radius
        Rotor radius R (m), > 0.
    omega
        Nominal rotor speed Ω (rad/s), > 0: rotor time is Ωt and velocities scale with ΩR.
    model
        ``"peters-he"`` or ``"pitt-peters"``.
    harmonics
        M, highest harmonic of ψ (Peters–He, 0…16); Pitt–Peters requires 1.
    power
        P, highest radial power (Peters–He, M…32; default M): states (r, j) with
        j = r+1, r+3, … ≤ P+1. Pitt–Peters requires ``None`` or 1.
    centre
        Hub centre (m, model axes). The disk normal is +z, ψ = 0 along +x.
    initial_thrust
        Thrust coefficient C_T = T/(ρπR²(ΩR)²) of a uniform disk loading whose steady inflow
        starts the states (0: all states zero), in [−0.1, 0.1].

    Notes
    -----
    The matrices depend on ``model``, ``harmonics`` and ``power`` and are set up at
    construction; ``flight``, ``radius`` and ``omega`` are read when used.
    """

    name: str
    flight: FlightCondition
    radius: float
    omega: float
    model: str = PETERS_HE
    harmonics: int = 1
    power: int | None = None
    centre: ArrayLike = (0.0, 0.0, 0.0)
    initial_thrust: float = 0.0

    def __post_init__(self) -> None:
        self._validate()
        self.centre = np.asarray(self.centre, dtype=float).copy()
        if self.model == PITT_PETERS:
            self._labels = ["lambda_0", "lambda_s", "lambda_c"]
            self._k = np.array([128.0 / (75.0 * math.pi), 16.0 / (45.0 * math.pi),
                                16.0 / (45.0 * math.pi)])
            # L(X) = Σ X^p L_p, rows and columns (λ0, λs, λc); forcing (C_T, C_s, C_c) with
            # C_s, C_c positive for load on the advancing side and at the rear: 4/(1 + cos χ)
            # = 2(1 + X²), 4 cos χ/(1 + cos χ) = 2(1 − X²), and the skew couples λ0 and λc
            # antisymmetrically (as the lowest Peters–He member)
            lp = np.zeros((3, 3, 3))
            lp[0] = np.diag([0.5, 2.0, 2.0])
            lp[1, 0, 2], lp[1, 2, 0] = -_PP_SKEW, _PP_SKEW
            lp[2] = np.diag([0.0, 2.0, -2.0])
            self._lp = lp
            self._mom = np.array([1.0, 0.0, 0.0])  # λ_m = λ0
            self._states = []
        else:
            p = self.harmonics if self.power is None else self.power
            self._states = peters_he_states(self.harmonics, p)
            self._labels = [("alpha" if c == "c" else "beta") + f"_{j}^{r}"
                            for (c, r, j) in self._states]
            self._k = np.array([2.0 / math.pi * _h(j, r) for (_, r, j) in self._states])
            self._lp = _peters_he_l_polynomial(self._states)
            self._mom = np.zeros(len(self._states))
            self._mom[0] = math.sqrt(3.0)  # λ_m = √3 α_1^0 (φ_1^0 = √3)
            self._coef = [peters_he_shape_coefficients(r, j) for (_, r, j) in self._states]
            ncoef = np.array([len(c) for c in self._coef], dtype=np.int64)
            coef = np.zeros((len(ncoef), int(ncoef.max())))
            for i, c in enumerate(self._coef):
                coef[i, : len(c)] = c
            self._shape_tables = (np.array([k == "s" for k, _, _ in self._states], dtype=np.int64),
                                  np.array([r for _, r, _ in self._states], dtype=np.int64),
                                  coef, ncoef)
            # ½τ weights, with τ = 1/(2π) for the axisymmetric states and 1/π for the harmonics
            self._half_tau = np.array([0.25 / math.pi if r == 0 else 0.5 / math.pi
                                       for (_, r, _) in self._states])
        self._fit = self._fit_vectors()

    # -- validation ---------------------------------------------------------------------
    def _validate(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"inflow name = {self.name!r} must be a non-empty string")
        who = f"inflow {self.name!r}"
        if not isinstance(self.flight, FlightCondition):
            raise ValueError(f"{who}: flight = {self.flight!r} must be a "
                             "solver.air.FlightCondition")
        if not (_is_real(self.radius) and 0.0 < self.radius < math.inf):
            raise ValueError(f"{who}: radius = {self.radius!r} m must be finite and > 0")
        if not (_is_real(self.omega) and 0.0 < self.omega < math.inf):
            raise ValueError(f"{who}: omega = {self.omega!r} rad/s must be finite and > 0")
        if self.model not in MODELS:
            raise ValueError(f"{who}: model = {self.model!r} must be one of "
                             f"{', '.join(map(repr, MODELS))}")
        if not _is_int(self.harmonics):
            raise ValueError(f"{who}: harmonics = {self.harmonics!r} must be an integer")
        if self.power is not None and not _is_int(self.power):
            raise ValueError(f"{who}: power = {self.power!r} must be an integer or None")
        if self.model == PITT_PETERS:
            if self.harmonics != 1:
                raise ValueError(f"{who}: harmonics = {self.harmonics!r}: pitt-peters has "
                                 "the first harmonic only (must be 1)")
            if self.power not in (None, 1):
                raise ValueError(f"{who}: power = {self.power!r}: pitt-peters is linear in "
                                 "r̄ (must be None or 1)")
        else:
            if not 0 <= self.harmonics <= MAX_HARMONICS:
                raise ValueError(f"{who}: harmonics = {self.harmonics!r} must be in "
                                 f"[0, {MAX_HARMONICS}]")
            if self.power is not None and not self.harmonics <= self.power <= MAX_POWER:
                raise ValueError(f"{who}: power = {self.power!r} must be in "
                                 f"[harmonics = {self.harmonics}, {MAX_POWER}]")
        c = np.asarray(self.centre)
        if c.shape != (3,) or not np.issubdtype(c.dtype, np.number) or np.iscomplexobj(c) \
                or not np.all(np.isfinite(c)):
            raise ValueError(f"{who}: centre = {self.centre!r} must be 3 finite real "
                             "coordinates (m)")
        if not (_is_real(self.initial_thrust)
                and abs(self.initial_thrust) <= MAX_THRUST_COEFFICIENT):
            raise ValueError(f"{who}: initial_thrust = {self.initial_thrust!r} must be a "
                             f"thrust coefficient in [−{MAX_THRUST_COEFFICIENT}, "
                             f"{MAX_THRUST_COEFFICIENT}]")

    # -- declaration --------------------------------------------------------------------
    @property
    def n_states(self) -> int:
        """Number of inflow states."""
        return len(self._labels)

    @property
    def labels(self) -> list[str]:
        """One label per state, in state order (``alpha_j^r``, ``beta_j^r``, ``lambda_0`` …)."""
        return list(self._labels)

    @property
    def harmonic_indices(self) -> list[tuple[str, int, int]]:
        """Peters–He: ``(kind, r, j)`` per state (see :func:`peters_he_states`); else empty."""
        return list(self._states)

    @property
    def mass_matrix(self) -> Array:
        """The first-order mass K/Ω (s), n_states × n_states."""
        return np.diag(self._k / self.omega)

    def states(self) -> list[StateBlock]:
        if self.initial_thrust == 0.0:
            x0 = np.zeros(self.n_states)
        else:
            x0 = self.steady_states(self.uniform_forcing(self.initial_thrust))
        return [StateBlock(self, FIRST, self.n_states, initial=x0, mass=self.mass_matrix,
                           units="1", long_name=f"{self.model} inflow states (on ΩR)")]

    # -- geometry and shapes (polynomial in ξ, η: complex-step safe) ---------------------
    def disk_coordinates(self, points: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Cartesian disk coordinates of points.

        Parameters
        ----------
        points
            (n, 3) positions in model axes (m); may be complex.

        Returns
        -------
        xi, eta
            ξ = (p − centre)·x̂ / R = r̄ cos ψ and η = (p − centre)·ŷ / R = r̄ sin ψ (n,).
        """
        p = np.asarray(points)
        d = p - self.centre
        return d[..., 0] / self.radius, d[..., 1] / self.radius

    def shape(self, xi: ArrayLike, eta: ArrayLike) -> np.ndarray:
        """Inflow shapes Φ at disk points: λ = Φ @ states (dimensionless).

        Parameters
        ----------
        xi, eta
            Disk coordinates ξ = r̄ cos ψ, η = r̄ sin ψ (broadcast together; may be complex).

        Returns
        -------
        ndarray, shape ``(*xi.shape, n_states)``
        """
        xi, eta = np.broadcast_arrays(np.asarray(xi), np.asarray(eta))
        dtype = np.result_type(xi, eta, float)
        out = np.empty((*xi.shape, self.n_states), dtype=dtype)
        if self.model == PITT_PETERS:
            out[..., 0] = 1.0
            out[..., 1] = eta  # r̄ sin ψ
            out[..., 2] = xi  # r̄ cos ψ
            return out
        # compiled (the lifting lines call this at every force evaluation): Horner in r̄² times
        # r̄^r cos rψ or r̄^r sin rψ, the parts of (ξ + iη)^r by recursion
        sine, harmonic, coef, ncoef = self._shape_tables
        flat = out.reshape(-1, self.n_states)
        work = np.empty((2, self.harmonics + 1), dtype=dtype)
        aero_kernels.peters_he_shapes(np.ascontiguousarray(xi, dtype=dtype).ravel(),
                                      np.ascontiguousarray(eta, dtype=dtype).ravel(), sine,
                                      harmonic, coef, ncoef, work[0], work[1], flat)
        return out

    def load_weights(self, xi: ArrayLike, eta: ArrayLike) -> np.ndarray:
        """Weights W of the section loads in the forcing: F = Σ_k W_k T_k.

        T_k = (force per unit span along +z at section k, N/m) × (its quadrature weight along
        the blade, m) / (ρ Ω² R⁴). Peters–He: W = ½ (1/(2π) for r = 0, 1/π for r ≥ 1) Φ, the
        ½τ of the state equation. Pitt–Peters: (1, η, ξ)/π, so that F = (C_T, C_s, C_c) with
        C_T the thrust coefficient and C_s, C_c the r̄ sin ψ- and r̄ cos ψ-weighted moments.

        Parameters
        ----------
        xi, eta
            Disk coordinates of the sections (broadcast together; may be complex).

        Returns
        -------
        ndarray, shape ``(*xi.shape, n_states)`` (dimensionless)
        """
        return self.shape(xi, eta) * self.load_factors

    @property
    def load_factors(self) -> Array:
        """Per state, the factor of the load weights on the shapes, W = Φ * factors state by
        state (:meth:`load_weights`): 1/π for Pitt–Peters, ½τ's 1/(4π) (r = 0) or 1/(2π)
        (r ≥ 1) for Peters–He. A caller that has Φ already forms W without a second shape
        call."""
        if self.model == PITT_PETERS:
            return np.full(3, 1.0 / math.pi)
        return self._half_tau.copy()

    def induced_velocity(self, points: ArrayLike, states: ArrayLike) -> np.ndarray:
        """Induced velocity −λ Ω R ẑ (m/s, model axes) at points (n, 3) for given states."""
        lam = self.shape(*self.disk_coordinates(points)) @ np.asarray(states)
        out = np.zeros((*lam.shape, 3), dtype=lam.dtype)
        out[..., 2] = -lam * (self.omega * self.radius)
        return out

    # -- disk averages ------------------------------------------------------------------
    def _fit_vectors(self) -> Array:
        """Rows (g0, gs, gc): the least-squares fit λ ≈ λ0 + λs η + λc ξ over the disk area
        is (g0, gs, gc) @ states. 1, ξ, η are orthogonal on the unit disk (∫1 = π,
        ∫ξ² = ∫η² = π/4), so λ0 = (1/π)∫λ dA, λs = (4/π)∫λ η dA, λc = (4/π)∫λ ξ dA; only
        the r = 0 (λ0) and r = 1 (λs, λc) states contribute, through ∫ r̄^{q+1} dr̄."""
        n = self.n_states
        if self.model == PITT_PETERS:
            return np.eye(3)
        g = np.zeros((3, n))
        for i, ((kind, r, _), coef) in enumerate(zip(self._states, self._coef, strict=True)):
            q = r + 2 * np.arange(len(coef))
            if r == 0:  # (1/π) ∫∫ φ r̄ dr̄ dψ = 2 ∫ φ r̄ dr̄
                g[0, i] = 2.0 * np.sum(coef / (q + 2))
            elif r == 1:  # (4/π) ∫∫ φ cos²ψ r̄² dr̄ dψ = 4 ∫ φ r̄² dr̄ (sin: the same)
                g[1 if kind == "s" else 2, i] = 4.0 * np.sum(coef / (q + 3))
        return g

    def mean_inflow(self, states: ArrayLike) -> float:
        """Disk-area average of λ (dimensionless); λ0 for Pitt–Peters."""
        return self._fit[0] @ np.asarray(states)

    def gradients(self, states: ArrayLike) -> tuple:
        """(λ0, λs, λc) of the area least-squares fit λ ≈ λ0 + r̄ (λs sin ψ + λc cos ψ)
        (dimensionless); exactly the states for Pitt–Peters and for Peters–He with M = P = 1
        (λ0 = √3 α_1^0, λs = √(15/2) β_2^1, λc = √(15/2) α_2^1)."""
        g = self._fit @ np.asarray(states)
        return g[0], g[1], g[2]

    # -- flow parameters and the state equation -----------------------------------------
    @property
    def free_stream(self) -> tuple[float, float]:
        """(μ, λ_f): in-plane free stream (along +x) and free stream down through the disk,
        both on ΩR."""
        v = self.flight.air_velocity / (self.omega * self.radius)
        return float(v[0]), float(-v[2])

    def _flow_terms(self, lam_m: float) -> tuple[float, ...]:
        """V_T, V_m, X and their derivatives with respect to λ_m
        (:func:`solver.aero_kernels.flow_terms`)."""
        return aero_kernels.flow_terms(*self.free_stream, lam_m)

    def flow(self, states: ArrayLike) -> InflowParameters:
        """The flow parameters (μ, λ_f, λ_m, λ, V_T, V_m, χ, X) for given states."""
        mu, lam_f = self.free_stream
        lam_m = float(self._mom @ np.asarray(states, dtype=float))
        vt, vm, x, *_ = self._flow_terms(lam_m)
        lam = lam_f + lam_m
        return InflowParameters(mu, lam_f, lam_m, lam, vt, vm, math.atan2(mu, lam), x)

    def l_matrix(self, skew: float) -> Array:
        """The full L matrix (dimensionless) at wake skew X = tan(χ/2), in state order."""
        return np.tensordot(skew ** np.arange(len(self._lp)), self._lp, axes=1)

    def rhs(self, states: ArrayLike, jacobian: bool = False):
        """f = −V L⁻¹ α, the element's own right-hand side (dimensionless; the equation in
        seconds is (K/Ω) α̇ = F + f), compiled (:func:`solver.aero_kernels.inflow_rhs`: the
        Newton iterations call it at every residual, and the NumPy form spent some 70 µs in
        calls on these 8 × 8 matrices).

        Returns f, or (f, ∂f/∂α) with ∂f/∂α dense n × n if ``jacobian``.
        """
        a = np.ascontiguousarray(states, dtype=float)
        jac = np.empty((len(a), len(a)))
        f = aero_kernels.inflow_rhs(a, self._mom, self._lp, *self.free_stream, jacobian, jac)
        return (f, jac) if jacobian else f

    # -- steady state -------------------------------------------------------------------
    def uniform_forcing(self, thrust_coefficient: float) -> Array:
        """F of a uniform disk loading Δp = C_T ρ (ΩR)² (dimensionless): Pitt–Peters
        (C_T, 0, 0); Peters–He ½τ_j^0 = ½ C_T ∫ φ_j^0 r̄ dr̄ on the axisymmetric states."""
        if self.model == PITT_PETERS:
            return np.array([thrust_coefficient, 0.0, 0.0])
        # ½ (1/2π) Σ_q ∫ L_q φ dr̄ with Σ_q L_q = 2π r̄ C_T: ½ C_T ∫ φ r̄ dr̄ = C_T g0/4
        return 0.25 * thrust_coefficient * self._fit[0]

    def steady_states(self, forcing: ArrayLike, tol: float = 1e-14,
                      max_iterations: int = 60) -> Array:
        """States with F = V L⁻¹ α (the steady inflow for the forcing F).

        Starts from the Glauert momentum solution for the thrust part of F and solves the full
        nonlinear system by Newton with the exact Jacobian and a backtracking line search.

        Parameters
        ----------
        forcing
            F (n_states,), dimensionless (see :meth:`load_weights`).
        tol
            Convergence on the update relative to max(|α|, 1e-12).

        Raises
        ------
        RuntimeError
            If no steady state is found (e.g. moments without thrust in hover: no mass flow).
        """
        f_load = np.asarray(forcing, dtype=float)
        if f_load.shape != (self.n_states,) or not np.all(np.isfinite(f_load)):
            raise ValueError(f"inflow {self.name!r}: forcing must be {self.n_states} finite "
                             f"numbers, got shape {f_load.shape}")
        if not np.any(f_load):
            return np.zeros(self.n_states)
        # start: momentum inflow of the equivalent thrust coefficient, then α = L V⁻¹ F there
        ct = f_load[0] / self.uniform_forcing(1.0)[0]
        vt, vm, x, *_ = self._flow_terms(self._glauert(ct))
        v = np.full(self.n_states, vm)
        v[0] = vt
        a = self.l_matrix(x) @ (f_load / np.where(v != 0.0, v, 1.0))
        res = f_load + self.rhs(a)
        for _ in range(max_iterations):
            _, jac = self.rhs(a, jacobian=True)
            try:
                step = np.linalg.solve(jac, -res)
            except np.linalg.LinAlgError:
                break
            t = 1.0
            norm0 = np.linalg.norm(res)
            if norm0 == 0.0:
                return a
            while True:  # backtrack until the residual decreases
                trial = a + t * step
                res_t = f_load + self.rhs(trial)
                if np.linalg.norm(res_t) <= norm0 or t < 1e-6:
                    break
                t *= 0.5
            a, res = trial, res_t
            small_step = t == 1.0 and np.max(np.abs(step)) <= tol * max(np.max(np.abs(a)), 1e-12)
            if small_step or np.linalg.norm(res) <= 1e-14 * np.linalg.norm(f_load):
                return a
        raise RuntimeError(f"inflow {self.name!r}: no steady inflow found for forcing "
                           f"{f_load} (residual {np.linalg.norm(res):.3g})")

    def _glauert(self, ct: float) -> float:
        """λ_m of :func:`glauert_inflow` in this inflow's free stream."""
        return glauert_inflow(ct, *self.free_stream)


def glauert_inflow(ct: float, mu: float, lam_f: float) -> float:
    """The momentum (Glauert) induced inflow λ_m with C_T = 2 λ_m √(μ² + (λ_f + λ_m)²), for
    the in-plane free stream μ and the free stream λ_f down through the disk (all on ΩR): a
    root of the same sign as C_T, bracketed by doubling."""
    if ct == 0.0:
        return 0.0

    def g(lm: float) -> float:
        return 2.0 * lm * math.hypot(mu, lam_f + lm) - ct

    hi = math.copysign(math.sqrt(abs(ct) / 2.0), ct)
    for _ in range(200):
        if g(hi) * ct > 0.0:
            return brentq(g, min(0.0, hi), max(0.0, hi), xtol=1e-300,
                          rtol=4 * np.finfo(float).eps)
        hi *= 2.0
    return math.copysign(math.sqrt(abs(ct) / 2.0), ct)


class DynamicInflowSet(ElementSet):
    """All inflow elements: f = −V L⁻¹ α on their state rows with the dense ∂f/∂α."""

    nonconservative = True

    def __init__(self, elements: list, system) -> None:
        super().__init__(elements, system)
        self._idx = [system.offset[e] + np.arange(e.n_states) for e in self.elements]
        cat = np.concatenate
        self.force_idx = cat(self._idx)
        self.fq_rows = cat([np.repeat(i, len(i)) for i in self._idx])
        self.fq_cols = cat([np.tile(i, len(i)) for i in self._idx])

    def force(self, q: Array, v: Array, t: float) -> Array:
        return np.concatenate([e.rhs(q[i]) for e, i in zip(self.elements, self._idx, strict=True)])

    def force_jacobians(self, q: Array, v: Array, t: float) -> tuple[Array, Array]:
        jac = [e.rhs(q[i], jacobian=True)[1].ravel()
               for e, i in zip(self.elements, self._idx, strict=True)]
        return np.concatenate(jac), EMPTY_F


DynamicInflow.set_class = DynamicInflowSet


def _is_real(x) -> bool:
    return (isinstance(x, (int, float, np.integer, np.floating)) and not isinstance(x, bool)
            and math.isfinite(x))


def _is_int(x) -> bool:
    return isinstance(x, (int, np.integer)) and not isinstance(x, bool)
