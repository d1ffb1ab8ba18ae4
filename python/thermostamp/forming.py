"""Forming runs from Python: :func:`run`."""

import os
import warnings

from . import _core
from .result import Result
from .scenario import Scenario

__all__ = ["run", "RunWarning"]


class RunWarning(UserWarning):
    """A run that did not finish (its result holds the records so far)."""


def run(scenario, output=None, threads=None, progress=None):
    """Runs a forming scenario in this process and returns its :class:`~thermostamp.Result`.

    ``scenario``: a :class:`~thermostamp.Scenario` or the path of a scenario file.
    ``output``: a folder to write the same files as ``thermostamp run`` (history CSV, ParaView
    series, pictures, formed blank); nothing is written without one. ``threads``: worker
    threads of the element loops (default all cores; results are the same on any number).
    ``progress``: a callable ``progress(fraction, step, time)`` called about ten times a second
    (``fraction`` of the stroke's time done, solver ``step``, process ``time`` in s); an
    exception it raises stops the run and is raised again with the result attached as
    ``exception.result``.

    The interpreter is free while the run goes (other Python threads run). Ctrl-C stops the run
    after its step as the command line does: ``KeyboardInterrupt`` is raised with the partial
    result, records so far and files written, as ``exception.result``. A run the solver or a
    check stopped is returned with ``ok`` false and a :class:`RunWarning`.
    Bad input raises :class:`~thermostamp.errors.ScenarioError`; an output folder held by
    another run, :class:`~thermostamp.errors.OutputError`.
    """
    if not isinstance(scenario, Scenario):
        scenario = Scenario.load(scenario)
    if output is not None:
        output = os.fspath(output)
    command = f"python: thermostamp.run({scenario.origin})"
    raw, raised = _core.run_scenario(
        scenario.to_toml(), scenario.origin, output, threads, progress, command
    )
    result = Result(raw)
    if raised is not None:
        raised.result = result
        raise raised
    if not result.ok:
        warnings.warn(f"{result.status}: {result.error}", RunWarning, stacklevel=2)
    return result
