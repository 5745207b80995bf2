"""The typed parameter object (studies.parameters.Parameters): validated once at the boundary,
frozen, typed as its declarations; a model's derived design made once per case; run facts as
declared outputs."""

from __future__ import annotations

import dataclasses
import pickle

import numpy as np
import pytest
import xarray as xr

from studies.parameters import (
    ModelSpec,
    Output,
    OutputError,
    Param,
    ParameterError,
    Parameters,
    output_dataset,
)

DECLARED = {
    "speed": Param(27.0, "rad s-1", "rotor speed", minimum=1.0, maximum=200.0),
    "steps": Param(40, "1", "steps per revolution", minimum=16),
    "shape": Param("circle", "1", "hole shape", choices=("circle", "cycloid")),
    "estimate": Param(True, "1", "estimate the step error"),
}
CHECKS: list[dict] = []


def _check(p) -> None:
    CHECKS.append(p.as_dict())
    if p.shape == "cycloid" and p.steps < 20:
        raise ParameterError(f"steps = {p.steps}: at least 20 for cycloids")


def _simulate(p) -> xr.Dataset:
    return xr.Dataset(attrs={"type": type(p).__name__, "speed": p.speed})


SPEC = ModelSpec("test-typed", DECLARED, _simulate, _check)


def test_validate_fills_types_and_freezes():
    p = SPEC.validate({"speed": 30, "steps": 32.0})
    assert isinstance(p, Parameters) and isinstance(p, SPEC.parameters_type)
    assert (p.speed, p.steps, p.shape, p.estimate) == (30.0, 32, "circle", True)
    assert type(p.speed) is float and type(p.steps) is int
    assert [f.type for f in dataclasses.fields(p)] == [float, int, str, bool]
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.speed = 10.0  # type: ignore[misc]
    assert p.as_dict() == {"speed": 30.0, "steps": 32, "shape": "circle", "estimate": True}
    assert SPEC.complete({"speed": 30}) == SPEC.validate({"speed": 30}).as_dict()
    assert SPEC.validate(p) is p  # validated already: returned as it is
    assert hash(p) == hash(SPEC.validate({"speed": 30.0, "steps": 32}))


@pytest.mark.parametrize("given, match", [
    ({"sped": 3.0}, r"unknown parameter\(s\) for model 'test-typed': sped"),
    ({"speed": 0.5}, r"speed = 0.5 rad s-1: outside the valid range \[1, 200\]"),
    ({"steps": 16.5}, "steps = 16.5: expected a whole number"),
    ({"shape": "ellipse"}, "shape = 'ellipse': must be one of 'circle', 'cycloid'"),
    ({"shape": "cycloid", "steps": 16}, "steps = 16: at least 20 for cycloids"),
])
def test_validate_names_the_parameter_value_and_range(given, match):
    with pytest.raises(ParameterError, match=match):
        SPEC.validate(given)


def test_replace_checks_the_changed_values_and_the_combination():
    p = SPEC.validate({"steps": 16})
    assert p.replace(speed=40).speed == 40.0
    with pytest.raises(ParameterError, match="speed = 0 rad s-1: outside the valid range"):
        p.replace(speed=0)
    with pytest.raises(ParameterError, match="at least 20 for cycloids"):
        p.replace(shape="cycloid")
    with pytest.raises(ParameterError, match="unknown parameter"):
        p.replace(sped=3.0)


def test_run_takes_the_validated_dict_without_checking_it_again():
    """The worker receives the plain dict that validation made: run rebuilds the typed object
    from it and does not run the model's cross-checks again."""
    given = SPEC.complete({"steps": 24})
    CHECKS.clear()
    ds = SPEC.run(given)
    assert ds.attrs["type"] == "TestTypedParameters" and ds.attrs["speed"] == 27.0
    assert CHECKS == []
    assert SPEC.run(SPEC.trusted(given)).attrs["type"] == "TestTypedParameters"
    with pytest.raises(ParameterError, match=r"not a complete parameter set.*missing: estimate"):
        SPEC.run({k: v for k, v in given.items() if k != "estimate"})


def test_parameters_pickle_and_read_by_name():
    p = SPEC.validate({"shape": "cycloid", "steps": 24})
    q = pickle.loads(pickle.dumps(p))
    assert q == p and type(q) is type(p)
    assert p["steps"] == 24
    with pytest.raises(KeyError):
        p["as_dict"]


def test_optional_outputs_may_be_left_out():
    outputs = {"period": Output("s", "period", dims=()),
               "estimate": Output("1", "an estimate some runs make", dims=(), optional=True)}
    ds = output_dataset(outputs, {"period": 1.0})
    assert "estimate" not in ds
    with pytest.raises(OutputError, match="not filled: period"):
        output_dataset(outputs, {"estimate": 1.0})
    # a history too (a modal airframe's stations), but not a plain indexed output
    history = {"x": Output("m", "x", history=True, optional=True)}
    assert "x" not in output_dataset(history, {})
    with pytest.raises(OutputError, match="only a scalar result, a history or a coordinate"):
        ModelSpec("bad", {}, _simulate, outputs={"x": Output("m", "x", optional=True)})


def test_hub_design_is_made_once_per_case_and_run_facts_are_declared(monkeypatch):
    """Validating a hub case designs its holes (the geometry check); the run takes them from
    there; the run facts are declared scalar outputs."""
    from studies import holes, hub

    calls = []
    design = holes.design

    def counting(*args, **kw):
        calls.append(args[0])
        return design(*args, **kw)

    monkeypatch.setattr(holes, "design", counting)
    holes._designed.cache_clear()
    p = hub.SPEC.validate({"tuning_order": 3.1, "revolutions": 1, "richardson": False,
                           "error_estimate": False})
    ds = hub.SPEC.run(p.as_dict())
    assert calls == ["circle"]
    d = hub.design(p)
    assert d.fuselage_stiffness == p.fuselage_stiffness * p.fuselage_stiffness_scale
    for name in ("run_hub_speed", "run_revolutions", "run_samples_per_rev",
                 "run_transient_revolutions", "run_simulated_revolutions", "run_richardson",
                 "effective_fuselage_stiffness", "tuning_order_linear", "pin_damping"):
        decl = hub.SPEC.outputs[name]
        assert decl.is_scalar and ds[name].attrs["units"] == decl.units, name
    assert "run_step_error_estimate" not in ds  # not asked for: left out, not NaN
    assert float(ds["effective_fuselage_stiffness"]) == d.fuselage_stiffness
    assert int(ds["run_revolutions"]) == 1 and ds["run_revolutions"].dtype == np.int32
    assert set(ds.attrs) == {"message"}


def test_rotor_scales_its_fuselage_beam_bending_stiffness():
    """One name per meaning: the hub's spring is scaled by fuselage_stiffness_scale, the
    rotor's fuselage-beam EI by fuselage_bending_stiffness_scale."""
    from studies import hub, rotor

    assert "fuselage_stiffness_scale" in hub.SPEC.parameters
    assert "fuselage_stiffness_scale" not in rotor.SPEC.parameters
    p = rotor.SPEC.validate({"fuselage_bending_stiffness_scale": 0.5})
    d = rotor.design(p)
    assert d.bending_stiffness == 0.5 * p.fuselage_bending_stiffness
    assert d.fuselage_stiffness == pytest.approx(
        3 * d.bending_stiffness / p.fuselage_length**3, rel=1e-15)


def test_parameter_names_that_the_object_uses_are_refused():
    with pytest.raises(ParameterError, match="replace are taken by the parameter object"):
        ModelSpec("test-clash", {"replace": Param(1.0)}, _simulate)
