"""Scene-file errors."""

from radioslam.errors import RadioslamError


class SceneError(RadioslamError):
    """A scene file that cannot be read or does not follow the schema."""
