"""Run a model in time and collect the results as an ``xarray.Dataset``."""

from __future__ import annotations

import time as _time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import xarray as xr

from solver.beams import Beam, SectionProbe
from solver.bodies import PointMass, PrescribedBody
from solver.integrators import Integrator, make_integrator
from solver.joints import Joint, Revolute
from solver.rotations import wiener_milenkovic_from_matrix
from solver.system import System


@dataclass
class Simulation:
    """Outcome of :func:`simulate`: the dataset plus status (failure is a value)."""

    dataset: xr.Dataset
    converged: bool
    message: str
    integrator: Integrator
    seconds: float
    extra: dict = field(default_factory=dict)


def simulate(model, t_end: float, h: float, scheme: str = "ep", rho_inf: float | None = None,
             record_every: int = 1, reactions: bool = True,
             callback: Callable[[Integrator], None] | None = None,
             reuse_jacobian: bool = True, system: System | None = None,
             record_initial: bool = False, tol: float | None = None,
             out: str | None = None) -> Simulation:
    """Integrate ``model`` from t = 0 to ``t_end`` (s) with step ``h`` (s).

    Parameters
    ----------
    scheme
        ``"ep"`` energy preserving, ``"ed"`` energy decaying, ``"galpha"`` generalized-α.
    rho_inf
        Spectral radius at infinite frequency for ``ed`` (default 0) and ``galpha`` (0.8).
    record_every
        Store the configuration every this many steps (energy, work, violation and Newton
        iterations are stored every step).
    out
        If given, the results are also written to this netCDF file.
    tol
        Newton tolerance on q relative to its scale (default
        :data:`solver.integrators.CONSTRAINT_TOL`, 3e-15).
    callback
        Called with the integrator after every converged step (e.g. to record study outputs),
        and once before the first step if ``record_initial``.

    Returns
    -------
    Simulation
        ``converged`` false (with ``message``) if a step failed; the dataset then holds the
        steps computed before the failure.
    """
    if not (np.isfinite(t_end) and t_end > 0):
        raise ValueError(f"t_end = {t_end!r} s must be > 0")
    if not t_end >= h:
        raise ValueError(f"t_end = {t_end!r} s must be at least one time step h = {h!r} s")
    if record_every < 1:
        raise ValueError(f"record_every = {record_every!r} must be ≥ 1")
    s = system if system is not None else System(model)
    kw = {} if tol is None else {"tol": tol}
    integ = make_integrator(s, scheme, h, rho_inf=rho_inf, reuse_jacobian=reuse_jacobian, **kw)
    n_steps = round(t_end / h)
    rec = _Recorder(s, reactions)
    rec.record(integ, 0)
    energy = [integ.energy()]
    work = [0.0]
    viol = [integ.violation()]
    iters = [0]
    ok, msg = True, ""
    if callback is not None and record_initial:
        callback(integ)
    t0 = _time.perf_counter()
    for k in range(1, n_steps + 1):
        info = integ.step()
        if not info.converged:
            ok, msg = False, f"step {k} at t = {integ.t:.6g} s: {info.message}"
            break
        energy.append(integ.energy())
        work.append(integ.work)
        viol.append(integ.violation())
        iters.append(info.iterations)
        if k % record_every == 0:
            rec.record(integ, k)
        if callback is not None:
            callback(integ)
    seconds = _time.perf_counter() - t0
    ds = rec.dataset()
    tt = np.arange(len(energy)) * h
    ds = ds.assign_coords(step_time=("step_time", tt, {"units": "s", "long_name": "time"}))
    ds["energy"] = ("step_time", np.array(energy), {"units": "J", "long_name": "total energy"})
    ds["work"] = ("step_time", np.array(work), {
        "units": "J", "long_name": "work of applied loads, dampers and drivers since t = 0"})
    ds["constraint_violation"] = ("step_time", np.array(viol), {
        "units": "1", "long_name": "max |C| over holonomic constraints (m or dimensionless)"})
    ds["newton_iterations"] = ("step_time", np.array(iters, dtype=np.int32), {
        "units": "1", "long_name": "Newton iterations of the step"})
    ds.attrs.update(scheme=scheme, time_step=h, converged=int(ok), message=msg,
                    solver_seconds=seconds)
    if out is not None:
        ds.to_netcdf(out)
    return Simulation(ds, ok, msg, integ, seconds)


class _Recorder:
    def __init__(self, s: System, reactions: bool) -> None:
        self.s = s
        self.bodies = [b for b in s.bodies if not (isinstance(b, PrescribedBody)
                                                   and b.name == "ground")]
        self.revolutes = s.model.of_type(Revolute)
        self.joints = s.model.of_type(Joint) if reactions else []
        self.beams = s.model.of_type(Beam)
        self.probes = [SectionProbe(b, b.node_s) for b in self.beams]
        self.loads: list = []
        self.t, self.x, self.r, self.v, self.w = [], [], [], [], []
        self.phi, self.f, self.m, self.sc = [], [], [], []
        self._phi_prev = None

    def record(self, integ: Integrator, k: int) -> None:
        s, q, v = self.s, integ.q, integ.v
        self.t.append(integ.t)
        xs, rs, vs, ws = [], [], [], []
        for b in self.bodies:
            o = s.offset[b]
            xs.append(q[o : o + 3])
            if isinstance(b, PrescribedBody):  # report the driver's exact velocities
                _, _, vel, w, *_ = b.motion(integ.t)
                vs.append(np.asarray(vel, dtype=float))
                rs.append(s.directors(q, b))
                ws.append(np.asarray(w, dtype=float))
                continue
            vs.append(v[o : o + 3])
            if isinstance(b, PointMass):
                rs.append(np.eye(3))
                ws.append(np.zeros(3))
            else:
                rs.append(s.directors(q, b))
                ws.append(s.angular_velocity(q, v, b))
        self.x.append(xs)
        self.r.append(rs)
        self.v.append(vs)
        self.w.append(ws)
        phi = np.array([s.joint_angle(j, q) for j in self.revolutes])
        if self._phi_prev is not None:  # unwrap against the previous record
            phi = self._phi_prev + np.angle(np.exp(1j * (phi - self._phi_prev)))
        self._phi_prev = phi
        self.phi.append(phi)
        fs, ms = [], []
        for j in self.joints:
            f, m = s.reaction(j, q, integ.lam, integ.t)
            fs.append(f)
            ms.append(m)
        self.f.append(fs)
        self.m.append(ms)
        self.sc.append([q[i] for i in s.scalar_index.values()])
        if self.beams:
            self.loads.append(np.concatenate([probe(s, q) for probe in self.probes]))

    def dataset(self) -> xr.Dataset:
        s = self.s
        t = np.array(self.t)
        nb = len(self.bodies)
        x = np.array(self.x).reshape(len(t), nb, 3)
        r = np.array(self.r).reshape(len(t), nb, 3, 3)
        ds = xr.Dataset(coords={
            "time": ("time", t, {"units": "s", "long_name": "time"}),
            "body": ("body", [b.name for b in self.bodies]),
            "xyz": ("xyz", ["x", "y", "z"]),
        })
        ds["position"] = (("time", "body", "xyz"), x,
                          {"units": "m", "long_name": "position of the body reference point"})
        ds["velocity"] = (("time", "body", "xyz"), np.array(self.v).reshape(x.shape),
                          {"units": "m s-1", "long_name": "velocity"})
        ds["angular_velocity"] = (("time", "body", "xyz"), np.array(self.w).reshape(x.shape),
                                  {"units": "rad s-1", "long_name": "angular velocity (global)"})
        ds["rotation"] = (("time", "body", "xyz", "col"), r,
                          {"units": "1", "long_name": "rotation matrix, columns d1 d2 d3"})
        ds["wiener_milenkovic"] = (("time", "body", "xyz"), wiener_milenkovic_from_matrix(r),
                                   {"units": "1", "long_name": "Wiener-Milenkovic parameters"})
        if self.revolutes:
            ds = ds.assign_coords(revolute=[j.name for j in self.revolutes])
            ds["joint_angle"] = (("time", "revolute"), np.array(self.phi),
                                 {"units": "rad", "long_name": "revolute relative rotation"})
        if self.joints:
            ds = ds.assign_coords(joint=[j.name for j in self.joints])
            ds["reaction_force"] = (("time", "joint", "xyz"), np.array(self.f),
                                    {"units": "N", "long_name": "joint force on body_b"})
            ds["reaction_moment"] = (("time", "joint", "xyz"), np.array(self.m), {
                "units": "N m", "long_name": "joint moment on body_b about the joint point"})
        if self.beams:
            ds = ds.assign_coords(
                station_beam=("station", [b.name for b in self.beams for _ in b.nodes]),
                station_s=("station", np.concatenate([b.node_s for b in self.beams]),
                           {"units": "m", "long_name": "arc length along the beam"}),
                section_axis=("section_axis", ["1", "2", "3"]))
            loads = np.array(self.loads)
            ds["section_force"] = (("time", "station", "section_axis"), loads[:, :, :3], {
                "units": "N", "long_name": "beam stress resultant: axial (1) and shear (2, 3) "
                                           "force, section frame d1 d2 d3"})
            ds["section_moment"] = (("time", "station", "section_axis"), loads[:, :, 3:], {
                "units": "N m", "long_name": "beam stress resultant: torsion (1) and bending "
                                             "(2, 3) moment, section frame d1 d2 d3"})
        if s.scalar_index:
            ds = ds.assign_coords(scalar=[sc.name for sc in s.scalar_index])
            ds["scalar_value"] = (("time", "scalar"), np.array(self.sc),
                                  {"units": "1", "long_name": "joint scalar unknowns"})
        return ds
