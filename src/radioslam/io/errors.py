"""File-format errors, one type per format."""

from radioslam.errors import RadioslamError


class SigMFError(RadioslamError):
    """A SigMF recording that is missing, malformed, truncated or inconsistent."""


class TumError(RadioslamError):
    """A TUM trajectory file that cannot be parsed."""


class PlyError(RadioslamError):
    """A PLY point cloud that is missing or malformed."""


class CalibrationFileError(RadioslamError):
    """A calibration.json that is missing or malformed."""


class RosMapError(RadioslamError):
    """A map_server map (YAML + PGM) that is missing or malformed."""


class ManifestError(RadioslamError):
    """A run directory whose run.json is malformed, or whose files do not belong to one complete run."""


class SlamSummaryError(RadioslamError):
    """A slam.json that is malformed."""
