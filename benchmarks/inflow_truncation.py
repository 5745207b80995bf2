"""The Peters–He inflow seen by discrete blades, against the truncation (M harmonics, power P).

A Q-bladed rotor's lifting lines load the disk at Q points of the azimuth. This script takes the
inflow element alone (no structure, no airfoil feedback): prescribed blade loads of one
rotating harmonic k, L(r̄, ψ_q) = g(r̄) e^{i k ψ_q} on every blade q, drive the states; the
periodic response of the states is solved exactly, frequency by frequency, from
(K/Ω) α̇ + V L(X)⁻¹ α = F(t) linearized about the steady inflow of the rotor's thrust; and the
inflow that blade 0 sees at a few radii is resolved into rotating harmonics. The table shows
how that blade-seen inflow (per unit load) moves with M and P: the quantity on which the
vibratory loads of the full rotor depend.

Run ``python benchmarks/inflow_truncation.py [--speed U] [--tip-cut]``; it prints the table
and the wall time. ``--tip-cut`` loads the blade as the rotor's lifting lines do (r̄² from 0.1R
to a tip-loss cut at 0.95R); without it the radial loading is the smooth r̄²√(1 − r̄²).
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from solver.air import FlightCondition
from solver.inflow import DynamicInflow

# The UH-60A at the paper's condition (Bauchau, Rodriguez & Chen 2003): R = 8.18 m,
# Ω = 27 rad/s, 150 ft/s with a 3° forward shaft tilt, C_T ≈ 0.0089 (C_T/σ ≈ 0.11).
RADIUS, OMEGA, BLADES = 8.18, 27.0, 4
THRUST_COEFFICIENT = 0.0089
SAMPLES = 256  # azimuth samples of one revolution (resolves the state response to 64P)


def blade_seen_inflow(element: DynamicInflow, harmonic: int, radial, cutout=(0.0, 1.0),
                      sections: int = 64, radii=(0.5, 0.75, 0.9),
                      blades: int = BLADES) -> np.ndarray:
    """Complex rotating harmonics λ̂_h (h = 0…SAMPLES−1) of the inflow blade 0 sees at
    ``radii`` for blade loads g(r̄) e^{i k ψ_q} (k = ``harmonic``), linearized about the
    steady inflow of :data:`THRUST_COEFFICIENT`. Loads are in the units of
    :meth:`DynamicInflow.load_weights` (T = L w / (ρ Ω² R⁴)); shape (SAMPLES, len(radii))."""
    steady = element.steady_states(element.uniform_forcing(THRUST_COEFFICIENT))
    flow = element.flow(steady)
    v = np.full(element.n_states, flow.v_m)
    v[0] = flow.v_t
    damping = v[:, None] * np.linalg.inv(element.l_matrix(flow.skew))
    mass = element.mass_matrix * element.omega  # rotor time Ωt
    x, w = np.polynomial.legendre.leggauss(sections)
    lo, hi = cutout
    rb, wb = lo + (x + 1.0) * (hi - lo) / 2.0, w * (hi - lo) / 2.0
    psi = 2.0 * math.pi * np.arange(SAMPLES) / SAMPLES
    forcing = np.zeros((SAMPLES, element.n_states), complex)
    for q in range(blades):
        pq = psi + 2.0 * math.pi * q / blades
        weights = element.load_weights(np.outer(np.cos(pq), rb), np.outer(np.sin(pq), rb))
        load = (radial(rb) * wb)[None, :] * np.exp(1j * harmonic * pq)[:, None]
        forcing += np.einsum("pin,pi->pn", weights, load)
    fh = np.fft.fft(forcing, axis=0)
    freq = np.fft.fftfreq(SAMPLES, 1.0 / SAMPLES)
    ah = np.array([np.linalg.solve(1j * f * mass + damping, fh[i]) for i, f in enumerate(freq)])
    states = np.fft.ifft(ah, axis=0)
    r = np.asarray(radii)
    shapes = element.shape(np.outer(np.cos(psi), r), np.outer(np.sin(psi), r))
    lam = np.einsum("pin,pn->pi", shapes, states)
    return np.fft.fft(lam, axis=0) / SAMPLES


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--speed", type=float, default=45.72, help="flight speed (m/s)")
    parser.add_argument("--tip-cut", action="store_true",
                        help="the rotor's loading: r̄² from 0.1R to a tip-loss cut at 0.95R")
    args = parser.parse_args()
    flight = FlightCondition(args.speed, math.radians(3.0), 1.225)
    if args.tip_cut:
        def radial(x):
            return x**2
        cutout = (0.1, 0.95)
    else:
        def radial(x):
            return x**2 * np.sqrt(1.0 - x**2)
        cutout = (0.0, 1.0)
    print(f"blade-seen inflow per unit load, speed {args.speed} m/s, "
          f"{'tip-cut' if args.tip_cut else 'smooth'} radial loading; columns: "
          "Re λ̂_0 of a steady load at r̄ = 0.5, 0.75, 0.9 | |λ̂_3| of a 3P load at r̄ = 0.75 "
          "| |λ̂_1| of a 1P load at r̄ = 0.75")
    start = time.perf_counter()
    for m in (1, 2, 3, 4, 5, 6, 8, 10, 12, 16):
        for p in (m + 1, m + 11):
            e = DynamicInflow("inflow", flight, RADIUS, OMEGA, harmonics=m, power=p)
            l0 = blade_seen_inflow(e, 0, radial, cutout)
            l3 = blade_seen_inflow(e, 3, radial, cutout)
            l1 = blade_seen_inflow(e, 1, radial, cutout)
            print(f"M = {m:2d}  P = {p:2d}  states {e.n_states:3d}: "
                  + " ".join(f"{l0[0, i].real:7.4f}" for i in range(3))
                  + f" | {abs(l3[3, 1]):7.4f} | {abs(l1[1, 1]):7.4f}")
    print(f"wall time {time.perf_counter() - start:.1f} s")


if __name__ == "__main__":
    main()
