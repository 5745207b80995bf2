"""The element protocol: declarations, and vectorized sets that evaluate them.

Every part of a model — body, joint, force, relation, first-order element — is an
:class:`Element`: passive data that declares the unknowns it owns (:meth:`Element.states`) and
names, through the class attribute ``set_class``, the :class:`ElementSet` that evaluates all
its instances at once. Assembly (:class:`solver.system.System`) groups the elements of a model
by ``(set_class, element.group_key())`` and builds one set per group, in order of first
appearance; the set resolves indices once and never writes into the declarations.

An element set supplies, for all its members together, whichever of these terms it has (each
defaults to nothing, so a set implements only its own physics):

* **potential** V(q): :meth:`~ElementSet.potential`, gradient at ``grad_idx``, exact discrete
  gradient (∇̄V·(q_f − q_i) = V_f − V_i, what keeps ``ep`` energy-exact), Hessian at
  ``(stiff_rows, stiff_cols)``;
* **generalized force** f(q, v, t) (dampers, loads, first-order right-hand sides) at
  ``force_idx`` with its Jacobians ∂f/∂q at ``(fq_rows, fq_cols)`` and ∂f/∂v at
  ``(fv_rows, fv_cols)``; the integrators book its work. A set with ``uses_acceleration``
  (apparent mass of a body moving through a fluid) has f(q, v, t, a), affine in the
  accelerations a = q̈, takes ``a`` as a fourth argument of :meth:`~ElementSet.force` and
  :meth:`~ElementSet.force_jacobians`, and gives ∂f/∂a at ``(fa_rows, fa_cols)`` from
  :meth:`~ElementSet.acceleration_jacobian`; every scheme passes the acceleration of its own
  kinematics (``ep``: (v_f − v_i)/h, ``galpha``: q̈_{n+1}); a set may also give the three
  Jacobians already weighted and summed, :meth:`~ElementSet.force_tangent` (the Newton matrix
  needs only their sum);
* **holonomic rows** C(q, t) = 0 (``n_holonomic``): values and Jacobian at the flat pattern
  ``(hol_rows, hol_cols)`` (local rows), the exact discrete derivative Ḡ with
  Ḡ·(q_f − q_i) = C_f − C_i, the λ-weighted Hessian at ``(hess_rows, hess_cols)``, ∂C/∂t and
  the acceleration-level curvature;
* **nonholonomic rows** A(q)·q̇ = 0 (``n_nonholonomic``): A at ``(nh_rows, nh_cols)`` and
  ∂(A(q)·Δq)/∂q at the same pattern;
* :meth:`~ElementSet.accept` after each converged step, :meth:`~ElementSet.initialize` to set
  geometry-dependent initial values of its own unknowns, and :meth:`~ElementSet.row_owner` to
  name the element behind a row in error messages.

Adding an element is one module: the declaration class (with ``states`` if it owns unknowns)
and its set class implementing its terms.
"""

from __future__ import annotations

from collections.abc import Hashable
from typing import ClassVar

import numpy as np
from numpy.typing import NDArray

from solver.state import StateBlock

Array = NDArray[np.float64]
IArray = NDArray[np.int64]
EMPTY_I = np.zeros(0, dtype=np.int64)
EMPTY_F = np.zeros(0)


class Element:
    """Base of every declaration. Subclasses set ``set_class`` and, if they own unknowns,
    override :meth:`states`."""

    set_class: ClassVar[type[ElementSet] | None] = None
    name: str  # every element has a name (joints and bodies: their first field)

    def states(self) -> list[StateBlock]:
        """State blocks this element owns (none by default)."""
        return []

    def group_key(self) -> Hashable:
        """Elements of one ``set_class`` with equal keys are evaluated by one set."""
        return ()

    def parts(self) -> list[Element]:
        """Elements assembled with this one (a beam's nodes); none by default."""
        return []


class ElementSet:
    """All elements of one class (and group key) in a model, evaluated together.

    Parameters
    ----------
    elements
        The declarations, in model order.
    system
        The system being assembled: gives the layout (``offset``, ``scalar_index``), the
        initial configuration ``q0_raw`` and the vector-expression helpers.
    """

    # patterns (set by subclasses in __init__)
    grad_idx: IArray = EMPTY_I
    stiff_rows: IArray = EMPTY_I
    stiff_cols: IArray = EMPTY_I
    force_idx: IArray = EMPTY_I
    fq_rows: IArray = EMPTY_I  # pattern of ∂f/∂q
    fq_cols: IArray = EMPTY_I
    fv_rows: IArray = EMPTY_I  # pattern of ∂f/∂v
    fv_cols: IArray = EMPTY_I
    fa_rows: IArray = EMPTY_I  # pattern of ∂f/∂a (sets with uses_acceleration)
    fa_cols: IArray = EMPTY_I
    uses_acceleration: bool = False
    n_holonomic: int = 0
    hol_rows: IArray = EMPTY_I
    hol_cols: IArray = EMPTY_I
    hess_rows: IArray = EMPTY_I
    hess_cols: IArray = EMPTY_I
    n_nonholonomic: int = 0
    nh_rows: IArray = EMPTY_I
    nh_cols: IArray = EMPTY_I
    # the gradient does not depend on q (a linear potential, e.g. gravity), nor then does the
    # discrete gradient: the system evaluates it once
    constant_gradient: bool = False
    # does a constraint depend on time explicitly (drivers), does the set do work on the system
    time_dependent: bool = False
    nonconservative: bool = False
    # does the set keep a history of the converged steps that its forces read back (delays):
    # then the steps must advance in time (no backward substep, solver.composition)
    step_history: bool = False

    def __init__(self, elements: list, system) -> None:
        self.elements = list(elements)

    @property
    def name(self) -> str:
        return ",".join(e.name for e in self.elements)

    # -- set-up -------------------------------------------------------------------------
    def initialize(self, q0: Array) -> None:
        """Write geometry-dependent initial values of the set's own unknowns into ``q0``."""

    def row_owner(self, row: int, holonomic: bool = True) -> str:
        """Name of the element that owns local row ``row`` (for error messages)."""
        return self.name

    # -- potential ----------------------------------------------------------------------
    def potential(self, q: Array) -> float:
        return 0.0

    def gradient(self, q: Array) -> Array:
        return EMPTY_F

    def discrete_gradient(self, qi: Array, qf: Array) -> Array:
        """Exact discrete gradient; the midpoint gradient is exact for quadratic potentials."""
        return self.gradient(0.5 * (qi + qf))

    def stiffness(self, q: Array) -> Array:
        return EMPTY_F

    def discrete_stiffness(self, qi: Array, qf: Array) -> Array:
        """∂(∇̄V(q_i, q_f))/∂q_f at ``(stiff_rows, stiff_cols)``: the Newton tangent of the
        discrete gradient; by default half the Hessian at the midpoint (sets whose discrete
        gradient moves far from that over a step override it)."""
        return 0.5 * self.stiffness(0.5 * (qi + qf))

    def material_stiffness(self, q: Array) -> Array:
        """A positive semidefinite part of the Hessian at ``(stiff_rows, stiff_cols)``: the
        material part BᵀCB of a strain energy ½εᵀCε (without the geometric part, which has no
        sign). The default is the Hessian itself, for sets whose Hessian is semidefinite
        (linear springs; Gauss–Newton rotational springs)."""
        return self.stiffness(q)

    # -- generalized forces ---------------------------------------------------------------
    def force(self, q: Array, v: Array, t: float) -> Array:
        return EMPTY_F

    def force_jacobians(self, q: Array, v: Array, t: float) -> tuple[Array, Array]:
        """(∂f/∂q at ``(fq_rows, fq_cols)``, ∂f/∂v at ``(fv_rows, fv_cols)``)."""
        return EMPTY_F, EMPTY_F

    def acceleration_jacobian(self, q: Array, v: Array, t: float, a: Array) -> Array:
        """∂f/∂a at ``(fa_rows, fa_cols)`` (sets with ``uses_acceleration``)."""
        return EMPTY_F

    def force_tangent(self, q: Array, v: Array, t: float, a: Array | None, wq: float,
                      wv: Array, wa: float) -> Array | None:
        """wq ∂f/∂q + (∂f/∂v) diag(wv) + wa ∂f/∂a summed at ``(fq_rows, fq_cols)``, for a set
        whose ∂f/∂v and ∂f/∂a patterns lie inside its ∂f/∂q pattern and that can sum them
        before mapping them to global coordinates (cheaper than three global blocks); ``wv``
        is the weight of each global unknown's velocity column (length n). None (the
        default) when the set cannot: the three Jacobians are then summed globally."""
        return None

    # -- holonomic rows -------------------------------------------------------------------
    def constraint(self, q: Array, t: float) -> tuple[Array, Array]:
        """(C (n_holonomic,), Jacobian values at the flat pattern)."""
        return EMPTY_F, EMPTY_F

    def constraint_value(self, q: Array, t: float) -> Array:
        """C alone (sets whose Jacobian costs extra override this)."""
        return self.constraint(q, t)[0]

    def constraint_jacobian(self, q: Array, t: float) -> Array:
        """Jacobian values alone (sets whose values cost extra override this)."""
        return self.constraint(q, t)[1]

    def discrete_jacobian(self, qi: Array, qf: Array, ti: float, tf: float) -> Array:
        """Ḡ with Ḡ·(q_f − q_i) = C(q_f) − C(q_i): Gonzalez's correction of the midpoint
        Jacobian, row by row along Δq (exact for any C; sets override it with cheaper exact
        forms)."""
        qm = 0.5 * (qi + qf)
        ci = self.constraint_value(qi, ti)
        cf = self.constraint_value(qf, tf)
        gm = self.constraint_jacobian(qm, 0.5 * (ti + tf))
        dq = qf[self.hol_cols] - qi[self.hol_cols]
        m = self.n_holonomic
        gdq = np.bincount(self.hol_rows, gm * dq, minlength=m)
        d2 = np.bincount(self.hol_rows, dq * dq, minlength=m)
        ok = d2 > 1e-28
        corr = np.where(ok, (cf - ci - gdq) / np.where(ok, d2, 1.0), 0.0)
        return gm + corr[self.hol_rows] * dq

    def constraint_hessian(self, q: Array, t: float, lam: Array) -> Array:
        """Σ_r λ_r ∂²C_r/∂q² at ``(hess_rows, hess_cols)``."""
        return EMPTY_F

    def constraint_rate(self, q: Array, t: float) -> Array:
        """∂C/∂t at fixed q."""
        return np.zeros(self.n_holonomic)

    def constraint_curvature(self, q: Array, v: Array, t: float) -> Array:
        """C̈ − G q̈ along a motion through (q, v); by default a central difference of the
        Jacobian along v (only the consistent initial accelerations use it)."""
        eps = 1e-6 / max(1e-12, float(np.abs(v).max()))
        _, gp = self.constraint(q + eps * v, t)
        _, gm = self.constraint(q - eps * v, t)
        return np.bincount(self.hol_rows, (gp - gm) / (2 * eps) * v[self.hol_cols],
                           minlength=self.n_holonomic)

    # -- nonholonomic rows ----------------------------------------------------------------
    def nh_matrix(self, q: Array) -> Array:
        """Values of A(q) at ``(nh_rows, nh_cols)``."""
        return EMPTY_F

    def nh_derivative(self, q: Array, dq: Array) -> Array:
        """Values of ∂(A(q)·dq)/∂q at ``(nh_rows, nh_cols)``; ``dq`` is the full vector."""
        return np.zeros(len(self.nh_cols))

    def nh_curvature(self, q: Array, v: Array) -> Array:
        eps = 1e-6 / max(1e-12, float(np.abs(v).max()))
        da = (self.nh_matrix(q + eps * v) - self.nh_matrix(q - eps * v)) / (2 * eps)
        return np.bincount(self.nh_rows, da * v[self.nh_cols], minlength=self.n_nonholonomic)

    # -- step hooks -----------------------------------------------------------------------
    def accept(self, q: Array, v: Array, t: float) -> None:
        """Called after every converged step with its end state (e.g. to unwrap angles, or
        to record a history)."""


def group_elements(elements: list) -> list[tuple[type[ElementSet], list]]:
    """Group declarations by ``(set_class, group_key())`` in order of first appearance."""
    groups: dict[tuple, list] = {}
    order: list[tuple] = []
    for e in elements:
        cls = type(e).set_class
        if cls is None:
            continue
        key = (cls, e.group_key())
        if key not in groups:
            groups[key] = []
            order.append(key)
        groups[key].append(e)
    return [(k[0], groups[k]) for k in order]


def dense_pattern(cols: IArray) -> tuple[IArray, IArray]:
    """Flat (rows, cols) pattern of rows that each touch the k columns of ``cols`` (m × k)."""
    m, k = cols.shape
    return np.repeat(np.arange(m), k), cols.ravel()
