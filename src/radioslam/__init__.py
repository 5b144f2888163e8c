"""radioslam: active mmWave sensing SLAM in 5G NR.

Implements Du et al., "Simultaneous Localization and Mapping Using Active mmWave
Sensing in 5G NR" (arXiv 2507.04662). Packages, one per pipeline stage:
``nr`` (waveform), ``antenna`` (codebook), ``scene`` (geometry, ray casting),
``sim`` (echo simulator), ``sensing`` (IQ to point clouds), ``slam``, ``eval``
(metrics), ``io`` (file formats), ``viz`` (figures); on top of them the
application: ``pipeline``, ``cli``. The numerical core never imports the
application layer (docs/architecture.md).
"""

__version__ = "0.2.0"  # the one place the version is written (pyproject.toml reads it)
