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


def resolve_model(ref: str) -> ModelSpec:
    """The :class:`ModelSpec` for a registry name or a ``"module:attribute"`` reference.

    Parameters
    ----------
    ref
        ``"hub"`` (a name in this registry) or ``"package.module:SPEC"`` (a plug-in model:
        every process that runs it, e.g. each dask worker, imports the module itself).

    Raises
    ------
    ParameterError
        With one line, if the model cannot be found or imported.
    """
    if ":" in ref:
        module_name, _, attr = ref.partition(":")
        try:
            spec = getattr(importlib.import_module(module_name), attr)
        except (ImportError, AttributeError) as exc:
            raise ParameterError(
                f"cannot load model {ref!r}: {type(exc).__name__}: {exc} "
                "(a plug-in model is 'importable.module:ATTRIBUTE'; is its module on the path?)"
            ) from exc
        if not isinstance(spec, ModelSpec):
            raise ParameterError(f"model {ref!r} is a {type(spec).__name__}, not a ModelSpec")
        return spec
    try:
        return get_model(ref)
    except ImportError as exc:
        raise ParameterError(
            f"cannot load model {ref!r}: {type(exc).__name__}: {exc}; available models: "
            f"{', '.join(available())}"
        ) from exc
