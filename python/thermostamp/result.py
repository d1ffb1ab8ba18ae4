"""What a forming run gives back: its status, summary, history, last frame and checks."""

from collections import namedtuple

from .errors import RunFailed

__all__ = ["Result", "Frame", "Check"]

Check = namedtuple("Check", ["name", "status", "figure"])
Check.__doc__ = """A run-time check: its name, ``OK``, ``WARNING`` or ``STOPPED``, and its figure."""


class Frame:
    """The sheet at the end of the run, as NumPy arrays (the ParaView frame's content).

    ``points``: (n, 3) reference (flat) positions in mm; ``point_data["displacement"]`` takes
    them to the formed part (:attr:`formed_points`). ``cells`` and ``cell_types``: VTK's flat
    cell list (corner count, then corners) and cell type codes (5 triangle, 9 quadrilateral).
    ``point_data`` and ``cell_data``: name to array, (n,) scalars or (n, 3) vectors and in-plane
    tensors (xx, yy, xy in the reference axes); ``code_meanings``: what each code of a coded
    field (``contact_status``) means. The fields and their units are listed in
    docs/guide/outputs.md."""

    def __init__(self, raw):
        self.points = raw["points"]
        self.cells = raw["cells"]
        self.cell_types = raw["cell_types"]
        self.point_data = raw["point_data"]
        self.cell_data = raw["cell_data"]
        self.code_meanings = raw["code_meanings"]

    @property
    def formed_points(self):
        """(n, 3) positions of the formed part: the points moved by their displacement."""
        return self.points + self.point_data["displacement"]

    def to_pyvista(self, formed=True):
        """A ``pyvista.UnstructuredGrid`` of the sheet with every field, on the formed part
        (``formed=True``) or the flat blank. Needs pyvista (``pip install pyvista``)."""
        try:
            import pyvista
        except ImportError as e:
            raise ImportError("to_pyvista needs pyvista: pip install pyvista") from e
        points = self.formed_points if formed else self.points
        grid = pyvista.UnstructuredGrid(self.cells, self.cell_types, points)
        for name, values in self.point_data.items():
            grid.point_data[name] = values
        for name, values in self.cell_data.items():
            grid.cell_data[name] = values
        return grid

    def __repr__(self):
        return f"Frame({len(self.points)} points, {len(self.cell_types)} cells)"


class Result:
    """A forming run's result, from :func:`thermostamp.run`.

    - ``status``: how it ended, in the summary's words; ``outcome``: ``finished``,
      ``interrupted``, ``failed`` (the solver or a check stopped it, results so far kept) or
      ``output`` (a result could not be written); ``ok`` is ``outcome == "finished"``, and
      ``error`` the full message otherwise.
    - ``summary``: the final measures of ``forming-result.csv`` by name (``peak_punch_force``
      in N, ``max_shear_deg``, ``waviness`` in mm, ...; ``None`` where the run has none),
      with ``steps``, ``wall_seconds``, ``elements``, ``nodes``, ``solver``, ``threads``.
    - ``history``: the columns of ``forming.csv`` by name, NumPy arrays (one value per record).
    - ``frame``: the sheet at the end (:class:`Frame`), ``None`` for a run stopped before its
      first record.
    - ``checks``: the run-time checks (:class:`Check`); ``files``: the files written (none
      without an output folder); ``notes``: the set-up's notes and advice.
    """

    def __init__(self, raw):
        self.status = raw["status"]
        self.outcome = raw["outcome"]
        self.error = raw["error"]
        self.summary = raw["summary"]
        self.history = raw["history"]
        self.frame = Frame(raw["frame"]) if raw["frame"] is not None else None
        self.checks = [Check(*c) for c in raw["checks"]]
        self.files = raw["files"]
        self.notes = raw["notes"]

    @property
    def ok(self):
        """Whether the run finished."""
        return self.outcome == "finished"

    def raise_for_status(self):
        """Raises :class:`thermostamp.errors.RunFailed` unless the run finished; returns the
        result otherwise."""
        if not self.ok:
            raise RunFailed(f"{self.status}: {self.error}", self)
        return self

    def to_pandas(self):
        """The history as a ``pandas.DataFrame``, one row per record. Needs pandas."""
        try:
            import pandas
        except ImportError as e:
            raise ImportError("to_pandas needs pandas: pip install pandas") from e
        return pandas.DataFrame(self.history)

    def to_pyvista(self, formed=True):
        """The last frame as a ``pyvista.UnstructuredGrid`` (:meth:`Frame.to_pyvista`)."""
        if self.frame is None:
            raise ValueError(f"the run has no frame: {self.status}")
        return self.frame.to_pyvista(formed=formed)

    def __repr__(self):
        s = self.summary
        return (
            f"Result({self.status!r}, peak punch force {s.get('peak_punch_force')} N, "
            f"largest shear {s.get('max_shear_deg')}°, {len(self.history['time'])} records)"
        )
