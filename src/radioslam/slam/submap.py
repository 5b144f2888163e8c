"""Submaps: N consecutive scans fused in the frame of the first (MATLAB lidarSLAM and
Cartographer both close loops against such submaps rather than single scans)."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass
class Submap:
    keys: list[int] = field(default_factory=list)  # scan indices, the first is the anchor

    @property
    def anchor(self) -> int:
        return self.keys[0]
