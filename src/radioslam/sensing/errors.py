"""Errors of the sensing stage."""

from radioslam.errors import RadioslamError


class SensingError(RadioslamError):
    """A capture or calibration the receiver cannot work with."""
