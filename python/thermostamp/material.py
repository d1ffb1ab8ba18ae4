"""The material models from Python: the material point (:func:`material_point`), the virtual
tests (:func:`uniaxial_test`, :func:`bias_extension_test`, :func:`picture_frame_test`) and the
fits (:func:`fit_matrix`, :func:`fit_fabric_tension`, :func:`fit_shear`), the same as
``thermostamp material-point``, ``thermostamp test ...`` and ``thermostamp fit ...``, with
tables as NumPy arrays.

Units: mm, N, s, MPa, °C; angles in degrees. Bad input raises
:class:`~thermostamp.errors.InputError` with the command line's message (a table handed in as
arrays is named by its row, from 1, where the command line names the file's line).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Union

import numpy as np

from . import _core
from .errors import InputError
from .result import Check

__all__ = [
    "material_point",
    "uniaxial_test",
    "bias_extension_test",
    "picture_frame_test",
    "TestResult",
    "fit_matrix",
    "fit_fabric_tension",
    "fit_shear",
    "FitResult",
]

PathLike = Union[str, "os.PathLike[str]"]
Table = Union[Mapping[str, Any], np.ndarray]


def _history_rows(history: Table, columns: List[str], origin: str) -> np.ndarray:
    """The table's columns in the order ``columns`` as an (n, len(columns)) float array, each
    present, of one length, and finite (the command line's checks of a CSV file)."""
    expected = ",".join(columns)
    if isinstance(history, Mapping):
        for name in history:
            if name not in columns:
                raise InputError(
                    f"{origin}: unexpected column '{name}' (expected columns: {expected})"
                )
        missing = [c for c in columns if c not in history]
        if missing:
            raise InputError(
                f"{origin}: missing column '{missing[0]}' (expected columns: {expected})"
            )
        arrays = [np.asarray(history[c], dtype=float) for c in columns]
        for name, a in zip(columns, arrays):
            if a.ndim != 1:
                raise InputError(f"{origin}: column '{name}' must be 1-D, not of shape {a.shape}")
        lengths = {len(a) for a in arrays}
        if len(lengths) != 1:
            sizes = ", ".join(f"{c} {len(a)}" for c, a in zip(columns, arrays))
            raise InputError(f"{origin}: the columns differ in length ({sizes})")
        rows = np.column_stack(arrays) if arrays else np.empty((0, 0))
    else:
        rows = np.asarray(history, dtype=float)
        if rows.ndim != 2 or rows.shape[1] != len(columns):
            raise InputError(
                f"{origin}: a 2-D array needs {len(columns)} columns ({expected}), "
                f"not shape {rows.shape}"
            )
    if len(rows) == 0:
        raise InputError(f"{origin}: the table has no data rows")
    bad = np.argwhere(~np.isfinite(rows))
    if len(bad):
        i, j = bad[0]
        raise InputError(
            f"{origin}: row {i + 1}: column '{columns[j]}': '{rows[i, j]}' is not a finite number"
        )
    return np.ascontiguousarray(rows)


def material_point(
    card: PathLike, layer: str, history: Table, angle: float = 0.0
) -> Dict[str, np.ndarray]:
    """Drives one material point through a deformation history, as ``thermostamp
    material-point`` does, and returns its response: column name to NumPy array.

    ``card``: the material card (TOML file). ``layer``: ``"matrix"`` (layer A, the
    visco-hyperelastic matrix), ``"fabric"`` (layer B) or ``"laminate"`` (the whole ply in
    plane stress). ``history``: a dict of column name to 1-D array, or a 2-D array with the
    columns in this order:

    - matrix, fabric: ``t, F11, F12, F13, F21, F22, F23, F31, F32, F33, T`` (s, the 3D
      deformation gradient by rows, °C);
    - laminate: ``t, F11, F12, F21, F22, T`` (the in-plane deformation gradient).

    ``angle``: warp direction, degrees from x in the x–y plane (weft 90° further on).

    Returns, for matrix and fabric, ``t, S11, S22, S33, S12, S23, S13`` (2nd Piola–Kirchhoff)
    and ``sigma11 .. sigma13`` (Cauchy), MPa; for the laminate ``t, N11, N22, N12`` (N/mm per
    unit reference width) and ``thickness`` (mm).

    A bad history (a missing or unknown column, a value that is not finite, t not increasing,
    det F <= 0, a state the card's law cannot take) raises
    :class:`~thermostamp.errors.InputError` naming the row (from 1) and the column.
    """
    columns = _core.point_history_columns(layer)
    rows = _history_rows(history, columns, "history")
    return _core.material_point_table(os.fspath(card), layer, rows, float(angle))


class TestResult:
    """A virtual test's result, from :func:`uniaxial_test`, :func:`bias_extension_test` or
    :func:`picture_frame_test`.

    - ``status``: how it ended, in the summary's words; ``outcome``: ``finished``,
      ``interrupted`` or ``failed`` (the solver or a check stopped it, records so far kept);
      ``ok`` is ``outcome == "finished"``, ``error`` the full message otherwise.
    - ``history``: the columns of the command line's CSV (``time`` process time in s,
      ``displacement`` mm, ``force`` N, the test's own columns, the energies in mJ and
      ``solver_time``), NumPy arrays with one value per record.
    - ``summary``: ``steps``, ``elements``, ``time_step`` (s), ``added_mass`` and
      ``physical_mass`` (tonne), ``time_scaling``, ``worst_balance_error``,
      ``worst_kinetic_ratio``, ``wall_seconds``, ``threads``, ``element_steps_per_second``,
      ``estimated_steps``, ``solver``, ``defaults_chosen`` (lines).
    - ``checks``: the run-time checks (:class:`~thermostamp.Check`); ``files``: the files
      written (none without an output folder); ``notes``: the lines the command line writes
      on standard error before the run (defaults chosen, warnings, the estimate).
    """

    __test__ = False  # not a pytest class

    def __init__(self, raw: Dict[str, Any]):
        self.status: str = raw["status"]
        self.outcome: str = raw["outcome"]
        self.error: Optional[str] = raw["error"]
        self.summary: Dict[str, Any] = raw["summary"]
        self.history: Dict[str, np.ndarray] = raw["history"]
        self.checks: List[Check] = [Check(*c) for c in raw["checks"]]
        self.files: List[Path] = raw["files"]
        self.notes: List[str] = raw["notes"]

    @property
    def ok(self) -> bool:
        """Whether the run finished."""
        return self.outcome == "finished"

    def to_pandas(self):
        """The history as a ``pandas.DataFrame``, one row per record. Needs pandas."""
        try:
            import pandas
        except ImportError as e:
            raise ImportError("to_pandas needs pandas: pip install pandas") from e
        return pandas.DataFrame(self.history)

    def __repr__(self) -> str:
        return f"TestResult({self.status!r}, {len(self.history['time'])} records)"


def _run_test(kind, card, output, threads, progress, **options) -> TestResult:
    if output is not None:
        output = os.fspath(output)
    command = f"python: thermostamp test {kind} ({os.fspath(card)})"
    raw, raised = _core.virtual_test(
        kind, os.fspath(card), options, output, threads, progress, command
    )
    result = TestResult(raw)
    if raised is not None:
        raised.result = result
        raise raised
    return result


_COMMON_DOC = """
    Options (``None``: the test's default, as ``thermostamp test ... --help`` lists it):
    ``temperature`` (°C; required when the card has a matrix, 20 for a dry fabric),
    ``speed`` (physical crosshead speed, mm/s), ``time_scaling`` (run this many times faster,
    eta1 divided by it), ``target_step`` (mass scaling to this time step, s; 0 for none),
    ``damping`` (1/s), ``element_size`` (mm), ``pattern`` (``"crossed"``, ``"quad"``,
    ``"right"``, ``"alternating"``), ``end_displacement`` (crosshead travel, mm), ``frames``
    (ParaView frames, 0 for none; written only with ``output``), ``history_points`` (rows of
    the history), ``solver`` (``"explicit"`` or ``"implicit"``).

    ``output``: a folder to write the command line's files (CSV history, plots, ParaView
    frames); nothing is written without one. ``threads``: worker threads (default all cores).
    ``progress``: a callable ``progress(fraction, step, time)`` as :func:`thermostamp.run`
    calls it; an exception it raises stops the test and is raised again with the result
    attached as ``exception.result``. Ctrl-C stops the test after its step:
    ``KeyboardInterrupt`` is raised with the partial result as ``exception.result``.
    Bad options raise :class:`~thermostamp.errors.InputError` with the command line's message,
    naming the option; an unknown option raises ``TypeError``.
    Returns a :class:`TestResult`.
"""


def uniaxial_test(
    card: PathLike,
    *,
    width: float = 25.0,
    length: float = 150.0,
    ply_angle: float = 0.0,
    temperature: Optional[float] = None,
    speed: Optional[float] = None,
    time_scaling: Optional[float] = None,
    target_step: Optional[float] = None,
    damping: float = 0.0,
    element_size: Optional[float] = None,
    pattern: str = "crossed",
    end_displacement: Optional[float] = None,
    frames: int = 20,
    history_points: int = 120,
    solver: str = "explicit",
    output: Optional[PathLike] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[float, int, float], Any]] = None,
) -> TestResult:
    return _run_test("uniaxial", **locals())


uniaxial_test.__doc__ = (
    """Uniaxial (strip) tension test, as ``thermostamp test uniaxial``: bottom edge clamped,
    top edge pulled. ``card``: the material card (TOML). ``width``, ``length``: the strip
    and its free length between the clamps (mm); ``ply_angle``: the warp's angle to the
    pulling direction (degrees: 0 warp, 90 weft, 45 bias). Its own history columns:
    ``strain``, ``stress_resultant`` (N/mm), ``shear_angle_deg``.
"""
    + _COMMON_DOC
)


def bias_extension_test(
    card: PathLike,
    *,
    width: float = 150.0,
    length: float = 450.0,
    temperature: Optional[float] = None,
    speed: Optional[float] = None,
    time_scaling: Optional[float] = None,
    target_step: Optional[float] = None,
    damping: float = 0.0,
    element_size: Optional[float] = None,
    pattern: str = "crossed",
    end_displacement: Optional[float] = None,
    frames: int = 20,
    history_points: int = 120,
    solver: str = "explicit",
    output: Optional[PathLike] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[float, int, float], Any]] = None,
) -> TestResult:
    return _run_test("bias-extension", **locals())


bias_extension_test.__doc__ = (
    """Bias-extension test, as ``thermostamp test bias-extension``: a ±45° specimen clamped
    at both ends and pulled. ``width``, ``length``: the specimen and its free length between
    the clamps (mm). Its own history columns: ``shear_angle_deg`` (central zone),
    ``shear_angle_pin_jointed_deg``, ``normalised_shear_force`` (N/mm).
"""
    + _COMMON_DOC
)


def picture_frame_test(
    card: PathLike,
    *,
    side: float = 150.0,
    temperature: Optional[float] = None,
    speed: Optional[float] = None,
    time_scaling: Optional[float] = None,
    target_step: Optional[float] = None,
    damping: float = 0.0,
    element_size: Optional[float] = None,
    pattern: str = "crossed",
    end_displacement: Optional[float] = None,
    frames: int = 20,
    history_points: int = 120,
    solver: str = "explicit",
    output: Optional[PathLike] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[float, int, float], Any]] = None,
) -> TestResult:
    return _run_test("picture-frame", **locals())


picture_frame_test.__doc__ = (
    """Picture-frame test, as ``thermostamp test picture-frame``: a square specimen in a
    pin-jointed frame pulled along its diagonal. ``side``: the frame's and the specimen's side,
    hinge to hinge (mm). Its own history columns: ``shear_angle_deg`` (interior),
    ``shear_angle_frame_deg``, ``normalised_shear_force`` (N/mm).
"""
    + _COMMON_DOC
)


# --- fits -----------------------------------------------------------------------------------

Curve = Union[PathLike, Mapping[str, Any]]


class FitResult:
    """A fit's result, from :func:`fit_matrix`, :func:`fit_fabric_tension` or
    :func:`fit_shear`.

    - ``parameters``: the fitted parameters by name (MPa, MPa·s, 1/MPa; for :func:`fit_matrix`
      NumPy arrays, one value per temperature);
    - ``standard_errors``: their standard errors, by the same names;
    - ``quality``: the figures of the command line's table (points, RMS residuals, ...);
    - ``card``: the card the command line writes to ``--output`` (TOML text);
    - ``files``: the files written (none without ``output`` or ``plot``);
    - ``notes``: the notes the command line writes on standard error.
    """

    def __init__(self, raw: Dict[str, Any]):
        self.parameters: Dict[str, Any] = raw["parameters"]
        self.standard_errors: Dict[str, Any] = raw["standard_errors"]
        self.quality: Dict[str, Any] = raw["quality"]
        self.card: str = raw["card"]
        self.files: List[Path] = raw["files"]
        self.notes: List[str] = raw["notes"]

    def __repr__(self) -> str:
        return f"FitResult({self.parameters!r})"


def _curve(curve: Optional[Curve], origin: str):
    """A curve for the Rust side: ``(path, None)`` for a file, ``(origin, csv_text)`` for a
    table (every value written with all its digits, so it reads back the same)."""
    if curve is None:
        return None
    if not isinstance(curve, Mapping):
        return (os.fspath(curve), None)
    names = list(curve)
    arrays = [np.atleast_1d(np.asarray(curve[n], dtype=float)) for n in names]
    lengths = {len(a) for a in arrays}
    if len(lengths) > 1:
        sizes = ", ".join(f"{n} {len(a)}" for n, a in zip(names, arrays))
        raise InputError(f"{origin}: the columns differ in length ({sizes})")
    lines = [",".join(names)]
    lines += [",".join(repr(float(v)) for v in row) for row in zip(*arrays)]
    return (origin, "\n".join(lines) + "\n")


def _path(path: Optional[PathLike]) -> Optional[str]:
    return None if path is None else os.fspath(path)


def fit_fabric_tension(
    card: PathLike,
    *,
    warp: Optional[Curve] = None,
    weft: Optional[Curve] = None,
    terms: Optional[int] = None,
    width: Optional[float] = None,
    output: Optional[PathLike] = None,
    plot: Optional[PathLike] = None,
) -> FitResult:
    """The yarn tension coefficients ``A_k`` of the card's ``[fabric]`` from strip tension
    tests along warp and weft, as ``thermostamp fit fabric-tension``.

    ``card``: the material card whose ``warp_tension`` / ``weft_tension`` are fitted (its
    ``fabric_thickness`` is t_B). ``warp``, ``weft`` (at least one): each the CSV file the
    command line reads, or a dict of column to array with the same columns: ``strain`` or
    ``stretch``, and ``force_per_width`` (N/mm) or ``force`` (N, divided by ``width`` in mm).
    ``terms``: coefficients A_2.. to fit (default as many as the card has).
    ``output``: where to write the card (as ``--output``); ``plot``: a PNG of data and model.
    Nothing is written without them.

    Returns a :class:`FitResult`: ``parameters`` ``warp_A2``, ``warp_A3``, ... (MPa),
    ``quality`` ``warp_points``, ``warp_rms_residual`` (N/mm), ... and ``fabric_thickness``.
    """
    if warp is None and weft is None:
        raise InputError("give warp or weft (or both): a strip curve each")
    raw = _core.fit_fabric_tension(
        os.fspath(card),
        _curve(warp, "warp"),
        _curve(weft, "weft"),
        terms,
        width,
        _path(output),
        _path(plot),
    )
    return FitResult(raw)


def fit_matrix(
    curves: Union[PathLike, List[Mapping[str, Any]]],
    *,
    card: Optional[PathLike] = None,
    bulk_modulus: Optional[float] = None,
    poisson: Optional[float] = None,
    output: Optional[PathLike] = None,
    plot: Optional[PathLike] = None,
) -> FitResult:
    """``C10(T)``, ``eta1(T)`` (and ``D1``) of the matrix law from neat-resin uniaxial tension
    curves, as ``thermostamp fit matrix``.

    ``curves``: the manifest the command line reads (TOML, one ``[[curve]]`` per CSV file), or
    a list of dicts, one per curve, with ``curve`` (a CSV file, or a dict of column to array:
    ``strain`` or ``stretch``, and ``stress`` (true, MPa) or ``nominal_stress``),
    ``temperature`` (°C) and ``strain_rate`` (1/s) or ``crosshead_speed`` (mm/s) and
    ``gauge_length`` (mm), the keys of a manifest's ``[[curve]]``.
    ``card``: a card whose ``[matrix]`` is replaced (without one the result is the
    ``[matrix]`` section alone). D1: ``bulk_modulus`` K (D1 = 2/K) or ``poisson`` nu, or with
    neither the card's table. ``output``: where to write the card; ``plot``: a PNG.

    Returns a :class:`FitResult` whose ``parameters`` are arrays, one value per temperature:
    ``temperature`` (°C), ``c10`` (MPa), ``eta1`` (MPa·s), ``d1`` (1/MPa); ``standard_errors``
    ``c10``, ``eta1`` (NaN where eta1 comes from the card); ``quality`` ``curves``,
    ``points``, ``rms_residual`` (MPa).
    """
    if bulk_modulus is not None and poisson is not None:
        raise InputError("bulk_modulus and poisson: give one, not both")
    if isinstance(curves, (str, os.PathLike)):
        manifest, entries = os.fspath(curves), []
    else:
        manifest, entries = None, []
        known = {"curve", "temperature", "strain_rate", "crosshead_speed", "gauge_length"}
        for i, entry in enumerate(curves, start=1):
            unknown = set(entry) - known
            if unknown:
                raise InputError(
                    f"curves #{i}: unknown key '{sorted(unknown)[0]}' "
                    f"(keys: {', '.join(sorted(known))})"
                )
            if "curve" not in entry or "temperature" not in entry:
                raise InputError(f"curves #{i}: needs 'curve' and 'temperature'")
            entries.append(
                (
                    _curve(entry["curve"], f"curves[{i}]"),
                    float(entry["temperature"]),
                    entry.get("strain_rate"),
                    entry.get("crosshead_speed"),
                    entry.get("gauge_length"),
                )
            )
    raw = _core.fit_matrix(
        manifest, entries, _path(card), bulk_modulus, poisson, _path(output), _path(plot)
    )
    return FitResult(raw)


def fit_shear(
    card: PathLike,
    data: Curve,
    *,
    test: str = "bias-extension",
    width: Optional[float] = None,
    length: Optional[float] = None,
    frame_side: Optional[float] = None,
    fabric_side: Optional[float] = None,
    temperature: Optional[float] = None,
    speed: Optional[float] = None,
    terms: Union[str, int, List[str]] = "3",
    friction_onset: Optional[float] = None,
    locking_angle: Optional[float] = None,
    max_shear: float = 50.0,
    output: Optional[PathLike] = None,
    plot: Optional[PathLike] = None,
) -> FitResult:
    """The shear law of the card's ``[fabric]`` from a bias-extension or picture-frame curve,
    as ``thermostamp fit shear`` (the analytic fit; ``--refine-fe`` is the command line's).

    ``data``: the CSV file the command line reads, or a dict of column to array:
    ``displacement_mm`` and ``force_N`` (or ``displacement`` and ``force``, as the virtual
    tests write them). ``test``: ``"bias-extension"`` (needs ``width`` and ``length``, mm) or
    ``"picture-frame"`` (needs ``frame_side``; ``fabric_side`` defaults to it).
    ``temperature`` (°C) and ``speed`` (mm/s): needed for a card with matrix layers, whose
    share of the force is subtracted first. ``terms``: as ``--terms`` (``"friction,1,2"``,
    ``3`` for c1..c3, or a list of names); ``friction_onset`` (degrees, default the command
    line's), ``locking_angle`` (degrees, with a ``locking`` term), ``max_shear`` (degrees).
    ``output``: where to write the card; ``plot``: a PNG.

    Returns a :class:`FitResult`: ``parameters`` by term (``c1``, ``friction``, ``locking``,
    MPa); ``quality`` ``points``, ``rms`` (in the fitted ``quantity``), ``rms_relative``,
    ``rms_of_mean``, ``rms_of_range`` and ``fitted`` (line, shear_deg, data, model arrays).
    """
    options = dict(
        test=test,
        width=width,
        length=length,
        frame_side=frame_side,
        fabric_side=fabric_side,
        temperature=temperature,
        speed=speed,
        terms=terms,
        friction_onset=friction_onset,
        locking_angle=locking_angle,
        max_shear=max_shear,
    )
    raw = _core.fit_shear(
        os.fspath(card), _curve(data, "data"), options, _path(output), _path(plot)
    )
    return FitResult(raw)
