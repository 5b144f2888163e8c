"""Echo simulator: ray-traced echo paths → NR waveform or resource grid → Capture."""

from radioslam.sim.channel import beam_path_gains, channel_response, delay_phasors, strongest_echo
from radioslam.sim.noise import measured_snr_db, noise_variance, reference_echo_power
from radioslam.sim.paths import EchoPaths, PathKind, echo_paths
from radioslam.sim.simulator import RANDOM_STREAM_VERSION, Simulator
from radioslam.sim.waveform import synthesize_windows

__all__ = ["RANDOM_STREAM_VERSION", "EchoPaths", "PathKind", "Simulator", "beam_path_gains", "channel_response",
           "delay_phasors", "echo_paths", "measured_snr_db", "noise_variance", "reference_echo_power",
           "strongest_echo", "synthesize_windows"]
