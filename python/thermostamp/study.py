"""Process studies from Python: a base scenario run over a design of parameter values, each case
in its own folder and its own process, on any ``concurrent.futures.Executor``."""

import concurrent.futures
import csv
import multiprocessing
import os

from . import _core

__all__ = ["Study", "Range", "FullFactorial", "LatinHypercube", "Sobol", "StudySummary"]


class Range:
    """Values from ``start`` to ``stop``: ``count`` evenly spaced ones, both ends included, in a
    full factorial; every value between them in a sampled design (leave ``count`` out)."""

    def __init__(self, start, stop, count=None):
        self.start, self.stop, self.count = float(start), float(stop), count

    def _as_written(self):
        table = {"from": self.start, "to": self.stop}
        if self.count is not None:
            table["count"] = int(self.count)
        return table

    def __repr__(self):
        count = "" if self.count is None else f", count={self.count}"
        return f"Range({self.start}, {self.stop}{count})"


class FullFactorial:
    """Every combination of the parameters' values, the last parameter varying fastest."""

    def _as_written(self):
        return None


class LatinHypercube:
    """``samples`` cases whose values of each parameter fall one into each of ``samples`` equal
    strata of its range; the same ``seed`` gives the same cases on any machine."""

    method = "latin-hypercube"

    def __init__(self, samples, seed=0):
        self.samples, self.seed = int(samples), int(seed)

    def _as_written(self):
        return {"method": self.method, "samples": self.samples, "seed": self.seed}


class Sobol(LatinHypercube):
    """``samples`` cases from a scrambled Sobol sequence (low discrepancy: spread evenly for any
    number of samples, best at powers of two); the same ``seed`` gives the same cases."""

    method = "sobol"


def _values(value):
    if isinstance(value, Range):
        return value._as_written()
    if hasattr(value, "tolist"):  # NumPy arrays
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [v.item() if hasattr(v, "item") else v for v in value]
    return [value]


class Study:
    """A study: the ``base`` scenario file run over ``parameters`` (dotted scenario keys to a
    list of values or a :class:`Range`) by a ``design`` (:class:`FullFactorial` by default,
    :class:`LatinHypercube`, :class:`Sobol`), the cases in ``folder`` (default
    ``<base name>-study-results``). The same study as a study file for ``thermostamp sweep``
    (:meth:`to_toml`, :meth:`load`): the same cases, folders and ``summary.csv``.

    ``wrinkle_threshold``: waviness (mm) above which a case counts as wrinkled (default half a
    ply); ``threads_per_case``: worker threads of each case."""

    def __init__(
        self,
        base,
        parameters,
        folder=None,
        design=None,
        wrinkle_threshold=None,
        threads_per_case=1,
    ):
        base = os.path.abspath(os.fspath(base))
        if folder is None:
            name = os.path.splitext(os.path.basename(base))[0]
            folder = f"{name}-study-results"
        table = {"base": base, "parameters": {k: _values(v) for k, v in parameters.items()}}
        output = {"folder": os.path.abspath(os.fspath(folder))}
        if wrinkle_threshold is not None:
            output["wrinkle_threshold"] = float(wrinkle_threshold)
        table["output"] = output
        table["run"] = {"threads_per_case": int(threads_per_case)}
        written = (design or FullFactorial())._as_written()
        if written is not None:
            table["design"] = written
        text = _core.toml_dumps(table)
        self._spec = (text, "<Study>", os.getcwd(), os.getcwd())
        self._describe()

    @classmethod
    def load(cls, path):
        """The study file at ``path``, as ``thermostamp sweep`` reads it."""
        path = os.fspath(path)
        with open(path, encoding="utf-8") as f:
            text = f.read()
        study = cls.__new__(cls)
        study._spec = (text, path, os.path.dirname(os.path.abspath(path)), os.getcwd())
        study._describe()
        return study

    def _describe(self):
        info = _core.study_open(*self._spec)
        self.folder = info["folder"]
        self.parameters = info["parameters"]
        self.cases_count = info["cases"]
        self.threads_per_case = info["threads_per_case"]

    def to_toml(self):
        """The study file's text."""
        return self._spec[0]

    def cases(self):
        """Every case: ``{"case": number, <key>: value, ..., "status": ...}``, as ``--list``."""
        return [
            {"case": n, **dict(zip(self.parameters, values)), "status": status}
            for n, values, status in _core.study_cases(*self._spec)
        ]

    def map(self, executor=None, jobs=None, progress=None):
        """Runs the cases not yet finished, each in its own folder by its own process, and
        returns the :class:`StudySummary` (also written as ``summary.csv`` and charts).

        ``executor``: any ``concurrent.futures.Executor`` whose workers are processes: Dask's
        ``Client.get_executor()``, submitit's for SLURM, Ray's, or a ``ProcessPoolExecutor``;
        default, a pool of ``jobs`` processes (default the cores divided by the threads per
        case). Resumable: a study killed part-way runs only what is left. ``progress``: a
        callable ``progress(done, total, case_number, status)`` called as each case ends. A
        case that failed is in the summary with its reason (and ``summary.failed``)."""
        command = f"python: thermostamp Study.map ({self._spec[1]})"
        pending = _core.study_prepare(*self._spec, command)
        own = executor is None
        if own:
            cores = os.cpu_count() or 1
            jobs = jobs or max(1, cores // self.threads_per_case)
            executor = concurrent.futures.ProcessPoolExecutor(
                max_workers=min(jobs, max(1, len(pending))),
                mp_context=multiprocessing.get_context("spawn"),
            )
        try:
            futures = {executor.submit(run_case, self._spec, n): n for n in pending}
            for done, future in enumerate(concurrent.futures.as_completed(futures), 1):
                status, _reason, _seconds = future.result()
                if progress is not None:
                    progress(done, len(futures), futures[future], status)
        finally:
            if own:
                executor.shutdown(wait=True, cancel_futures=True)
        return self.summarise()

    def run_case(self, number):
        """Runs case ``number`` here (as ``thermostamp sweep --case N``): ``(status, reason,
        wall_seconds)``. Ctrl-C stops it with ``KeyboardInterrupt`` and leaves it unfinished:
        the study runs it again."""
        return run_case(self._spec, number)

    def summarise(self):
        """Writes ``summary.csv`` and the charts from the case folders, and returns the
        :class:`StudySummary`."""
        path = _core.study_summarise(*self._spec, f"python: thermostamp Study.summarise ({self._spec[1]})")
        return StudySummary(path)

    def __repr__(self):
        return f"Study({self._spec[1]!r}, {self.cases_count} cases, parameters {self.parameters})"


def run_case(spec, number):
    """Runs case ``number`` of the study ``spec`` in this process (the function the executors'
    workers call): ``(status, reason, wall_seconds)``."""
    return _core.study_run_case(*spec, number, f"python: thermostamp study case {number} ({spec[1]})")


class StudySummary:
    """A study's ``summary.csv``: ``columns`` (name to list of values: numbers as floats, empty
    cells as ``None``), ``path``, the ``failed`` case numbers; ``to_pandas()``."""

    def __init__(self, path):
        self.path = os.fspath(path)
        with open(self.path, newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
        header, body = rows[0], rows[1:]
        self.columns = {name: [_cell(r[k]) for r in body] for k, name in enumerate(header)}
        self.failed = [
            int(n) for n, s in zip(self.columns["case"], self.columns["status"]) if s == "failed"
        ]

    def __len__(self):
        return len(self.columns["case"])

    def to_pandas(self):
        """The summary as a ``pandas.DataFrame``, one row per case. Needs pandas."""
        import pandas

        return pandas.read_csv(self.path)

    def __repr__(self):
        return f"StudySummary({self.path!r}, {len(self)} cases, {len(self.failed)} failed)"


def _cell(text):
    if text == "":
        return None
    try:
        return float(text)
    except ValueError:
        return text
