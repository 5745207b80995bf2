"""The N-link chain side by side with Exudyn, at equal accuracy.

Both codes integrate the chain of ``benchmarks/chain.py`` (1 kg, 1 m slender links on
revolute joints about z, released horizontal under gravity) for 1 s at h = 1 ms with
generalized-α, ρ∞ = 0.8, and a sparse solver. Each result is compared with the same reference,
this solver at h/8 with a roundoff-level Newton tolerance, through the links' centre
positions at t = 1 s. The two codes' own references agree to about 1e-9 m, which checks the
comparison itself.

Exudyn's default Newton test (relative residual 1e-8) leaves its error at the time
discretization's level. This solver's ``--tol`` sets the Newton tolerance on q relative to
the chain's size; 1e-10 leaves the error within 1 % of the discretization's, as the printed
errors show. Each timing is the best of ``--repeat`` runs (wall time of the time loop only;
model building and output excluded for both).

    pip install exudyn==1.13.6      # optional: only this benchmark uses it
    python benchmarks/chain_exudyn.py --links 16 64
"""

from __future__ import annotations

import argparse
import time
import warnings

import numpy as np
from chain import chain

from solver.simulation import simulate

H = 1e-3  # s
T_END = 1.0  # s
RHO_INF = 0.8


def ours(links: int, h: float, tol: float | None,
         scheme: str = "galpha") -> tuple[float, np.ndarray, dict]:
    """Wall time of the time loop (s), link centres at T_END (links × 3, m), counters."""
    rho = RHO_INF if scheme == "galpha" else None
    sim = simulate(chain(links), T_END, h, scheme=scheme, rho_inf=rho,
                   record_every=round(T_END / h), reactions=False, tol=tol)
    s, q = sim.integrator.sys, sim.integrator.q
    pos = np.array([q[s.offset[b] : s.offset[b] + 3] for b in s.bodies
                    if b.name.startswith("link")])
    e = sim.dataset.energy.values
    scale = s.kinetic(sim.integrator.v)  # released at rest from zero potential: E = 0
    info = {"newton_iterations_per_step": float(sim.dataset.newton_iterations[1:].mean()),
            "factorizations": sim.integrator.n_factorizations,
            "energy_drift_relative": float(np.abs(e - e[0]).max() / scale)}
    return sim.seconds, pos, info


def exudyn_chain(links: int, h: float) -> tuple[float, np.ndarray, dict]:
    """The same chain in Exudyn: rigid bodies with Euler parameters, revolute joints."""
    import exudyn as exu
    from exudyn.utilities import RigidBodyInertia

    sc = exu.SystemContainer()
    mbs = sc.AddSystem()
    prev = mbs.CreateGround(referencePosition=[0.0, 0.0, 0.0])
    nodes = []
    j_rod = 1.0 / 12.0
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)
        for i in range(links):
            b = mbs.CreateRigidBody(
                inertia=RigidBodyInertia(mass=1.0, inertiaTensor=np.diag([0.0, j_rod, j_rod])),
                referencePosition=[i + 0.5, 0.0, 0.0], gravity=[0.0, -9.81, 0.0],
                returnDict=True)
            mbs.CreateRevoluteJoint(bodyNumbers=[prev, b["bodyNumber"]],
                                    position=[float(i), 0.0, 0.0], axis=[0.0, 0.0, 1.0])
            prev = b["bodyNumber"]
            nodes.append(b["nodeNumber"])
        mbs.Assemble()
        s = exu.SimulationSettings()
        s.timeIntegration.numberOfSteps = round(T_END / h)
        s.timeIntegration.endTime = T_END
        s.timeIntegration.generalizedAlpha.spectralRadius = RHO_INF
        s.timeIntegration.verboseMode = 0
        s.solutionSettings.writeSolutionToFile = False
        s.linearSolverType = exu.LinearSolverType.EigenSparse
    t0 = time.perf_counter()
    mbs.SolveDynamic(s)
    seconds = time.perf_counter() - t0
    pos = np.array([mbs.GetNodeOutput(nd, exu.OutputVariableType.Position) for nd in nodes])
    solver = mbs.sys["dynamicSolver"]
    its = solver.it.newtonStepsCount / max(1, solver.it.currentStepIndex)
    return seconds, pos, {"newton_iterations_per_step": float(its),
                          "exudyn": exu.__version__}


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--links", type=int, nargs="+", default=[16, 64])
    p.add_argument("--tol", type=float, default=1e-10,
                   help="this solver's Newton tolerance (relative to the chain's size)")
    p.add_argument("--repeat", type=int, default=3, help="timings: best of this many runs")
    a = p.parse_args()
    try:
        import exudyn  # noqa: F401
        have_exudyn = True
    except ImportError:
        have_exudyn = False
        print("exudyn is not installed (pip install exudyn==1.13.6): this solver only")
    for n in a.links:
        _, ref, _ = ours(n, H / 8, None)
        runs = [ours(n, H, a.tol) for _ in range(a.repeat)]
        t_ours = min(r[0] for r in runs)
        err = float(np.abs(runs[0][1] - ref).max())
        print(f"N = {n:3d}  this solver  galpha: {t_ours:7.3f} s  {1 / H / t_ours * T_END:7.0f}"
              f" steps/s  error {err:.2e} m  Newton iterations/step "
              f"{runs[0][2]['newton_iterations_per_step']:.2f}")
        if have_exudyn:
            _, xref, _ = exudyn_chain(n, H / 8)
            xruns = [exudyn_chain(n, H) for _ in range(a.repeat)]
            t_x = min(r[0] for r in xruns)
            xerr = float(np.abs(xruns[0][1] - ref).max())
            print(f"         Exudyn {xruns[0][2]['exudyn']} galpha: {t_x:7.3f} s  "
                  f"{1 / H / t_x * T_END:7.0f} steps/s  error {xerr:.2e} m  Newton "
                  f"iterations/step {xruns[0][2]['newton_iterations_per_step']:.2f}  "
                  f"(references differ by {np.abs(xref - ref).max():.1e} m)  "
                  f"time ratio {t_ours / t_x:.2f}")
        t_ep, _, info = ours(n, H, None, scheme="ep")
        print(f"         this solver  ep: {t_ep:7.3f} s  energy conserved to "
              f"{info['energy_drift_relative']:.1e} relative")


if __name__ == "__main__":
    main()
