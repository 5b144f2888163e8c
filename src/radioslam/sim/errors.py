"""Errors of the simulation stage."""

from radioslam.errors import RadioslamError


class SimulationError(RadioslamError):
    """A radio or scene the simulator cannot model."""
