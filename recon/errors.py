"""Exceptions raised for bad input anywhere in spectwin."""


class SpectwinInputError(ValueError):
    """Input that is malformed: the message names the field and what was expected."""


class SpectwinDataError(FileNotFoundError):
    """A data file that spectwin needs could not be found or read."""
