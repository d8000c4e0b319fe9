"""The add-on's one user-facing error type (a module of its own so that every module can
raise it without importing the engine or ``core``)."""


class OsteonError(Exception):
    """A user-facing problem: its message is shown by report() / printed by batch."""
