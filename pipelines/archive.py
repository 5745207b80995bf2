"""netCDF archive of a study: one file per case, written atomically, consolidated at the end.

netCDF-C/HDF5 is not thread safe and a sweep may be killed at any time, so every worker writes
its own case file (``cases/<case_id>.nc``) through a temporary file in the same directory and an
``os.replace``: a case file either exists complete or not at all. The sweep process alone then
reads them all and writes the consolidated archive, following the CF-1.8 conventions (the
newest version the CF checker, ``cfchecks`` of the ``cfchecker`` package, verifies; nothing here
needs a later one). Every file passes that checker:

* strings (messages, case ids and names, string parameters) are fixed-length character arrays
  (a ``string<N>`` dimension), not netCDF-4 variable-length strings;
* every dimension has a coordinate variable. A dimension whose values are names (``direction``
  x/y, a swept string parameter such as ``hole``) has an integer index as its coordinate variable
  and the names in the auxiliary label variable ``<dim>_label``; :func:`open_archive` and
  :func:`read_case` turn the names back into the dimension's coordinate, so that
  ``ds.sel(direction="x")`` works (with plain ``xarray.open_dataset`` use
  ``ds.sel(direction=0)`` or ``ds.swap_dims``);
* ``standard_name`` is given where CF has one (``time``).

Files are created with the permissions the user's umask gives (e.g. 0644), so colleagues on a
shared cluster can read them.

Case file (one case)
    The case summary made by :func:`case_summary` from the model's output declarations
    (:class:`studies.parameters.Output`): its scalar results; for a per-rev periodic model
    (the hub) the harmonics from :func:`studies.harmonics.case_harmonics`, the last recorded
    revolution of the declared histories (dimension ``time_in_rev`` with its sample-number
    coordinate, auxiliary coordinate ``psi`` in degrees) and a few ``run_*`` scalars; for any
    other model (collar, pendulum) the declared
    histories whole (dimension ``sample``, with the variable ``time``). An output dimension named
    like a model parameter is renamed ``<dim>_index`` (the hub's ``bifilar`` becomes
    ``bifilar_index``). Global attributes ``Conventions``, ``case_id``, ``model``,
    ``model_version`` (package and model version, part of the case id), ``parameters`` (JSON),
    ``status``, ``message``, ``wall_time`` and, for a failure, ``traceback``. A failed case
    holds the attributes only.

Consolidated archive
    The same variables with the case dimensions in front: one dimension per swept parameter
    (a Cartesian sweep) or one ``case`` dimension (an explicit case list); ``status`` (int8 flags
    ok/failed/not_run), ``message`` and ``case_id`` per case; parameters that vary are coordinates
    on the case dimensions and those common to all cases are scalar variables, all with the
    ``units`` and ``long_name`` of their :class:`~studies.parameters.Param`. Data of cases that did
    not finish are NaN (floats) or the ``_FillValue`` -1 (integers).

Branches (a study with a ``[continuation]`` table, :mod:`studies.branches`)
    Each case is a branch of periodic responses. Its case file (:func:`branch_summary`) holds
    the case summary of every point stacked along the dimension ``point`` (coordinate: the
    point's number from ``start``; scalars that are the same at every point are stacked too),
    and per point the continued parameter's value as a variable named like the parameter
    (its ``units`` and ``long_name``), ``stable`` and ``fold`` (int8 flags 0/1 with
    ``flag_values`` and ``flag_meanings``) and ``floquet_multiplier_max`` (the largest
    modulus of the point's Floquet multipliers; above 1 is unstable). In the consolidated
    archive the branches of a study, which can differ in length, are padded to the longest:
    NaN for floats, the ``_FillValue`` -1 for the int8 flags (:func:`open_archive` gives them
    as floats with NaN there, as for any integer variable). The continued parameter is
    archived only per point, never as a case coordinate or constant.
"""

from __future__ import annotations

import contextlib
import importlib.metadata
import os
import socket
import tempfile
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

import dask.config
import numpy as np
import xarray as xr

from pipelines.checks import process_alive
from studies.harmonics import (
    N_MAX,
    case_harmonics,
    copy_coords,
    harmonic_names,
    recording_layout,
)
from studies.parameters import ModelSpec

CONVENTIONS = "CF-1.8"
# Suffix of the auxiliary variable holding the names of a dimension whose values are strings.
LABEL_SUFFIX = "_label"
REFERENCES = (
    "O. A. Bauchau, J. Rodriguez, S.-Y. Chen, Modeling the Bifilar Pendulum Using Nonlinear, "
    "Flexible Multibody Dynamics, Journal of the American Helicopter Society, 2003"
)

# Case status flags (CF flag_values / flag_meanings).
STATUS_OK = 0
STATUS_FAILED = 1
STATUS_NOT_RUN = 2
FLAG_VALUES = np.array([STATUS_OK, STATUS_FAILED, STATUS_NOT_RUN], dtype=np.int8)
FLAG_MEANINGS = "ok failed not_run"

# The writing host in the names of temporary files (dots would split the name's fields).
_WRITER = socket.gethostname().replace(".", "_") or "host"

# netCDF compression of float variables: level 4 is most of zlib's gain at a fraction of level 9's
# time.
COMPRESSION = {"zlib": True, "complevel": 4}
# Missing value of integer variables (a failed case has no revolution count).
INT_FILL = -1

# The dimension of a branch's points, and the variables a branch adds per point besides the
# continued parameter's value (a model parameter or output with one of these names cannot be
# continued).
POINT = "point"
BRANCH_VARIABLES = (POINT, "stable", "fold", "floquet_multiplier_max")
# The flags of a branch point (int8, CF flag_values / flag_meanings).
BRANCH_FLAGS = {
    "stable": ("1 if every Floquet multiplier is inside the unit circle (a stable periodic "
               "response), else 0", "unstable stable"),
    "fold": ("1 if the point is a fold (turning point) of the branch in the continued "
             "parameter, else 0", "no_fold fold"),
}

# Names the archive itself uses, whatever the model: a model parameter with one of these names (or
# with the name of one of the model's archived outputs, see :func:`reserved_names`) cannot be
# archived.
RESERVED_NAMES = frozenset(
    {"case", "case_name", "case_id", "status", "message", "harmonic", "direction",
     "time_in_rev", "psi", "sample", "time", "run_hub_speed", "run_revolutions",
     "run_transient_revolutions", "run_samples_per_rev", "run_wall_time",
     "run_step_error_estimate", "run_simulated_revolutions"}
)


def history_variables(spec: ModelSpec) -> dict[str, tuple[str, str]]:
    """Time histories the archive keeps per case: name -> (units, long_name), as declared."""
    return {name: (out.units, out.long_name) for name, out in spec.outputs.items()
            if out.history and not out.is_vector and "time" in out.dims}


def scalar_variables(spec: ModelSpec) -> dict[str, tuple[str, str]]:
    """Scalar results the archive keeps per case: name -> (units, long_name), as declared."""
    return {name: (out.units, out.long_name) for name, out in spec.outputs.items()
            if out.is_scalar}


def _renamed(dim: str, spec: ModelSpec) -> str:
    """Archive name of an output dimension: ``<dim>_index`` if a parameter has its name."""
    return f"{dim}_index" if dim in spec.parameters else dim


def reserved_names(spec: ModelSpec) -> frozenset[str]:
    """Every name the archive of ``spec`` uses besides its parameters.

    :data:`RESERVED_NAMES`, the archived scalar results and histories, the harmonic variables
    (:func:`studies.harmonics.harmonic_names`) and the output dimensions.
    """
    names = set(RESERVED_NAMES) | set(scalar_variables(spec)) | set(history_variables(spec))
    if spec.periodic:
        names |= set(harmonic_names(spec.outputs))
    for name, out in spec.outputs.items():
        if name in names or (spec.periodic and out.harmonics):
            names |= {_renamed(d, spec) for d in out.dims if d != "time"}
    return frozenset(names)


class ArchiveError(ValueError):
    """A case file or archive cannot be read or has an unexpected layout."""


def code_version() -> str:
    """The installed version of the ``bifilar`` distribution, or ``"unknown"``."""
    try:
        return importlib.metadata.version("bifilar")
    except importlib.metadata.PackageNotFoundError:
        return "unknown"


def global_attrs(*, title: str, model: str, study_text: str, command: str) -> dict[str, str]:
    """CF-1.11 global attributes of an archive.

    Parameters
    ----------
    title
        Short description of the study.
    model
        The model that produced the cases as the study file gives it (registry name or
        ``module:attribute``), so that :func:`pipelines.plots.plot_archive` can find its output
        declarations again.
    study_text
        Full text of the study file, kept so the archive alone can reproduce the study.
    command
        Command line that produced the archive (goes into ``history``).
    """
    now = datetime.now(UTC).isoformat(timespec="seconds")
    return {
        "Conventions": CONVENTIONS,
        "title": title,
        "source": f"bifilar {code_version()} (model {model!r})",
        "history": f"{now}: {command}",
        "references": REFERENCES,
        "comment": "Per-rev harmonics are x = c0 + sum_k (c_k cos k psi + s_k sin k psi), "
                   "psi = hub_speed * time; amplitude = hypot(c_k, s_k).",
        "model": model,
        "study": study_text,
    }


def _one_revolution(values: np.ndarray, samples_per_rev: int, psi_start: float) -> np.ndarray:
    """Last revolution of ``values`` (time last) re-sampled to start at azimuth 0.

    A whole-sample offset is a plain rotation; a fractional one is a Fourier shift, exact for the
    band-limited periodic signal.
    """
    last = values[..., -samples_per_rev:]
    phase = psi_start % (2 * np.pi)  # reduced first: m·psi_start loses digits after many revs
    offset = phase / (2 * np.pi) * samples_per_rev
    whole = round(offset)
    if abs(offset - whole) < 1e-9:
        # roll(a, s)[j] = a[j - s]: the sample at azimuth j·Δψ
        return np.roll(last, whole % samples_per_rev, axis=-1)
    m = np.arange(samples_per_rev // 2 + 1)
    shifted = np.fft.rfft(last, axis=-1) * np.exp(-1j * m * phase)
    return np.fft.irfft(shifted, n=samples_per_rev, axis=-1)


def _time_in_rev_coord(samples_per_rev: int) -> xr.Variable:
    return xr.Variable("time_in_rev", np.arange(samples_per_rev, dtype=np.int32),
                       {"units": "1", "long_name": "sample number within the last recorded "
                        "revolution (azimuth in psi)"})


def _psi_coord(samples_per_rev: int) -> xr.Variable:
    return xr.Variable(
        "time_in_rev",
        360.0 * np.arange(samples_per_rev) / samples_per_rev,
        {"units": "degree",
         "long_name": "rotor azimuth psi = hub_speed * time, over the last recorded revolution"},
    )


def case_summary(ds: xr.Dataset, spec: ModelSpec, n_max: int = N_MAX) -> xr.Dataset:
    """What the archive keeps of one model result, as the model's outputs declare.

    Parameters
    ----------
    ds
        The model result (:attr:`ModelSpec.run`), filled through its declarations.
    spec
        The model: its :attr:`~studies.parameters.ModelSpec.outputs` say what is kept; an output
        dimension named like one of its parameters is renamed ``<dim>_index`` (the hub's
        ``bifilar`` dimension becomes ``bifilar_index``, since ``bifilar`` is a parameter).
    n_max
        Highest harmonic kept (per-rev periodic models).

    Returns
    -------
    xarray.Dataset
        Every declared scalar result (dims ``()``; an ``optional`` one if the run gave it),
        the run facts among them (``run_hub_speed``, ``run_revolutions``,
        ``run_samples_per_rev``, ``run_transient_revolutions``, ...). For a per-rev periodic
        model (:attr:`ModelSpec.periodic`): the harmonics of
        :func:`studies.harmonics.case_harmonics` and the declared histories over the last
        recorded revolution (dim ``time_in_rev``, coordinate ``psi`` in degree, starting at
        psi = 0). Otherwise: the declared histories whole (dim ``sample``) with their ``time``
        (s).
        Every variable has the ``units`` and ``long_name`` of its declaration.

    Raises
    ------
    ValueError
        If a declared scalar result or history is missing from ``ds``, or (periodic models) the
        time base is not whole revolutions.
    """
    histories = history_variables(spec)
    scalars = scalar_variables(spec)
    missing = [name for name in (*scalars, *histories)
               if name not in ds and not spec.outputs[name].optional]
    if missing:
        raise ValueError(f"model result lacks declared output(s) {', '.join(missing)}")
    if spec.periodic:
        _, n, revs, psi0 = recording_layout(ds)
        out = case_harmonics(ds, spec.outputs, n_max)
        psi_last = psi0 + 2 * np.pi * (revs - 1)
        for name, (units, long_name) in histories.items():
            if name not in ds:  # an optional history this run has not
                continue
            other = tuple(d for d in ds[name].dims if d != "time")
            var = ds[name].transpose(*other, "time")
            attrs = {"units": units, "long_name": long_name,
                     "comment": "last recorded revolution, from azimuth psi = 0"}
            out[name] = ((*other, "time_in_rev"),
                         _one_revolution(var.values.astype(float), n, psi_last), attrs)
            out = copy_coords(out, ds, other)
        if histories:
            out = out.assign_coords(psi=_psi_coord(n), time_in_rev=_time_in_rev_coord(n))
    else:
        out = xr.Dataset()
        for name, (units, long_name) in histories.items():
            if name not in ds:
                continue
            other = tuple(d for d in ds[name].dims if d != "time")
            var = ds[name].transpose(*other, "time")
            out[name] = ((*other, "sample"), var.values,
                         {"units": units, "long_name": long_name,
                          "comment": "whole time history; shorter cases are padded with NaN"})
            out = copy_coords(out, ds, other)
        if histories:
            decl = spec.outputs.get("time")
            time_attrs = decl.attrs() if decl is not None else {"units": "s", "long_name": "time"}
            time_attrs = {**time_attrs, "standard_name": "time"}
            out["time"] = ("sample", np.asarray(ds["time"].values, dtype=float), time_attrs)
            out = out.assign_coords(sample=_sample_coord(ds.sizes["time"]))
    for name, (units, long_name) in scalars.items():
        if name in ds:  # (an optional result a run may leave out)
            out[name] = ((), ds[name].values, {"units": units, "long_name": long_name})
    renames = {d: _renamed(d, spec) for d in out.dims if _renamed(d, spec) != d}
    return out.rename(renames) if renames else out


def branch_summary(points: Sequence[Any], spec: ModelSpec, parameter: str,
                   n_max: int = N_MAX,
                   summaries: Sequence[xr.Dataset] | None = None) -> xr.Dataset:
    """What the archive keeps of one branch: the case summary of each point, stacked.

    Parameters
    ----------
    points
        The branch (:class:`studies.branches.BranchPoint`, in order from ``start``): each
        point's ``result`` is what the model's ``simulate`` returns for that response.
    spec
        The model.
    parameter
        The continued parameter.
    n_max
        Highest harmonic kept (per-rev periodic models).
    summaries
        The points' :func:`case_summary`, if made already (then ``n_max`` is theirs).

    Returns
    -------
    xarray.Dataset
        :func:`case_summary` of every point along the dimension ``point`` (every variable,
        also those equal at every point), the continued parameter's value per point (named
        like the parameter, with its ``units`` and ``long_name``), ``stable`` and ``fold``
        (int8 0/1 flags) and ``floquet_multiplier_max``.

    Raises
    ------
    ValueError
        If the branch has no points, or a point's result lacks a declared output or has
        another layout than the others.
    """
    if not points:
        raise ValueError("the branch has no points")
    if summaries is None:
        summaries = [case_summary(point.result, spec, n_max) for point in points]
    # coords="minimal": the coordinates of the inner dimensions (harmonic, direction, psi, …)
    # are the same at every point and stay unstacked; join="exact" refuses points whose
    # layouts differ (it would pad them with NaN in silence).
    out = xr.concat(summaries, dim=POINT, data_vars="all", coords="minimal",
                    compat="override", join="exact", combine_attrs="override")
    out.attrs = {}
    param = spec.parameters[parameter]
    out[parameter] = ((POINT,), np.array([float(p.value) for p in points]), param.attrs())
    for name, (long_name, meanings) in BRANCH_FLAGS.items():
        out[name] = ((POINT,), np.array([bool(getattr(p, name)) for p in points], np.int8),
                     {"units": "1", "long_name": long_name,
                      "flag_values": np.array([0, 1], np.int8), "flag_meanings": meanings})
    out["floquet_multiplier_max"] = (
        (POINT,), np.array([p.multiplier_max for p in points], dtype=float),
        {"units": "1", "long_name": "largest modulus of the Floquet multipliers over one "
         "revolution (above 1: unstable)"})
    return out.assign_coords({POINT: _point_coord(len(points))})


def _point_coord(points: int) -> xr.Variable:
    return xr.Variable(POINT, np.arange(points, dtype=np.int32),
                       {"units": "1", "long_name": "point number along the branch, from its "
                        "start"})


def _sample_coord(samples: int) -> xr.Variable:
    return xr.Variable("sample", np.arange(samples, dtype=np.int32),
                       {"units": "1", "long_name": "sample number of the time histories"})


def _float_encoding(ds: xr.Dataset) -> dict[str, dict[str, Any]]:
    return {
        name: dict(COMPRESSION)
        for name, var in ds.variables.items()
        if np.issubdtype(var.dtype, np.floating)
    }


def _is_text(var: xr.Variable) -> bool:
    return var.dtype.kind in "OUS"


def cf_encode(ds: xr.Dataset) -> tuple[xr.Dataset, dict[str, dict[str, Any]]]:
    """The CF-valid form of ``ds`` and the encoding of its strings (see the module notes).

    A dimension coordinate of strings becomes an int32 index with the names in the auxiliary
    coordinate ``<dim>_label``; every string variable is written as a fixed-length character
    array.

    Returns
    -------
    tuple
        The dataset to write and ``{name: {"dtype": "S1"}}`` for its string variables.
    """
    for dim in list(ds.dims):
        if dim in ds.coords and _is_text(ds[dim].variable):
            names = ds[dim].variable
            meaning = names.attrs.get("long_name", dim)
            index = xr.Variable(dim, np.arange(names.size, dtype=np.int32), {
                "units": "1",
                "long_name": f"{meaning}: index, names in {dim}{LABEL_SUFFIX}",
            })
            label = xr.Variable(dim, np.asarray(names.values, dtype=object), dict(names.attrs))
            ds = ds.drop_vars(dim).assign_coords({dim: index, f"{dim}{LABEL_SUFFIX}": label})
    encoding = {name: {"dtype": "S1"} for name, var in ds.variables.items() if _is_text(var)}
    return ds, encoding


def cf_decode(ds: xr.Dataset) -> xr.Dataset:
    """Undo :func:`cf_encode`: the names of ``<dim>_label`` become the coordinate of ``dim``."""
    for name in list(ds.coords):
        dim = name.removesuffix(LABEL_SUFFIX)
        if (name != dim and ds[name].dims == (dim,) and dim in ds.coords
                and ds[dim].dtype.kind in "iu"):
            names = ds[name].variable
            ds = ds.drop_vars([dim, name]).assign_coords(
                {dim: xr.Variable(dim, names.values.astype(str).astype(object),
                                  dict(names.attrs))})
    return ds


def _umask() -> int:
    """The process's umask, read without changing it where Linux allows."""
    with contextlib.suppress(OSError, ValueError):
        with open("/proc/self/status") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    mask = os.umask(0o022)  # fallback: read by setting, then restore at once
    os.umask(mask)
    return mask


def _write_atomic(ds: xr.Dataset, path: Path, encoding: Mapping[str, Any]) -> Path:
    """Write ``ds`` to ``path`` so that ``path`` is never seen half written.

    The file gets the permissions a plain ``open`` would give (0666 less the umask), not the
    private 0600 of a temporary file.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    ds, text = cf_encode(ds)
    encoding = {**text, **{k: v for k, v in encoding.items() if k in ds.variables}}
    # A writer killed mid-write (kill -9, a batch system's limit) leaves its temporary: remove
    # those of this target whose writer no longer runs, before writing a new one.
    for stale in stale_temporaries(path.parent, path.stem):
        with contextlib.suppress(OSError):
            stale.unlink()
    # Same directory as the target, so that os.replace is an atomic rename on one filesystem.
    # The name does not end in .nc: a leftover from a killed writer is never taken for a case.
    # It names the writer's host and process, so that a later writer can tell a leftover from
    # the temporary of a writer still at work.
    fd, tmp = tempfile.mkstemp(dir=path.parent, suffix=".tmp",
                               prefix=f".{path.stem}.{_WRITER}.{os.getpid()}.")
    os.close(fd)
    try:
        os.chmod(tmp, 0o666 & ~_umask())
        # The data are in memory. Without this, xarray inside a dask worker would open a client
        # to the scheduler and take a cluster-wide lock for every write.
        with dask.config.set(scheduler="synchronous"):
            ds.to_netcdf(tmp, engine="netcdf4", format="NETCDF4", encoding=dict(encoding))
        # Data on disk before the rename, so a power cut cannot leave an empty "finished" case.
        with open(tmp, "rb") as fh:
            os.fsync(fh.fileno())
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise
    return path


def write_case(ds: xr.Dataset, path: str | os.PathLike[str]) -> Path:
    """Write one case file atomically (temporary file in the same directory, then rename).

    Parameters
    ----------
    ds
        Case summary (see :func:`case_summary`) with the case's global attributes; float
        variables are zlib-compressed.
    path
        Target ``.nc`` path; its directory is created if needed.

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    return _write_atomic(ds, Path(path), _float_encoding(ds))


def read_case(path: str | os.PathLike[str]) -> xr.Dataset:
    """Load a case file fully into memory (the file is closed on return)."""
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return cf_decode(ds.load())
    except (OSError, ValueError) as exc:
        raise ArchiveError(
            f"cannot read case file {path}: {exc}; delete it and rerun the sweep to recompute it"
        ) from exc


def _writer_alive(name: str, stem: str) -> bool:
    """Whether the writer that made the temporary file ``name`` may still be writing it."""
    fields = name[len(stem) + 2: -len(".tmp")].split(".")
    if len(fields) < 3 or not fields[1].isdigit():
        return False  # not named after its writer: a leftover
    host, pid = fields[0], int(fields[1])
    if host != _WRITER:
        return True  # another machine's writer (a worker on a shared file system): unknown
    if pid == os.getpid():
        return False  # this process writes one file at a time: its own are leftovers
    return process_alive(pid)


def stale_temporaries(directory: Path, stem: str, *, all_writers: bool = False) -> list[Path]:
    """Temporary files a killed writer of ``<stem>.nc`` left in ``directory``.

    Parameters
    ----------
    directory, stem
        Where the target ``<stem>.nc`` is written.
    all_writers
        Also those of writers that may still run: another host's, or a live process's (for
        a sweep that holds the output directory's lock and is about to write the target).
    """
    found = sorted(Path(directory).glob(f".{stem}.*.tmp"))
    if all_writers:
        return found
    return [p for p in found if not _writer_alive(p.name, stem)]


@dataclass(frozen=True)
class CaseEntry:
    """Where one case goes in the archive and where its file is.

    Attributes
    ----------
    index
        Position along the case dimensions (one integer per dimension).
    case_id
        Stable identifier (hash of model and parameters).
    path
        The case file ``cases/<case_id>.nc`` (may not exist: the case did not run).
    """

    index: tuple[int, ...]
    case_id: str
    path: Path


def _upsample(values: np.ndarray, samples: int) -> np.ndarray:
    """Periodic Fourier re-sampling to more samples along the last axis.

    Exact for a band-limited periodic signal: cases of one archive may differ in
    ``samples_per_rev`` and their one-revolution histories share the finest azimuth grid.
    """
    n = values.shape[-1]
    if n == samples:
        return values
    spectrum = np.fft.rfft(values, axis=-1)
    if n % 2 == 0:
        # The Nyquist bin of the coarse grid is a cosine that the fine grid resolves: half of
        # it belonged to the negative frequency.
        spectrum[..., -1] *= 0.5
    return np.fft.irfft(spectrum, n=samples, axis=-1) * (samples / n)


def _pad(values: np.ndarray, axis: int, length: int, fill: float = np.nan) -> np.ndarray:
    """``values`` extended to ``length`` along ``axis`` (a shorter time history, a shorter
    branch) with ``fill``: NaN (as floats), or an integer fill value (dtype kept)."""
    width = [(0, 0)] * values.ndim
    width[axis] = (0, length - values.shape[axis])
    if isinstance(fill, float) and np.isnan(fill):
        values = values.astype(float)
    return np.pad(values, width, constant_values=fill)


def status_counts(archive: xr.Dataset) -> dict[str, int]:
    """Number of cases per status (``ok``, ``failed``, ``not_run``) of an opened archive."""
    status = np.asarray(archive["status"].values)
    return {meaning: int((status == flag).sum())
            for flag, meaning in zip(FLAG_VALUES, FLAG_MEANINGS.split(), strict=True)}


def consolidate(
    path: str | os.PathLike[str],
    *,
    dims: Mapping[str, int],
    coords: Mapping[str, xr.Variable],
    cases: Sequence[CaseEntry],
    constants: Mapping[str, xr.Variable],
    attrs: Mapping[str, str],
) -> Path:
    """Gather all case files into one CF-1.11 netCDF archive, written atomically.

    Parameters
    ----------
    path
        Archive to write.
    dims
        Case dimensions in order and their sizes, e.g. ``{"tuning_order": 3,
        "fuselage_stiffness_scale": 2}`` or ``{"case": 4}``.
    coords
        Coordinates on the case dimensions (swept values, ``case_name``, …) with ``units`` and
        ``long_name``.
    cases
        Every case of the study; a case whose file is missing gets status ``not_run``.
    constants
        Scalar variables (parameters common to all cases), with ``units`` and ``long_name``.
    attrs
        Global attributes (see :func:`global_attrs`).

    Returns
    -------
    pathlib.Path
        ``path``.
    """
    shape = tuple(dims.values())
    case_dims = tuple(dims)
    status = np.full(shape, STATUS_NOT_RUN, dtype=np.int8)
    message = np.full(shape, "not run: no case file; rerun the sweep to compute it", dtype=object)
    case_ids = np.full(shape, "", dtype=object)
    wall_time = np.full(shape, np.nan)
    loaded: list[tuple[tuple[int, ...], xr.Dataset]] = []
    for entry in cases:
        case_ids[entry.index] = entry.case_id
        if not entry.path.exists():
            continue
        try:
            ds = read_case(entry.path)
        except ArchiveError as exc:
            status[entry.index], message[entry.index] = STATUS_FAILED, str(exc)
            continue
        status[entry.index] = int(ds.attrs.get("status", STATUS_FAILED))
        message[entry.index] = str(ds.attrs.get("message", ""))
        wall_time[entry.index] = float(ds.attrs.get("wall_time", np.nan))
        if status[entry.index] == STATUS_OK:
            loaded.append((entry.index, ds))

    # Layout of the per-case variables: the union over finished cases, at the finest azimuth
    # resolution among them (cases may differ in samples_per_rev), and as long as the longest
    # whole time history (cases may differ in their number of time steps).
    samples = max((ds.sizes.get("time_in_rev", 0) for _, ds in loaded), default=0)
    steps = max((ds.sizes.get("sample", 0) for _, ds in loaded), default=0)
    # (branches: as long as the longest branch)
    points = max((ds.sizes.get(POINT, 0) for _, ds in loaded), default=0)
    resized = {"time_in_rev": samples, "sample": steps, POINT: points}
    template: dict[str, xr.Variable] = {}
    inner_coords: dict[str, xr.Variable] = {}
    for _, ds in loaded:
        for name, var in ds.data_vars.items():
            if name not in template:
                sizes = {d: resized.get(d, var.sizes[d]) for d in var.dims}
                template[name] = xr.Variable(var.dims, np.empty(tuple(sizes.values()), var.dtype),
                                             var.attrs)
        for name, coord in ds.coords.items():
            if (name not in ("psi", "sample", "time_in_rev", POINT)
                    and name not in inner_coords):
                inner_coords[name] = coord.variable
    if samples:
        inner_coords["psi"] = _psi_coord(samples)
        inner_coords["time_in_rev"] = _time_in_rev_coord(samples)
    if steps:
        inner_coords["sample"] = _sample_coord(steps)
    if points:
        inner_coords[POINT] = _point_coord(points)

    data_vars: dict[str, xr.Variable] = {}
    encoding: dict[str, dict[str, Any]] = {}
    for name, var in template.items():
        is_int = np.issubdtype(var.dtype, np.integer)
        # integers as int32, but 0/1 flags (a branch point's stable, fold) stay int8: INT_FILL
        # fits either
        int_type = np.int8 if var.dtype == np.int8 else np.int32
        values = np.full(shape + var.shape, INT_FILL if is_int else np.nan,
                         dtype=int_type if is_int else float)
        for index, ds in loaded:
            if name not in ds:
                continue
            case_values = ds[name].transpose(*var.dims).values
            if "time_in_rev" in var.dims:
                case_values = _upsample(case_values, samples)
            if "sample" in var.dims and case_values.shape != var.shape:
                case_values = _pad(case_values, var.dims.index("sample"), steps)
            if POINT in var.dims and case_values.shape != var.shape:
                case_values = _pad(case_values, var.dims.index(POINT), points,
                                   INT_FILL if is_int else np.nan)
            if case_values.shape != var.shape:
                raise ArchiveError(
                    f"variable {name!r} has shape {case_values.shape} in case "
                    f"{case_ids[index]} but {var.shape} in others; the cases of one archive "
                    "must come from one model layout"
                )
            values[index] = case_values
        data_vars[name] = xr.Variable(case_dims + var.dims, values, var.attrs)
        encoding[name] = {"_FillValue": INT_FILL} if is_int else dict(COMPRESSION)

    data_vars["status"] = xr.Variable(case_dims, status, {
        "units": "1", "long_name": "case status",
        "flag_values": FLAG_VALUES, "flag_meanings": FLAG_MEANINGS,
    })
    data_vars["message"] = xr.Variable(case_dims, message, {
        "units": "1", "long_name": "failure message (exception type and text); for an ok case "
        "the model's note (e.g. how the periodic response was reached), usually empty",
    })
    data_vars["case_id"] = xr.Variable(case_dims, case_ids, {
        "units": "1",
        "long_name": "case identifier (hash of model and parameters); file cases/<case_id>.nc",
    })
    data_vars["run_wall_time"] = xr.Variable(case_dims, wall_time, {
        "units": "s", "long_name": "wall-clock time of the case on its worker",
    })
    encoding["run_wall_time"] = dict(COMPRESSION)
    # a per-case variable wins over a constant or coordinate of the same name (a branch's
    # continued parameter, archived per point)
    data_vars.update({k: v for k, v in constants.items() if k not in data_vars})
    coords = {k: v for k, v in coords.items() if k not in data_vars}

    archive = xr.Dataset(data_vars, coords={**coords, **inner_coords}, attrs=dict(attrs))
    for name, var in archive.variables.items():
        if np.issubdtype(var.dtype, np.floating) and name not in encoding:
            encoding[name] = dict(COMPRESSION)
        # xarray writes bools as int8 with a dtype attribute; give them no fill value.
        if var.dtype == bool:
            encoding.setdefault(name, {})["_FillValue"] = None
    return _write_atomic(archive, Path(path), encoding)


def open_archive(path: str | os.PathLike[str]) -> xr.Dataset:
    """Load a consolidated archive fully into memory (the file is closed on return)."""
    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"archive not found: {path}")
    try:
        with xr.open_dataset(path, engine="netcdf4") as ds:
            return cf_decode(ds.load())
    except (OSError, ValueError) as exc:
        raise ArchiveError(f"cannot read archive {path}: {exc}") from exc
