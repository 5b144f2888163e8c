"""Errors of the SLAM stage."""

from radioslam.errors import RadioslamError


class SlamError(RadioslamError):
    """Scans or settings the SLAM stage cannot work with."""
