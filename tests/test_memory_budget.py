"""Memory is estimated before it is allocated (issue #15 point 3): the estimate bounds what
``tracemalloc`` measures, a radio beyond the budget is one line naming the field, and the ray caster's
blocks give the same hits as one table."""

import subprocess
import sys
import tracemalloc

import numpy as np
import pytest

from radioslam.io import read_capture, write_capture
from radioslam.scene import load_scene, raycast
from radioslam.sensing import Receiver
from radioslam.sim import Simulator
from radioslam.sim.memory import recording_memory


def _peak(work) -> int:
    tracemalloc.start()
    try:
        work()
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


@pytest.mark.parametrize("radio", [{}, {"frames": 4}, {"ray_spacing_deg": 0.1}, {"elevation_beams": 3}])
def test_simulating_a_pose_stays_within_its_estimate(radio):
    scene = load_scene("paper-cnv").with_radio(**radio)
    sim = Simulator.from_scene(scene)
    estimate = sim.memory().total
    peak = _peak(lambda: sim.simulate_pose(0, np.random.default_rng(0)))
    assert peak <= estimate <= 4 * peak  # a bound, not a wild one


def test_sensing_a_recording_stays_within_its_estimate(tmp_path):
    scene = load_scene("paper-cnv")
    write_capture(Simulator.from_scene(scene).simulate_pose(0, np.random.default_rng(0)), tmp_path / "0000")
    data = tmp_path / "0000.sigmf-data"
    receiver = Receiver(scene.radio, scene.radio.hardware_delay_s)
    peak = _peak(lambda: receiver.sense(read_capture(tmp_path / "0000")))
    assert peak <= recording_memory(data.stat().st_size).total


def test_a_radio_beyond_the_budget_is_one_line_naming_the_field(tmp_path):
    out = subprocess.run([sys.executable, "-m", "radioslam.cli", "simulate", "paper-cnv", "--out", str(tmp_path / "o"),
                          "--max-memory", "0.05"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 2 and out.stderr.count("\n") == 1
    assert "paper-cnv: radio.fft_size × symbols × beams: needs ≈" in out.stderr and "--max-memory" in out.stderr
    assert not (tmp_path / "o").exists()  # refused before anything was written


def test_rays_cast_in_blocks_hit_what_one_table_hits(monkeypatch):
    scene = load_scene("corridor-loop")
    angles = np.linspace(-np.pi, np.pi, 721)
    args = (scene.poses[3][:2], angles, scene.segments, scene.material_array("transmission"), 3, 40.0)
    whole = raycast.cast_rays(*args)
    monkeypatch.setattr(raycast, "TABLE_CELLS", 7 * len(scene.segments))  # blocks of 7 rays
    blocks = raycast.cast_rays(*args)
    for field in ("distance", "segment", "cos_incidence", "transmission"):
        np.testing.assert_array_equal(getattr(blocks, field), getattr(whole, field))
