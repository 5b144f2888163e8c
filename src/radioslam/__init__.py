"""radioslam: active mmWave sensing SLAM in 5G NR.

Implements Du et al., "Simultaneous Localization and Mapping Using Active mmWave
Sensing in 5G NR" (arXiv 2507.04662). Packages, one per pipeline stage:
``nr`` (waveform), ``antenna`` (codebook), ``scene`` (geometry, ray casting),
``sim`` (echo simulator), ``io`` (file formats). The numerical core never
imports ``cli``.
"""

__version__ = "0.1.0"
