"""The engine's side of the package (Rust, PyO3): the functions the Python classes call. Users
call :func:`thermostamp.run`, :class:`thermostamp.Scenario` and :class:`thermostamp.Study`."""

from os import PathLike
from typing import Any, Callable, Optional, Sequence, Union

__version__: str
HISTORY_COLUMNS: list[str]

def scenario_load(path: Union[str, PathLike[str]], overrides: Sequence[str]) -> str:
    """The scenario file with ``key=value`` overrides, checked, as standalone TOML text."""

def scenario_from_text(
    text: str, origin: str, folder: Union[str, PathLike[str]], overrides: Sequence[str]
) -> str:
    """A scenario's TOML text (paths relative to ``folder``), checked, as standalone text."""

def toml_dumps(table: dict[str, Any]) -> str:
    """TOML text of a dictionary of tables, lists and scalars."""

def toml_loads(text: str) -> dict[str, Any]:
    """A dictionary of TOML text."""

def run_scenario(
    text: str,
    origin: str,
    output: Optional[str] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[float, int, float], Any]] = None,
    command: str = "",
) -> tuple[dict[str, Any], Optional[BaseException]]:
    """Runs a standalone scenario: the result's dictionary and the exception that stopped it."""

def study_open(text: str, origin: str, base_dir: str, run_dir: str) -> dict[str, Any]:
    """A study file's folder, parameters, number of cases and threads per case (checked)."""

def study_cases(
    text: str, origin: str, base_dir: str, run_dir: str
) -> list[tuple[int, list[Any], str]]:
    """Every case: number, values, status (as ``sweep --list``)."""

def study_prepare(text: str, origin: str, base_dir: str, run_dir: str, command: str) -> list[int]:
    """Claims the study's folder and checks the cases not finished; their numbers."""

def study_run_case(
    text: str, origin: str, base_dir: str, run_dir: str, number: int, command: str
) -> tuple[str, str, float]:
    """Runs one case in this process (as ``sweep --case N``): status, reason, wall seconds."""

def study_summarise(text: str, origin: str, base_dir: str, run_dir: str, command: str) -> str:
    """Writes the study's summary and charts; the path of ``summary.csv``."""


def material_point_table(card: str, layer: str, rows: Any, angle: float) -> dict[str, Any]:
    """One material point through the history ``rows`` (2-D, the layer's columns in order)."""

def point_history_columns(layer: str) -> list[str]:
    """The history columns of ``layer`` (``matrix``, ``fabric`` or ``laminate``)."""

def virtual_test(
    kind: str,
    card: str,
    options: dict[str, Any],
    output: Optional[str] = None,
    threads: Optional[int] = None,
    progress: Optional[Callable[[float, int, float], Any]] = None,
    command: str = "",
) -> tuple[dict[str, Any], Optional[BaseException]]:
    """A virtual test (``uniaxial``, ``bias-extension``, ``picture-frame``) with every option."""

def fit_matrix(
    manifest: Optional[str],
    curves: Sequence[tuple[Any, float, Optional[float], Optional[float], Optional[float]]],
    card: Optional[str],
    bulk_modulus: Optional[float],
    poisson: Optional[float],
    output: Optional[str],
    plot: Optional[str],
) -> dict[str, Any]:
    """``fit matrix`` from a manifest or from curves."""

def fit_fabric_tension(
    card: str,
    warp: Optional[Any],
    weft: Optional[Any],
    terms: Optional[int],
    width: Optional[float],
    output: Optional[str],
    plot: Optional[str],
) -> dict[str, Any]:
    """``fit fabric-tension`` from strip curves."""

def fit_shear(
    card: str, data: Any, options: dict[str, Any], output: Optional[str], plot: Optional[str]
) -> dict[str, Any]:
    """``fit shear`` (analytic) from a bias-extension or picture-frame curve."""
