"""Antenna arrays: steering vector (eq. (1)), DFT codebook, beam set, two-way gain ϖ."""

from radioslam.antenna.array import array_response, spatial_frequency, steering_vector
from radioslam.antenna.codebook import BeamSet, beam_angle, dft_codebook

__all__ = ["BeamSet", "array_response", "beam_angle", "dft_codebook", "spatial_frequency",
           "steering_vector"]
