"""The model: a passive declaration of bodies, joints, forces and extra constraints.

Build a :class:`Model`, then hand it to :func:`solver.integrators.simulate` (declare, then solve).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from solver.bodies import Body, Scalar
from solver.forces import ForceElement
from solver.joints import Joint


@dataclass
class Model:
    """Bodies, joints, force elements and extra constraint groups of a multibody system.

    ``constraints`` holds holonomic constraint groups that are not quadratic (e.g. the curve
    sliding joint) and ``nonholonomic`` the velocity constraints A(q)·q̇ = 0 (rolling, arc
    length). ``scalars`` are extra massless unknowns they own (η, s).
    """

    bodies: list[Body] = field(default_factory=list)
    joints: list[Joint] = field(default_factory=list)
    forces: list[ForceElement] = field(default_factory=list)
    constraints: list = field(default_factory=list)
    nonholonomic: list = field(default_factory=list)
    scalars: list[Scalar] = field(default_factory=list)

    def add(self, *items):
        """Add bodies, joints, force elements, scalars or constraint groups; returns the last."""
        from solver.constraints import HolonomicGroup, NonholonomicGroup
        from solver.curve_joints import CurveSliding

        for it in items:
            if isinstance(it, Joint):
                self.joints.append(it)
            elif isinstance(it, ForceElement):
                self.forces.append(it)
            elif isinstance(it, Scalar):
                self.scalars.append(it)
            elif isinstance(it, (list, tuple)):
                self.add(*it)
            elif isinstance(it, (HolonomicGroup, CurveSliding)):
                self.constraints.append(it)
                self.scalars.extend(s for s in it.scalars() if s not in self.scalars)
            elif isinstance(it, NonholonomicGroup):
                self.nonholonomic.append(it)
                self.scalars.extend(s for s in it.scalars() if s not in self.scalars)
            else:
                self.bodies.append(it)
        return items[-1] if items else None
