"""Exceptions that the CLI turns into one clear line and an exit code, and the guarded import
of the optional dependency torch (:func:`import_torch`).

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


class MissingExtra(DemseisError, ImportError):
    """An optional dependency (an extra of the ``demseis`` package) is not installed."""


#: what a user without torch is told to run
TORCH_HINT = ("install the torch build for your machine (https://pytorch.org/get-started/locally/),"
              " then pip install \"demseis[torch]\"")


def import_torch(what: str):  # noqa: ANN201 - the torch module, which may not be installed
    """The ``torch`` module, or :class:`MissingExtra` naming the extra when it is missing.

    ``what`` says what needs it (``"demseis train"``, ``"the PyTorch Dataset"`` ...). Generating,
    validating, rendering and scoring never call this: only the Dataset, training and prediction.
    """
    try:
        import torch  # noqa: PLC0415 - optional: the [torch] extra
    except ImportError:
        raise MissingExtra(f"{what} needs PyTorch, which is not installed: {TORCH_HINT}") from None
    return torch
