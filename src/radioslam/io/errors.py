"""File-format errors, one type per format."""

from radioslam.errors import RadioslamError


class SigMFError(RadioslamError):
    """A SigMF recording that is missing, malformed, truncated or inconsistent."""


class TumError(RadioslamError):
    """A TUM trajectory file that cannot be parsed."""
