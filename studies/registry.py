"""Registry of the models the pipeline can sweep, by name.

Models are imported lazily so that asking for one does not import every study.
"""

from __future__ import annotations

import importlib

from studies.parameters import ModelSpec, ParameterError

# name -> "module:attribute" of a ModelSpec
_LAZY: dict[str, str] = {
    "hub": "studies.hub:SPEC",
    "pendulum": "studies.bifilar:SPEC",
    "collar": "studies.collar:SPEC",
    "rotor": "studies.rotor:SPEC",
}
_LOADED: dict[str, ModelSpec] = {}


def register(spec: ModelSpec) -> None:
    """Make ``spec`` available under ``spec.name`` (used by tests and plug-in models)."""
    _LOADED[spec.name] = spec


def available() -> list[str]:
    return sorted(set(_LAZY) | set(_LOADED))


def get_model(name: str) -> ModelSpec:
    """The :class:`ModelSpec` called ``name``; :class:`ParameterError` if there is none."""
    if name in _LOADED:
        return _LOADED[name]
    if name not in _LAZY:
        raise ParameterError(f"unknown model {name!r}; available models: {', '.join(available())}")
    module, attr = _LAZY[name].split(":")
    spec = getattr(importlib.import_module(module), attr)
    _LOADED[name] = spec
    return spec
