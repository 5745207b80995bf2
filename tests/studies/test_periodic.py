"""Reaching the periodic response (studies.periodic) against closed-form sequences.

A signal made of a periodic part and decaying free modes, e^{st} with Re s < 0 at frequencies
that are not whole per-rev harmonics (the lag mode, the fuselage, a pendulum), is what a
forced, damped linear system gives after its start. Its periodic part is known exactly, so
the extrapolated limit and the marching can be checked against it.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from studies.parameters import ParameterError
from studies.periodic import (
    PARAMETERS,
    check,
    coarser_steps,
    harmonic_change,
    march,
    resample,
    rev_harmonics,
    richardson,
    rre_weights,
    secant_weights,
    sector_response,
)

OMEGA = 2 * np.pi  # rad/s: one revolution per second
N = 64  # samples per revolution


def periodic_part(t: np.ndarray) -> np.ndarray:
    """Two columns: a 3P/4P response on a mean, and a 1P one."""
    psi = OMEGA * t
    return np.column_stack([2.0 + np.cos(3 * psi) + 0.05 * np.sin(4 * psi + 0.3),
                            0.5 * np.sin(psi - 0.2)])


# free modes: (s per revolution, amplitudes of the two columns); per-rev decay |e^{sT}| from
# 0.87 (a lag mode at 0.27/rev with 4 % damping, aliased) to 0.55
MODES = [(-0.14 + 2j * np.pi * 0.27, (0.8, 0.3)), (-0.05 + 2j * np.pi * 2.93, (0.4, -0.2)),
         (-0.6 + 2j * np.pi * 0.73, (0.5, 0.6))]


def signal(t: np.ndarray) -> np.ndarray:
    out = periodic_part(t)
    for s, amp in MODES:
        e = np.exp(s * t)  # t in revolutions (T = 1 s)
        out = out + np.real(np.outer(e, np.asarray(amp) * (1 + 0.5j)))
    return out


def sampler():
    """(step, sample) that walk through ``signal`` at N samples per revolution."""
    k = [0]

    def step() -> None:
        k[0] += 1

    def sample() -> np.ndarray:
        t = k[0] / N
        return np.concatenate([[t], signal(np.array([t]))[0]])

    return step, sample


def test_rre_is_exact_for_a_linear_sequence():
    """s_j = s* + Σ Re(μ_m^j v_m) with 3 complex modes (6 eigenvalues μ, μ̄): 7 changes
    (8 members) give s* to roundoff."""
    rng = np.random.default_rng(1)
    star = rng.normal(size=20)
    mus = [0.9 * np.exp(0.4j), 0.7 * np.exp(2.0j), 0.95 * np.exp(-1.1j)]
    vs = [rng.normal(size=20) + 1j * rng.normal(size=20) for _ in mus]
    seq = [star + sum(np.real(mu**j * v) for mu, v in zip(mus, vs, strict=True))
           for j in range(8)]
    gamma, residual = rre_weights(seq)
    assert gamma.sum() == pytest.approx(1.0, abs=1e-12)
    est = np.tensordot(gamma, np.array(seq[1:]), axes=1)
    assert np.max(np.abs(est - star)) < 1e-9
    assert residual < 1e-9


def test_march_extrapolates_the_periodic_part():
    """The estimate from 8-revolution windows is the periodic part to the tolerance's order
    after about 12 revolutions; marching alone is still far from it."""
    step, sample = sampler()
    rec = march(step, sample, lambda b: b[:, 1:], steps_per_rev=N, revolutions=2,
                max_revolutions=40, tolerance=1e-6, window=8)
    assert rec.extrapolated and rec.transient <= 14
    t = rec.samples[:, 0]
    assert np.allclose(np.diff(t), 1.0 / N)  # two whole revolutions after the transient
    err = np.abs(rec.samples[:, 1:] - periodic_part(t)).max()
    assert err < 1e-6
    # what marching alone would have recorded at that point: the transient is still there
    marched = signal(t) - periodic_part(t)
    assert np.abs(marched).max() > 1e-3


def test_march_without_extrapolation_is_marched():
    step, sample = sampler()
    rec = march(step, sample, lambda b: b[:, 1:], steps_per_rev=N, revolutions=1,
                max_revolutions=400, tolerance=1e-5, window=0)
    assert not rec.extrapolated
    t = rec.samples[:, 0]
    assert np.allclose(rec.samples[:, 1:], signal(t))  # the marched samples themselves
    # periodic within the tolerance (decay 0.95 per revolution: some 180 revolutions), and
    # as far from the periodic part as the slowest mode's change allows (1/(1 − 0.95))
    assert rec.transient > 150
    cur = rev_harmonics(rec.samples[:, 1:])
    assert harmonic_change(cur, rev_harmonics(periodic_part(t)), None) < 20 * 1e-5


def test_march_raises_when_not_periodic():
    step, sample = sampler()
    with pytest.raises(RuntimeError, match="not periodic after 6 revolutions"):
        march(step, sample, lambda b: b[:, 1:], steps_per_rev=N, revolutions=1,
              max_revolutions=6, tolerance=1e-9, window=4)


def test_floor_judges_a_response_without_vibration_against_it():
    """A hover-like signal: a steady mean and only a decaying free mode (0.7 per rev, its
    amplitude falling by 10 % a revolution). Relative to its own vibratory harmonics the
    change between revolutions stays of order 1 however small the mode gets; against a floor
    it is the mode's size over the floor; a floor below the scale changes nothing."""
    t = np.arange(2 * N) / N

    def revolution(amp: float) -> np.ndarray:
        free = amp * np.exp(-0.105 * t) * np.cos(2 * np.pi * 0.7 * t)
        return np.column_stack([5.0 + free, free])

    for amp in (1e-3, 1e-9):
        both = revolution(amp)
        cur, prev = rev_harmonics(both[N:]), rev_harmonics(both[:N])
        assert harmonic_change(cur, prev, [0, 0], separate_mean=True) > 0.1
        floored = harmonic_change(cur, prev, [0, 0], separate_mean=True, floor=[1.0, 1.0])
        # every harmonic of the free part on the floor's scale (the steady 5 on its own)
        assert floored == pytest.approx(np.abs(cur - prev)[:, 1].max(), rel=1e-12)
        assert floored < amp
    both = revolution(1.0)
    cur, prev = rev_harmonics(both[N:]), rev_harmonics(both[:N])
    assert harmonic_change(cur, prev, [0, 0], True, floor=[1e-3, 1e-3]) == harmonic_change(
        cur, prev, [0, 0], True)


def test_window_of_one_is_refused():
    def params(**kw):  # the attributes check reads, as a model's Parameters has them
        return SimpleNamespace(**{**{name: prm.default for name, prm in PARAMETERS.items()},
                                  "revolutions": 1, "max_revolutions": 10, **kw})
    check(params())
    with pytest.raises(ParameterError, match="extrapolation_window = 1"):
        check(params(extrapolation_window=1))
    with pytest.raises(ParameterError, match="shooting_window = 1"):
        check(params(shooting_window=1))
    with pytest.raises(ParameterError, match="revolutions = 11 must not exceed max_revolutions"):
        check(params(revolutions=11))


def _rows(n: int, revs: int, t0: float, values) -> np.ndarray:
    t = t0 + np.arange(1, n * revs + 1) / (n * OMEGA / (2 * np.pi))
    return np.column_stack([t, values(t)])


def test_richardson_removes_the_h2_term_exactly():
    # a periodic response computed at h and 2h with an error a h² e(t) + b h⁴ g(t) (e, g
    # band-limited to harmonics ≤ 8, as the archive's): the extrapolation leaves −4 b h⁴ g,
    # the fine step's own h⁴ term times (1 − (16 − 1)/3)
    a, b = 40.0, 3e3

    def e(t):
        psi = OMEGA * t
        return np.column_stack([np.cos(3 * psi + 0.4) + 0.2, 0.3 * np.sin(8 * psi)])

    def g(t):
        return np.column_stack([np.sin(2 * OMEGA * t), np.cos(OMEGA * t)])

    h = 1.0 / N
    for bb in (0.0, b):
        def computed(t, step, bb=bb):
            return periodic_part(t) + a * step**2 * e(t) + bb * step**4 * g(t)

        fine = _rows(N, 2, 3.25, lambda t: computed(t, h))
        coarse = _rows(N // 2, 2, 1.5, lambda t: computed(t, 2 * h))
        out, est = richardson(fine, coarse, OMEGA, 8)
        err = out[:, 1:] - periodic_part(fine[:, 0])
        expect = -4 * bb * h**4 * g(fine[:, 0])
        assert np.abs(err - expect).max() < 1e-13
        assert np.array_equal(out[:, 0], fine[:, 0])
        # the estimate: the h² term's largest harmonic against the signal's largest harmonic
        # at h (column 0: |c_3| = ½ a h² against the fine mean 2 + 0.2 a h², with the
        # harmonics c_k of x = c_0 + 2 Re Σ c_k e^{ikψ})
        assert est[0] == pytest.approx(0.5 * a * h**2 / (2.0 + 0.2 * a * h**2), rel=1e-12)
    # any coarser step: H = 1.6 h takes the h² term out with the factor 1/(1.6² − 1)
    fine = _rows(N, 1, 3.0, lambda t: periodic_part(t) + a * h**2 * e(t))
    coarse = _rows(40, 1, 2.0, lambda t: periodic_part(t) + a * (1.6 * h) ** 2 * e(t))
    out, _ = richardson(fine, coarse, OMEGA, 8)
    assert np.abs(out[:, 1:] - periodic_part(fine[:, 0])).max() < 1e-13
    with pytest.raises(ValueError, match="at a coarser step with at least 18 samples"):
        richardson(fine, fine, OMEGA, 8)
    with pytest.raises(ValueError, match="got 64 and 16 samples"):
        richardson(fine, _rows(16, 1, 2.0, periodic_part), OMEGA, 8)


def test_coarser_steps_resolve_the_harmonics():
    assert coarser_steps(40, 4, 8) == 20  # twice the step
    assert coarser_steps(44, 4, 8) == 20  # the largest multiple of the sectors below half
    assert coarser_steps(36, 4, 8) is None  # 16 samples: harmonic 8 is the Nyquist one
    assert coarser_steps(37, 1, 8) == 18
    assert coarser_steps(240, 4, 8, ratio=4 / 3) == 180  # the rotor's companion
    assert coarser_steps(242, 4, 8, ratio=4 / 3) == 180
    with pytest.raises(ValueError, match="ratio"):
        coarser_steps(240, 4, 8, ratio=1.0)


def test_resample_puts_a_sectors_samples_at_the_coarser_steps_times():
    """Every other sample at twice the step; at 3/4 of the steps a cubic spline, whose error
    at 240 steps a revolution is O(h⁴): measured 4.9e-5 of harmonic 8's amplitude (its largest
    near the block's ends) and 1.1e-6 of harmonic 3's."""
    h = 1.0 / 240  # s, one revolution per second
    t = (np.arange(60) + 1) * h + 0.25  # the second quarter revolution
    signal = np.column_stack([np.cos(2 * np.pi * 8 * t), np.sin(2 * np.pi * 3 * t)])
    block = np.column_stack([t, signal])
    np.testing.assert_array_equal(resample(block, 30), block[1::2])
    coarse = resample(block, 45)
    np.testing.assert_allclose(coarse[:, 0], 0.25 + (np.arange(45) + 1) / 180, atol=1e-15)
    exact = np.column_stack([np.cos(2 * np.pi * 8 * coarse[:, 0]),
                             np.sin(2 * np.pi * 3 * coarse[:, 0])])
    assert np.abs(coarse[:, 1] - exact[:, 0]).max() < 1e-4
    assert np.abs(coarse[:, 2] - exact[:, 1]).max() < 3e-6


class _Ring:
    """A linear, periodically forced discrete system with a quarter-revolution symmetry,
    stepped like an integrator: four damped oscillators (u_i + i w_i turns by 0.3 rad and
    shrinks by 0.97 a step), oscillator i forced by f(ψ + iπ/2), f(ψ) = cos ψ + 0.3 sin 3ψ
    + 0.2 cos 4ψ, so that oscillator i a quarter revolution later is oscillator i + 1 now,
    and their sum (the 4P part) repeats every quarter revolution."""

    def __init__(self, n: int, z0: np.ndarray) -> None:
        self.h = 1.0 / n  # s (one revolution per second)
        self.t, self.z, self.n_steps = 0.0, np.array(z0, dtype=complex), 0
        self.mu = 0.97 * np.exp(0.3j)

    def force(self, t: float) -> np.ndarray:
        psi = OMEGA * t + np.arange(4) * np.pi / 2
        return np.cos(psi) + 0.3 * np.sin(3 * psi) + 0.2 * np.cos(4 * psi)

    def step(self):
        self.t += self.h
        self.z = self.mu * self.z + self.h * self.force(self.t)
        self.n_steps += 1
        return type("Info", (), {"converged": True, "message": ""})()

    def sample(self) -> np.ndarray:
        u = self.z.real
        return np.concatenate([[self.t], [u.sum()], u])

    def periodic(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The exact periodic state at t = 0 and one revolution of samples from it."""
        g = np.zeros(4, dtype=complex)
        for k in range(1, n + 1):  # one revolution from z = 0
            g = self.mu * g + self.h * self.force(k * self.h)
        z0 = g / (1 - self.mu**n)
        ring = _Ring(n, z0)
        rows = []
        for _ in range(n):
            ring.step()
            rows.append(ring.sample())
        return z0, np.array(rows)


def _sector_blocks(ring: _Ring, align, count: int) -> list[np.ndarray]:
    """The ring's next ``count`` quarter revolutions' blocks of samples from t = 0, each
    aligned to the phase of t = 0."""
    out = []
    for j in range(1, count + 1):
        rows = []
        for _ in range(round(1 / ring.h) // 4):
            ring.step()
            rows.append(ring.sample())
        out.append(align(np.array(rows), j))
    return out


def _aligner(n_sectors: int):
    """``align`` for the ring: a sector is 4/n_sectors quarter revolutions."""
    def align(block: np.ndarray, j: int) -> np.ndarray:
        out = block.copy()  # column 1 (the sum) repeats every quarter revolution
        out[:, 2:] = np.roll(block[:, 2:], j * (4 // n_sectors), axis=1)
        return out
    return align


@pytest.mark.parametrize("n_sectors", [4, 1])
def test_sector_response_is_the_periodic_response_at_the_other_step(n_sectors):
    """Started from the exact periodic state at twice the steps (as after shooting), the
    extrapolated iterates of the quarter-revolution map (10 of them) or of the one-revolution
    map (6) give this step's exact periodic revolution to roundoff (measured 1e-14 of the
    change between the two steps); cut short, it says it is uncertain."""
    n = 24
    z_fine, fine = _Ring(2 * n, np.zeros(4)).periodic(2 * n)
    _, exact = _Ring(n, np.zeros(4)).periodic(n)
    change = np.abs(rev_harmonics(exact[:, 1:]) - rev_harmonics(fine[1::2, 1:])).max()
    assert change > 0.1  # the two steps' responses differ

    def run(max_iterates: int):
        ring = _Ring(n, z_fine)
        rev, uncertainty, iterates = sector_response(
            ring, ring.sample, _aligner(n_sectors), n_sectors=n_sectors, steps_per_rev=n,
            reference=fine, omega=OMEGA, accuracy=1e-8, max_iterates=max_iterates)
        assert iterates == ring.n_steps * n_sectors // n
        err = np.abs(rev_harmonics(rev[:, 1:]) - rev_harmonics(exact[:, 1:])).max()
        return rev, uncertainty, iterates, err

    rev, uncertainty, iterates, err = run(40)
    assert uncertainty <= 1e-8 and iterates == {4: 10, 1: 6}[n_sectors]
    assert err < 1e-12 * change
    assert np.allclose(rev[:, 0], exact[:, 0], rtol=0, atol=1e-12)  # from the start
    _, uncertainty, *_ = run(iterates - 2)
    assert uncertainty > 1e-3
    ring = _Ring(n, z_fine)
    ring.step()  # off the sector boundary
    with pytest.raises(ValueError, match="not a whole sector period"):
        sector_response(ring, ring.sample, _aligner(n_sectors), n_sectors=n_sectors,
                        steps_per_rev=n, reference=fine, omega=OMEGA)
    with pytest.raises(ValueError, match="max_iterates = 3: must be at least 4"):
        sector_response(_Ring(n, z_fine), ring.sample, _aligner(n_sectors),
                        n_sectors=n_sectors, steps_per_rev=n, reference=fine, omega=OMEGA,
                        max_iterates=3)


def test_sector_response_with_the_slow_modes_known_from_other_iterates():
    """Given the iterates of the same map from another start (what shooting extrapolated),
    the secant step finds the periodic response in four iterates (the least it checks):
    exact to roundoff (measured 1.2e-14 of the change), against ten without them; the history
    is checked for shape."""
    n = 24
    z_fine, fine = _Ring(2 * n, np.zeros(4)).periodic(2 * n)
    _, exact = _Ring(n, np.zeros(4)).periodic(n)
    change = np.abs(rev_harmonics(exact[:, 1:]) - rev_harmonics(fine[1::2, 1:])).max()
    align = _aligner(4)
    other = _Ring(n, np.ones(4))  # a transient from another start
    history = []
    for j in range(1, 11):
        rows = []
        for _ in range(n // 4):
            other.step()
            rows.append(other.sample())
        history.append(align(np.array(rows), j))
    ring = _Ring(n, z_fine)
    rev, uncertainty, iterates = sector_response(
        ring, ring.sample, align, n_sectors=4, steps_per_rev=n, reference=fine, omega=OMEGA,
        accuracy=1e-8, min_iterates=4, history=[history])
    err = np.abs(rev_harmonics(rev[:, 1:]) - rev_harmonics(exact[:, 1:])).max()
    assert iterates == 4 and uncertainty <= 1e-8 and err < 1e-12 * change, (iterates, err)
    with pytest.raises(ValueError, match="history blocks must be 6 samples of 6 columns"):
        sector_response(_Ring(n, z_fine), ring.sample, align, n_sectors=4, steps_per_rev=n,
                        reference=fine, omega=OMEGA, history=[[h[::2] for h in history]])


def test_sector_response_with_the_maps_jacobian_known_as_pairs():
    """Given the map's Jacobian as secant pairs of blocks (U, JU): each of the ring's eight
    state directions perturbed, the first block's change and the next one's (what the
    multipliers' Arnoldi run gives, :meth:`solver.period_map.SlowSubspace.pairs`), the
    secant step finds the periodic response in four iterates (the least it checks), exact to
    roundoff (measured 3.1e-15 of the change), with no other start's iterates; pairs
    of the wrong shape are refused."""
    n = 24
    z_fine, fine = _Ring(2 * n, np.zeros(4)).periodic(2 * n)
    _, exact = _Ring(n, np.zeros(4)).periodic(n)
    change = np.abs(rev_harmonics(exact[:, 1:]) - rev_harmonics(fine[1::2, 1:])).max()
    align = _aligner(4)

    def blocks(z0: np.ndarray) -> list[np.ndarray]:  # two sectors' aligned blocks from z0
        return _sector_blocks(_Ring(n, z0), align, 2)

    base = blocks(np.zeros(4))
    directions = [*np.eye(4), *(1j * np.eye(4))]
    u = np.array([blocks(d)[0] - base[0] for d in directions])
    ju = np.array([blocks(d)[1] - base[1] for d in directions])
    ring = _Ring(n, z_fine)
    rev, uncertainty, iterates = sector_response(
        ring, ring.sample, align, n_sectors=4, steps_per_rev=n, reference=fine, omega=OMEGA,
        accuracy=1e-8, min_iterates=4, pairs=(u, ju))
    err = np.abs(rev_harmonics(rev[:, 1:]) - rev_harmonics(exact[:, 1:])).max()
    assert iterates == 4 and uncertainty <= 1e-8 and err < 1e-12 * change, (iterates, err)
    # judged as the periodicity test judges (vibratory harmonics against the vibratory scale)
    ring = _Ring(n, z_fine)
    again, uncertainty, iterates = sector_response(
        ring, ring.sample, align, n_sectors=4, steps_per_rev=n, reference=fine, omega=OMEGA,
        accuracy=1e-8, min_iterates=4, pairs=(u, ju), separate_mean=True)
    assert iterates == 4 and uncertainty <= 1e-8 and np.array_equal(again, rev)
    with pytest.raises(ValueError, match="pairs must be two arrays of blocks of 6 samples"):
        sector_response(_Ring(n, z_fine), ring.sample, align, n_sectors=4, steps_per_rev=n,
                        reference=fine, omega=OMEGA, pairs=(u[:, ::2], ju[:, ::2]))


def test_secant_pairs_of_another_map_leave_the_change_unexplained():
    """The quantity sector_response's guard reads: secant pairs from iterates of the same map
    (another start) explain this run's first change (unexplained part 3e-14); pairs from
    another map (the ring with other damping and turn) do not (0.15, above sector_response's
    ``max_residual`` 0.1), so no estimate counts until this map's own pairs explain it: the
    response found is still this step's (1.9e-14 of the change, after 10 iterates)."""
    n = 24
    z_fine, fine = _Ring(2 * n, np.zeros(4)).periodic(2 * n)
    _, exact = _Ring(n, np.zeros(4)).periodic(n)
    change = np.abs(rev_harmonics(exact[:, 1:]) - rev_harmonics(fine[1::2, 1:])).max()
    align = _aligner(4)

    same = _sector_blocks(_Ring(n, np.ones(4)), align, 10)
    other_ring = _Ring(n, np.ones(4))
    other_ring.mu = 0.9 * np.exp(0.5j)
    other = _sector_blocks(other_ring, align, 10)
    own = _sector_blocks(_Ring(n, z_fine), align, 2)
    _, consistent = secant_weights([[b[:, 1:] for b in same], [b[:, 1:] for b in own]])
    _, inconsistent = secant_weights([[b[:, 1:] for b in other], [b[:, 1:] for b in own]])
    assert consistent < 1e-10 and inconsistent > 0.1, (consistent, inconsistent)
    ring = _Ring(n, z_fine)
    rev, _, count = sector_response(ring, ring.sample, align, n_sectors=4, steps_per_rev=n,
                                    reference=fine, omega=OMEGA, min_iterates=4,
                                    history=[other], max_iterates=40)
    err = np.abs(rev_harmonics(rev[:, 1:]) - rev_harmonics(exact[:, 1:])).max()
    assert err < 1e-10 * change and count > 4, (err / change, count)
