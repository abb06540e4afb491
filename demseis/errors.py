"""Exceptions that the CLI turns into one clear line and an exit code.

Every error a user can cause (a bad config, a missing path, a foreign store, bad arrays) is a
:class:`DemseisError`. The CLI prints ``demseis: error: <message>`` and exits with
``exit_code`` (2 for usage and input errors), never a traceback.
"""


class DemseisError(Exception):
    """Base class of user-facing errors. ``exit_code`` is what the CLI exits with."""

    exit_code = 2


class ConfigError(DemseisError, ValueError):
    """A config key is unknown, has the wrong type, or is out of range."""


class StoreError(DemseisError):
    """A store is missing, foreign, of another schema version, or inconsistent."""


class InputError(DemseisError, ValueError):
    """An input array, file or argument is malformed."""


class SimulationError(DemseisError, RuntimeError):
    """A DEM run went unstable (NaN, kinetic-energy blow-up, element leaving the box)."""

    exit_code = 1
