"""The exceptions thermostamp raises. All derive from :class:`ThermostampError`; those for bad
input are also :class:`ValueError`, those for files also :class:`OSError`, so that code written
for the standard exceptions catches them too. The messages are the command line's."""

import re

__all__ = [
    "ThermostampError",
    "ScenarioError",
    "InputError",
    "StudyError",
    "OutputError",
    "RunFailed",
]


class ThermostampError(Exception):
    """Base class of thermostamp's exceptions."""


def _key_of(message):
    """The scenario key a message names: ``key `a.b`: ...``, ``a.b = 3: ...``, ``--set a.b=...``."""
    for pattern in (
        r"key `([^`]+)`",
        r"--set ([A-Za-z_][\w.\[\]]*)=",
        r"^([a-z_]+(?:\[\d+\])?(?:\.[A-Za-z_]\w*(?:\[\d+\])?)+)\b",
    ):
        found = re.search(pattern, message)
        if found:
            return found.group(1)
    return None


class ScenarioError(ThermostampError, ValueError):
    """A scenario that cannot be run: a bad key or value, a missing file, a model that cannot be
    built. ``origin`` is the file (or ``<dict>``), ``message`` the command line's message and
    ``key`` the scenario key it names (``None`` where it names none)."""

    def __init__(self, origin, message):
        super().__init__(f"{origin}: {message}")
        self.origin = origin
        self.message = message
        self.key = _key_of(message)


class InputError(ThermostampError, ValueError):
    """Bad input other than a scenario: a material card, a table of values, an option."""


class StudyError(ThermostampError, ValueError):
    """A study that cannot be run: a bad study file or parameter, a folder holding another study."""


class OutputError(ThermostampError, OSError):
    """A result that could not be written, or an output folder another run is writing."""


class RunFailed(ThermostampError):
    """Raised by :meth:`thermostamp.Result.raise_for_status` for a run that did not finish;
    ``result`` is the run's result, its records so far kept."""

    def __init__(self, message, result):
        super().__init__(message)
        self.result = result
