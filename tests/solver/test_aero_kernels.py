"""The compiled lifting-line kernels (solver/aero_kernels.py) against independent computations.

The reference is a vectorized NumPy transcription of the section formulas of
:mod:`solver.lifting_line` (all sections at once, dense 12 × 48 support maps S, the inflow's own
``shape`` and ``load_weights``), run on real and on complex inputs. Checked, on a twisted beam
line in forward flight with a Peters–He inflow (drag, quarter-chord offset, tip loss), the same
with a prescribed periodic wind at the sections, on body lines with the Pitt–Peters inflow, and
on quasi-steady sections (no wake states):

* the forces, the wake-state rates, the inflow forcing and every ``airloads`` output;
* the local Jacobian (compiled complex steps, one input at a time, the inflow shapes taken at
  the stepped positions) against complex steps of the reference, column by column;
* the global Jacobian blocks (nonzeros of S) against the dense products Sᵀ ds J S.

Random states well off equilibrium (nonzero rates and accelerations everywhere). Measured
agreement: ≤ 6e-15 of each array's largest entry; asserted at 1e-13.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from solver.air import FlightCondition
from solver.inflow import DynamicInflow
from solver.lifting_line import COMPLEX_STEP, LiftingLineSet
from solver.system import System
from tests.solver.lifting_line_models import RHO, beam_line, rotor

TOL = 1e-13
T = 0.137  # s: the time the kernels are called at (a prescribed wind between its samples)


MODELS = {
    "beam, peters-he": lambda: beam_line(zero_lift_angle=-0.03)[0],
    "beam, peters-he, wind": lambda: beam_line(zero_lift_angle=-0.03, wind=True)[0],
    "bodies, pitt-peters": lambda: rotor(np.radians(8.0), flight=FlightCondition(20.0, 0.05,
                                                                                RHO))[0],
    "bodies, quasi-steady": lambda: rotor(np.radians(8.0), n=0)[0],
}


def reference(st: LiftingLineSet, x, xd, xa, mu, al) -> dict:
    """The section formulas of solver/lifting_line.py's docstring, vectorized in NumPy over
    the sections (real or complex inputs (K, ·))."""

    def dot(a, b):
        return np.einsum("...i,...i->...", a, b)

    rho, b, ct, st_ = st.rho, st.b, st.cos_t, st.sin_t
    xq = st.xq
    pos, d1, d2, d3 = x[:, 0:3], x[:, 3:6], x[:, 6:9], x[:, 9:12]
    vel, dd2, dd3 = xd[:, 0:3], xd[:, 6:9], xd[:, 9:12]
    acc, ad2, ad3 = xa[:, 0:3], xa[:, 6:9], xa[:, 9:12]
    ec = ct[:, None] * d2 + st_[:, None] * d3
    en = -st_[:, None] * d2 + ct[:, None] * d3
    dec = ct[:, None] * dd2 + st_[:, None] * dd3
    den = -st_[:, None] * dd2 + ct[:, None] * dd3
    aec = ct[:, None] * ad2 + st_[:, None] * ad3
    vair = st.air(T).astype(pos.dtype)  # the free stream and the wind at each section
    if st.n_i:
        xi, eta = st.inflow.disk_coordinates(pos)
        lam = dot(st.inflow.shape(xi, eta), al)
        vair = vair - (lam * st.omega_r)[:, None] * np.array([0.0, 0.0, 1.0])
    xm, x34 = xq - 0.5 * b, xq - b
    w_mid = vair - vel - xm[:, None] * dec
    w_34 = vair - vel - x34[:, None] * dec
    w_qc = vair - vel - xq[:, None] * dec
    u = -dot(w_mid, ec)
    w0, w34 = dot(w_mid, en), dot(w_34, en)
    w1 = b * dot(dec, en)
    if st.n:
        lam0 = dot(mu, st.pb) + st.kappa * w34
        rates = -(np.sqrt(u * u + st.u_floor2) / b)[:, None] * (mu + w34[:, None] * st.ainv_c)
    else:
        lam0 = 0.0 * w34
        rates = np.zeros((len(b), 0), dtype=w34.dtype)
    wc = w34 - lam0
    gam = st.a_lift * b * wc
    f_qc = (rho * gam)[:, None] * (u[:, None] * en + wc[:, None] * ec)
    wp = w_qc - (dot(w_qc, d1) / dot(d1, d1))[:, None] * d1
    f_qc = f_qc + (rho * b * st.cd0 * np.sqrt(dot(wp, wp)))[:, None] * wp
    w0dot = -dot(acc + xm[:, None] * aec, en) + dot(w_mid, den)
    w1dot = b * (dot(aec, en) + dot(dec, den))
    pib2 = math.pi * rho * b * b
    l_nc = pib2 * w0dot
    m_nc = -pib2 * (0.5 * u * w1 + 0.125 * b * w1dot)
    f_mid = l_nc[:, None] * en
    g = np.zeros(x.shape, dtype=np.result_type(x, xd, xa, mu, al))
    g[:, 0:3] = f_qc + f_mid
    for col, c in ((6, ct), (9, st_)):
        g[:, col : col + 3] = (xq * c)[:, None] * f_qc + (xm * c)[:, None] * f_mid
    mvec = m_nc[:, None] * d1
    for i, d in enumerate((d1, d2, d3)):
        g[:, 3 + 3 * i : 6 + 3 * i] += 0.5 * np.cross(mvec, d)
    ftot = f_qc + f_mid
    if st.n_i:
        forcing = st.inflow.load_weights(xi, eta) * (ftot[:, 2] * st.ds * st.load_scale)[:, None]
    else:
        forcing = np.zeros((len(b), 0), dtype=g.dtype)
    return {"g": g, "rates": rates, "forcing": forcing, "force": ftot, "circulatory": f_qc,
            "u": u, "w0": w0, "w34": w34, "lam0": lam0, "lift": rho * gam * u,
            "apparent_lift": l_nc, "apparent_moment": m_nc, "position": pos, "air": vair}


def local_inputs(st: LiftingLineSet, q, v, a):
    """x, xd, xa (K, 12) = S q, S v, S a with the dense S; μ (K, N); α (K, n_i)."""
    xs = st.S @ np.stack([q[st.idx48], v[st.idx48], a[st.idx48]], axis=2)
    return (xs[:, :, 0], xs[:, :, 1], xs[:, :, 2], q[st.state_idx],
            np.broadcast_to(q[st.inflow_idx], (st.K, st.n_i)))


def relerr(new, ref) -> float:
    new, ref = np.asarray(new), np.asarray(ref)
    assert new.shape == ref.shape
    scale = np.abs(ref).max() if ref.size else 0.0
    return float(np.abs(new - ref).max() / scale) if scale > 0 else float(np.abs(new).max()
                                                                          if new.size else 0.0)


@pytest.fixture(scope="module", params=list(MODELS))
def case(request):
    system = System(MODELS[request.param]())
    st = next(s for s in system.sets if isinstance(s, LiftingLineSet))
    rng = np.random.default_rng(11)
    q = system.q0_raw + 1e-2 * rng.standard_normal(system.n)
    v = 3.0 * rng.standard_normal(system.n)
    a = 30.0 * rng.standard_normal(system.n)
    return st, q, v, a


def test_forces_and_airloads_match_the_numpy_formulas(case):
    st, q, v, a = case
    ref = reference(st, *local_inputs(st, q, v, a))
    fs = (ref["g"] * st.ds[:, None])[:, None, :] @ st.S  # Sᵀ g ds
    expect = np.concatenate([fs[:, 0], ref["rates"], ref["forcing"]], axis=1).ravel()
    assert relerr(st.force(q, v, T, a), expect) < TOL
    out = st.airloads(q, v, a, T)
    for key in ("force", "circulatory", "u", "w0", "w34", "lam0", "lift", "apparent_lift",
                "apparent_moment", "position", "air"):
        assert relerr(out[key], np.broadcast_to(ref[key], out[key].shape)) < TOL, key


def test_local_jacobian_matches_complex_steps_of_the_numpy_formulas(case):
    st, q, v, a = case
    x, xd, xa, mu, al = local_inputs(st, q, v, a)
    st._cache = None
    jac = st._local_jacobian(q, v, a, T)
    # columns: x (12), μ (N), α (n_i), ẋ (12), ẍ (12)
    cols = ([(0, c) for c in range(12)] + [(3, c) for c in range(st.n)]
            + [(4, c) for c in range(st.n_i)] + [(1, c) for c in range(12)]
            + [(2, c) for c in range(12)])
    expect = np.empty((st.K, 12 + st.n + st.n_i, len(cols)))
    for j, (which, c) in enumerate(cols):
        ins = [z.astype(complex) for z in (x, xd, xa, mu, al)]
        ins[which][:, c] += 1j * COMPLEX_STEP
        r = reference(st, *ins)
        expect[:, :, j] = np.concatenate([r["g"], r["rates"], r["forcing"]],
                                         axis=1).imag / COMPLEX_STEP
    assert relerr(jac, expect) < TOL


def test_global_jacobian_blocks_are_the_dense_products(case):
    st, q, v, a = case
    st._cache = None
    jac = st._local_jacobian(q, v, a, T)
    n, ni = st.n, st.n_i
    st_t = np.swapaxes(st.S, 1, 2)

    def rows(j):  # local output rows to global ones: Sᵀ ds on the 12 force components
        return np.concatenate([st_t @ (j[:, :12] * st.ds[:, None, None]), j[:, 12:]], axis=1)

    jq = rows(jac[:, :, : 12 + n + ni])
    dq = np.concatenate([jq[:, :, :12] @ st.S, jq[:, :, 12:]], axis=2)
    dv = rows(jac[:, :, 12 + n + ni : 24 + n + ni]) @ st.S
    da = rows(jac[:, :, 24 + n + ni :]) @ st.S
    got_q, got_v = st.force_jacobians(q, v, T, a)
    assert relerr(got_q, dq.ravel()) < TOL
    assert relerr(got_v, dv.ravel()) < TOL
    assert relerr(st.acceleration_jacobian(q, v, T, a), da.ravel()) < TOL


def test_newton_tangent_is_the_weighted_sum_of_the_jacobians(case):
    """The Newton matrix's block from one complex step along a coordinate, its rate and its
    acceleration together (weights of a generalized-α step at 240 steps a revolution: a rate
    weight near 2e3 /s, an acceleration weight near 2e6 /s²) is the sum of the separate
    Jacobians so weighted, to roundoff (measured 2.3e-16–3.4e-16 of its largest entry)."""
    st, q, v, a = case
    wq, wa = -1.0, -2.3e6
    wv = np.full(len(v), -1.9e3)
    st._cache = None
    jq, jv = st.force_jacobians(q, v, T, a)
    ja = st.acceleration_jacobian(q, v, T, a)
    m = 48 + st.n + st.n_i  # a section's support coordinates and states
    expect = wq * jq.reshape(st.K, m, m)
    expect[:, :, :48] += wv[0] * jv.reshape(st.K, m, 48) + wa * ja.reshape(st.K, m, 48)
    assert relerr(st.force_tangent(q, v, T, a, wq, wv, wa), expect.ravel()) < TOL


@pytest.mark.parametrize("model", ["pitt-peters", "peters-he"])
def test_inflow_load_factors(model):
    """W = Φ · factors state by state: 1/π (Pitt–Peters); 1/(4π) for r = 0 and 1/(2π) for
    r ≥ 1 (Peters–He's ½τ)."""
    kw = {"harmonics": 3, "power": 5} if model == "peters-he" else {}
    infl = DynamicInflow("i", FlightCondition(0.0, 0.0, RHO), 5.0, 30.0, model=model, **kw)
    if model == "pitt-peters":
        expect = np.full(3, 1 / math.pi)
    else:
        expect = np.array([(0.25 if r == 0 else 0.5) / math.pi
                           for _, r, _ in infl.harmonic_indices])
    assert np.array_equal(infl.load_factors, expect)
    rng = np.random.default_rng(2)
    xi, eta = rng.uniform(-1, 1, 7), rng.uniform(-1, 1, 7)
    assert np.array_equal(infl.load_weights(xi, eta), infl.shape(xi, eta) * expect)


@pytest.mark.parametrize(("harmonics", "power"), [(0, 0), (2, 3), (8, 12)])
def test_compiled_peters_he_shapes_against_the_polar_form(harmonics, power):
    """DynamicInflow.shape (aero_kernels.peters_he_shapes) on 2-D, broadcast and scalar inputs,
    real and complex, against φ_j^r(r̄) cos rψ / sin rψ in polar form (measured ≤ 1.7e-13 of
    the largest shape at M = 8, P = 12: cancellation in the alternating high-order
    coefficients, in either form), and its complex step along ξ against central differences
    of the polar form."""
    from solver.inflow import peters_he_shape_coefficients, peters_he_states

    infl = DynamicInflow("i", FlightCondition(0.0, 0.0, RHO), 5.0, 30.0, model="peters-he",
                         harmonics=harmonics, power=power)
    states = peters_he_states(harmonics, power)

    def polar(xi, eta):
        rb, psi = np.hypot(xi, eta), np.arctan2(eta, xi)
        return np.stack([np.polyval(peters_he_shape_coefficients(r, j)[::-1], rb * rb) * rb**r
                         * (np.cos(r * psi) if kind == "c" else np.sin(r * psi))
                         for kind, r, j in states], axis=-1)

    rng = np.random.default_rng(5)
    xi, eta = rng.uniform(-0.7, 0.7, (3, 4)), rng.uniform(-0.7, 0.7, (3, 4))
    ref = polar(xi, eta)
    scale = np.abs(ref).max()
    for a, b, expect in ((xi, eta, ref), (xi[0], 0.3, polar(xi[0], np.full(4, 0.3))),
                         (0.2, -0.4, polar(np.array(0.2), np.array(-0.4)))):
        got = infl.shape(a, b)
        assert got.shape == expect.shape
        assert np.abs(got - expect).max() < 1e-12 * scale
    h = 1e-7  # central differences of the polar form: truncation ~ h² ≈ 1e-14
    fd = (polar(xi + h, eta) - polar(xi - h, eta)) / (2 * h)
    cs = infl.shape(xi + 1j * COMPLEX_STEP, eta)
    assert np.abs(cs.real - ref).max() < 1e-12 * scale
    assert np.abs(cs.imag / COMPLEX_STEP - fd).max() <= 1e-6 * np.abs(fd).max()
