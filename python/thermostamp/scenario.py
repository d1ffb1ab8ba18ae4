"""Scenarios: the same files as ``thermostamp run`` reads, checked the same way."""

import os

from . import _core

__all__ = ["Scenario"]


def _toml_literal(value):
    """``value`` written as ``--set`` reads it."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return repr(value)
    if isinstance(value, str):
        return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if hasattr(value, "item"):  # NumPy scalars
        return _toml_literal(value.item())
    raise TypeError(f"{value!r}: a scenario value is a number, a string or a boolean")


def _overrides(set):
    return [f"{key}={_toml_literal(value)}" for key, value in (set or {}).items()]


class Scenario:
    """A checked forming scenario (blank, tools, process, output), as ``thermostamp run`` reads it.

    Make one with :meth:`load` (a file, with overrides as ``--set`` gives them) or
    :meth:`from_dict`; every key, its unit and default are in docs/guide/scenario.md. A bad key
    or value raises :class:`thermostamp.errors.ScenarioError` naming the key, with the command
    line's message. The scenario is held as TOML text whose file paths (card, meshes, tool
    files) are absolute, so that it runs from any folder and in any process (it pickles)."""

    def __init__(self, text, origin):
        self._text = text
        self.origin = origin

    @classmethod
    def load(cls, path, set=None):
        """The scenario file at ``path`` with the overrides ``set`` (a dict of dotted keys to
        values, e.g. ``{"process.temperature": 310, "blank.interfaces[1].friction": 0.2}``)."""
        path = os.fspath(path)
        return cls(_core.scenario_load(path, _overrides(set)), path)

    @classmethod
    def from_dict(cls, table, base_dir=None, origin="<dict>"):
        """The scenario of a dictionary laid out as the file (``{"blank": {...}, "tools": {...},
        "process": {...}}``); relative file paths are taken from ``base_dir`` (default: the
        current folder)."""
        text = _core.toml_dumps(table)
        folder = os.fspath(base_dir) if base_dir is not None else os.getcwd()
        return cls(_core.scenario_from_text(text, origin, folder, []), origin)

    def with_set(self, set):
        """A copy with the overrides ``set`` applied (checked)."""
        return Scenario(
            _core.scenario_from_text(self._text, self.origin, os.getcwd(), _overrides(set)),
            self.origin,
        )

    def to_toml(self):
        """The scenario as TOML text, its file paths absolute: a file ``thermostamp run`` runs."""
        return self._text

    def to_dict(self):
        """The scenario as a dictionary laid out as the file."""
        return _core.toml_loads(self._text)

    def __getitem__(self, key):
        """A value by its dotted key, e.g. ``scenario["process.temperature"]``."""
        here = self.to_dict()
        for part in key.split("."):
            here = here[part]
        return here

    def __repr__(self):
        return f"Scenario({self.origin!r})"

    def __eq__(self, other):
        return isinstance(other, Scenario) and self._text == other._text

    def __getstate__(self):
        return {"text": self._text, "origin": self.origin}

    def __setstate__(self, state):
        self._text = state["text"]
        self.origin = state["origin"]
