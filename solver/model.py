"""The model: a passive declaration of the elements of a multibody system.

Build a :class:`Model`, then hand it to :func:`solver.simulation.simulate` (declare, then
solve). Assembly (:class:`solver.system.System`) reads the model and never writes into it, so
one model can be assembled any number of times.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from solver.element import Element


@dataclass
class Model:
    """The elements of a multibody system — bodies, joints, forces, relations, first-order
    elements — in the order they were added."""

    elements: list[Element] = field(default_factory=list)

    def add(self, *items):
        """Add elements (or lists of them); returns the last one added."""
        for it in items:
            if isinstance(it, (list, tuple)):
                self.add(*it)
            elif isinstance(it, Element):
                self.elements.append(it)
            else:
                raise TypeError(f"cannot add a {type(it).__name__} to a model: expected a body, "
                                "joint, force or other solver element")
        return items[-1] if items else None

    def of_type(self, *types: type) -> list:
        """The elements that are instances of ``types``, in model order."""
        return [e for e in self.elements if isinstance(e, types)]

    @property
    def bodies(self) -> list:
        """Rigid bodies, point masses and prescribed bodies, in model order."""
        from solver.bodies import PointMass, PrescribedBody, RigidBody

        return self.of_type(RigidBody, PointMass, PrescribedBody)

    @property
    def joints(self) -> list:
        """Lower-pair joints, in model order."""
        from solver.joints import Joint

        return self.of_type(Joint)
