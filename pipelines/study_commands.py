"""`bifilar collar` and `bifilar pendulum`: single validation runs and the paper's figures.

Their model options are generated from the models' :class:`~studies.parameters.Param`
declarations (:func:`param_options`): option name, default, units, meaning and valid range are
written once, in the study module. Values are checked by the declaration, which answers a bad
one with one line naming the parameter and its valid range (exit status 2).
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Mapping
from pathlib import Path
from typing import Any

import click
import numpy as np
import xarray as xr

from pipelines.archive import CONVENTIONS, open_archive, write_case
from pipelines.checks import InputError
from pipelines.cluster import SweepError
from pipelines.options import OutPath
from pipelines.single import (
    check_writable,
    command_line,
    fail,
    finish_figure,
    run_single,
    toml_value,
)
from pipelines.studyfile import StudyError
from pipelines.sweep import run_sweep
from studies import bifilar as pendulum_study
from studies import collar as collar_study
from studies.parameters import ModelSpec, Param, ParameterError

_CLICK_TYPES: dict[type, Any] = {float: float, int: int, str: str, bool: bool}


def option_help(param: Param, note: str = "") -> str:
    """Help text of a parameter's option: meaning, units and valid range (or choices)."""
    if param.choices is not None:
        text = f"{param.long_name}: {param.describe_range()}"
    else:
        valid = param.describe_range().removesuffix(f" {param.units}")
        valid = valid.removesuffix(" (dimensionless)")
        units = "dimensionless" if param.units == "1" else param.units
        text = f"{param.long_name} ({units}); valid {valid}"
    return f"{text}; {note}" if note else text


def param_options(parameters: Mapping[str, Param], *, no_default: Collection[str] = (),
                  notes: Mapping[str, str] | None = None) -> Callable[[Any], Any]:
    """Decorator adding one click option per declared parameter, in declaration order.

    Parameters
    ----------
    parameters
        The model's declarations; ``name_x`` becomes ``--name-x`` with the declared default
        (shown in ``--help``), type, and a help text with units and valid range. Values are not
        range-checked by click: :meth:`studies.parameters.ModelSpec.complete` does it, with one
        line naming the parameter.
    no_default
        Parameters whose option defaults to ``None`` (required, or with a meaning of "not
        given" handled by the command).
    notes
        Extra help text per parameter.
    """
    notes = notes or {}

    def decorate(fn: Any) -> Any:
        for name, param in reversed(list(parameters.items())):
            given = name not in no_default
            # a string parameter with choices lists them in --help and refuses others
            kind = (click.Choice(param.choices) if param.choices is not None
                    else _CLICK_TYPES[param.kind])
            fn = click.option(
                "--" + name.replace("_", "-"), name, type=kind,
                default=param.default if given else None, show_default=given,
                help=option_help(param, notes.get(name, "")),
            )(fn)
        return fn

    return decorate


def _run_and_write(spec: ModelSpec, given: dict[str, Any], out: Path) -> xr.Dataset:
    """Validate, run and write one case (:func:`pipelines.single.run_single`)."""
    return run_single(spec, spec.name, given, out)


def _sweep_figure_cases(out_dir: Path, name: str, model: str, fixed: dict[str, Any],
                        sweep: dict[str, list[Any]], workers: int) -> xr.Dataset:
    """Run a figure's cases as a sweep into ``out_dir`` (study file, ``cases/``,
    ``archive.nc``; an interrupted figure run resumes) and return the archive."""
    lines = [f'model = "{model}"', f'title = "{name}"', "[fixed]"]
    lines += [f"{k} = {toml_value(v)}" for k, v in fixed.items()]
    lines += ["[sweep]"] + [f"{k} = [{', '.join(map(toml_value, v))}]" for k, v in sweep.items()]
    study = out_dir / f"{name}_study.toml"
    study.write_text("\n".join(lines) + "\n", encoding="utf-8")
    try:
        archive = run_sweep(study, out_dir, workers=workers, command=command_line())
    except (StudyError, SweepError, InputError) as exc:
        fail(str(exc))
    return open_archive(archive)


# ------------------------------------------------------------------------------- collar
def collar_figures(out_dir: Path, steps_per_period: int = 1000, workers: int = 2) -> list[Path]:
    """Figs. 11 and 12: period against θ0 for both curves and both cases; PNG, PDF, netCDF.

    The 32 cases run as a sweep into ``out_dir`` (``collar_study.toml``, ``cases/``,
    ``archive.nc``); ``collar_periods.nc`` is the table of the figures.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from studies.collar import SPEC, analytic_period

    out_dir.mkdir(parents=True, exist_ok=True)
    thetas = np.arange(10.0, 81.0, 10.0)
    curves, inertias = ("circle", "cycloid"), (0.0, 0.25)
    res = _sweep_figure_cases(out_dir, "collar", "collar",
                              {"steps_per_period": steps_per_period},
                              {"inertia": list(inertias), "curve": list(curves),
                               "theta0": [float(t) for t in thetas]}, workers)
    per = res["period"].transpose("inertia", "curve", "theta0").values
    ana = res["period_analytic"].transpose("inertia", "curve", "theta0").values
    table = xr.Dataset(
        {"period": (("case", "curve", "theta0"), per, {"units": "s",
                    "long_name": "period measured from the simulated motion"}),
         "period_analytic": (("case", "curve", "theta0"), ana, {"units": "s",
                             "long_name": "analytic period (Eqs. 8, 26, 27 with errata)"}),
         "relative_error": (("case", "curve", "theta0"), per / ana - 1, {"units": "1",
                            "long_name": "relative period error"})},
        coords={"case": ("case", [1, 2], {"units": "1",
                                          "long_name": "1: Ip = 0, 2: Ip = 0.25 kg m2"}),
                "curve": ("curve", list(curves), {"units": "1", "long_name": "curve"}),
                "theta0": ("theta0", thetas, {"units": "degree", "long_name": "release angle"})},
        attrs={"title": "Collar on a circle and a cycloid (paper Figs. 11-12)",
               "Conventions": CONVENTIONS})
    paths = [write_case(table, out_dir / "collar_periods.nc")]
    fine = np.linspace(1.0, 89.0, 200)
    for ci, (case, ip) in enumerate(zip((1, 2), inertias, strict=True)):
        fig, ax = plt.subplots(figsize=(6.4, 4.4))
        for k, (curve, style, mark) in enumerate(zip(curves, ("-", "--"), ("+", "o"),
                                                     strict=True)):
            th = fine if curve == "circle" else fine[fine < 89.5]
            p0 = SPEC.validate({"curve": curve, "inertia": ip})
            line = [analytic_period(p0.replace(theta0=float(t))) for t in th]
            ax.plot(th, line, style, color="k", lw=1.2, label=f"{curve}: analytic")
            ax.plot(thetas, per[ci, k], mark, color="C3" if k else "C0", ms=8, mfc="none",
                    label=f"{curve}: multibody")
        ax.set_xlabel("release angle θ0 (degree)")
        ax.set_ylabel("period T (s)")
        ax.set_title(f"Collar, case {case} (Ip = {ip:g} kg·m²)")
        paths += finish_figure(fig, ax, out_dir / f"collar_case{case}")
    return paths


@click.command()
@param_options(collar_study.PARAMETERS, no_default=("curve", "theta0"),
               notes={"curve": "required unless --figures",
                      "theta0": "required unless --figures"})
@click.option("--out", type=OutPath(dir_okay=False, path_type=Path),
              help="netCDF file for the time histories")
@click.option("--figures", type=OutPath(file_okay=False, path_type=Path),
              help="reproduce Figs. 11 and 12 into this directory instead")
def collar(out: Path | None, figures: Path | None, **params: Any) -> None:
    """The paper's validation: a collar sliding on a circle or a cycloid (Figs. 10-12)."""
    check_writable(out, figures)
    if figures is not None:
        for p in collar_figures(figures, params["steps_per_period"]):
            click.echo(str(p))
        return
    missing = [n for n, v in (("--curve", params["curve"]), ("--theta0", params["theta0"]),
                              ("--out", out)) if v is None]
    if missing:
        fail(f"missing {', '.join(missing)} (or give --figures DIR)")
    assert out is not None
    ds = _run_and_write(collar_study.SPEC, params, out)
    click.echo(f"measured period  {float(ds.period):.9f} s")
    click.echo(f"analytic period  {float(ds.period_analytic):.9f} s")
    click.echo(f"relative error   {float(ds.period_error):.3e}")


# ----------------------------------------------------------------------------- pendulum
def pendulum_figures(out_dir: Path, base: dict[str, Any], workers: int = 2) -> list[Path]:
    """Frequency order against amplitude (1-40°) for circle, cycloid and epicycloid holes
    tuned to the same small-amplitude order.

    The 27 cases run as a sweep into ``out_dir`` (``pendulum_study.toml``, ``cases/``,
    ``archive.nc``); ``pendulum_order.nc`` is the table of the figure.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from studies.analytic import amplitude_frequency_ratio
    from studies.bifilar import SPEC, holes_for

    out_dir.mkdir(parents=True, exist_ok=True)
    amps = np.array([1.0, 5.0, 10.0, 15.0, 20.0, 25.0, 30.0, 35.0, 40.0])
    shapes = ("circle", "cycloid", "epicycloid")
    fixed = {k: v for k, v in base.items() if k not in ("hole", "amplitude")}
    res = _sweep_figure_cases(out_dir, "pendulum", "pendulum", {**fixed, "hole_diameter": 0.0},
                              {"hole": list(shapes), "amplitude": [float(a) for a in amps]},
                              workers)
    orders = res["frequency_order"].transpose("hole", "amplitude").values
    n_lin = holes_for(SPEC.validate({**base, "hole": "circle", "hole_diameter": 0.0}))
    table = xr.Dataset(
        {"frequency_order": (("hole", "amplitude"), orders, {"units": "1",
                             "long_name": "ω/Ω measured from the free response"})},
        coords={"hole": ("hole", list(shapes), {"units": "1", "long_name": "hole shape"}),
                "amplitude": ("amplitude", amps, {"units": "degree",
                              "long_name": "release angle"})},
        attrs={"title": "Bifilar tuning order against amplitude", "Conventions": CONVENTIONS,
               "frequency_order_linear": n_lin.order_linear})
    paths = [write_case(table, out_dir / "pendulum_order.nc")]
    fig, ax = plt.subplots(figsize=(6.4, 4.4))
    fine = np.linspace(0.0, 40.0, 200)
    ax.plot(fine, [n_lin.order_linear * amplitude_frequency_ratio(np.radians(a))
                   for a in fine], "k-", lw=1, label="circle: π/(2K(sin A/2)) × Eq. (7)")
    for k, (s, m) in enumerate(zip(shapes, ("o", "s", "^"), strict=True)):
        ax.plot(amps, orders[k], m + "--", color=f"C{k}", mfc="none", label=f"{s} holes")
    ax.axhline(n_lin.order_linear, color="0.6", lw=0.8, ls=":")
    ax.set_xlabel("amplitude (degree)")
    ax.set_ylabel("tuning order ω/Ω")
    ax.set_title(f"Bifilar tuned to {n_lin.order_linear:.3g}P at Ω = {base['hub_speed']:g} rad/s")
    return paths + finish_figure(fig, ax, out_dir / "pendulum_order")


@click.command()
@param_options(pendulum_study.PARAMETERS, no_default=("hole_diameter", "tuning_order", "amplitude"),
               notes={"hole_diameter": "exclusive with --tuning-order",
                      "tuning_order": "default 3",
                      "amplitude": "required unless --figures"})
@click.option("--out", type=OutPath(dir_okay=False, path_type=Path))
@click.option("--figures", type=OutPath(file_okay=False, path_type=Path),
              help="draw frequency order against amplitude for the three hole shapes")
def pendulum(out: Path | None, figures: Path | None, **params: Any) -> None:
    """One bifilar pendulum on a hub spinning at constant speed (Figs. 1, 5-7, Eq. 7)."""
    spec = pendulum_study.SPEC
    check_writable(out, figures)
    hole_diameter, amplitude = params["hole_diameter"], params.pop("amplitude")
    if hole_diameter is not None and params["tuning_order"] is not None:
        fail("give either --hole-diameter or --tuning-order, not both")
    if hole_diameter is not None and not hole_diameter > 0:
        fail(f"hole_diameter = {hole_diameter:g} m: must be > 0")
    given = {name: value for name, value in params.items() if value is not None}
    try:
        if figures is not None:
            base = spec.complete({**given, "hole": "circle", "amplitude": 1.0})
            for p in pendulum_figures(figures, base):
                click.echo(str(p))
            return
    except ParameterError as exc:
        fail(str(exc))
    missing = [n for n, v in (("--amplitude", amplitude), ("--out", out)) if v is None]
    if missing:
        fail(f"missing {', '.join(missing)} (or give --figures DIR)")
    assert out is not None
    ds = _run_and_write(spec, {**given, "amplitude": amplitude}, out)
    click.echo(f"tuning order measured   {float(ds.frequency_order):.6f}")
    click.echo(f"tuning order linear     {float(ds.frequency_order_linear):.6f}")
    jac = ds.jacobi.values
    click.echo(f"Jacobi integral change  {np.ptp(jac) / abs(jac[0]):.2e} (relative)")
