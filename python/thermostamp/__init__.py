"""thermostamp: thermo-stamping simulation of woven-fabric thermoplastic prepregs with the
lamination model of Gong et al. (Composite Structures 2018), from Python.

The same engine as the ``thermostamp`` command line, in this process::

    import thermostamp as ts
    scenario = ts.Scenario.load("examples/hemisphere.toml", set={"process.temperature": 310})
    result = ts.run(scenario)                 # a Result: summary, history, last frame
    result.summary["peak_punch_force"]        # N
    result.history["punch_force"]             # NumPy array, one value per record

Units everywhere: mm, N, s, MPa, tonne/mm^3, °C. The guide is docs/guide/python.md.
"""

from . import errors
from ._core import HISTORY_COLUMNS, __version__
from .errors import (
    InputError,
    OutputError,
    RunFailed,
    ScenarioError,
    StudyError,
    ThermostampError,
)
from .forming import RunWarning, run
from .material import (
    FitResult,
    TestResult,
    bias_extension_test,
    fit_fabric_tension,
    fit_matrix,
    fit_shear,
    material_point,
    picture_frame_test,
    uniaxial_test,
)
from .result import Check, Frame, Result
from .scenario import Scenario
from .study import FullFactorial, LatinHypercube, Range, Sobol, Study, StudySummary

__all__ = [
    "Check",
    "FitResult",
    "Frame",
    "FullFactorial",
    "HISTORY_COLUMNS",
    "InputError",
    "LatinHypercube",
    "OutputError",
    "Range",
    "Result",
    "RunFailed",
    "RunWarning",
    "Scenario",
    "ScenarioError",
    "Sobol",
    "Study",
    "StudyError",
    "StudySummary",
    "TestResult",
    "ThermostampError",
    "__version__",
    "bias_extension_test",
    "errors",
    "fit_fabric_tension",
    "fit_matrix",
    "fit_shear",
    "material_point",
    "picture_frame_test",
    "run",
    "uniaxial_test",
]
