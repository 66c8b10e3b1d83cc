"""Measurement chain: calibration (gain) error and time delay.

A wrong hammer or accelerometer sensitivity scales every FRF by one factor
(a constant offset in dB, no frequency shift). A delay between force and
response channels (anti-alias filters, sample skew) multiplies every FRF by
``exp(−iωτ)``: a phase drift proportional to frequency, magnitudes intact.
"""

from __future__ import annotations

import numpy as np

from jointdb.diagnose.physics._candidate import Candidate, Param, register


class Gain(Candidate):
    name = "calibration_gain"
    family = "gain"
    slot = "gain"
    explanation = "a calibration (sensitivity) error in the measurement chain"
    params = (Param("gain", "-", 0.2, 5.0, 1.0),)

    def chain(self, freq, values, level=0):
        return np.full(freq.shape, values["gain"], dtype=complex)


class Delay(Candidate):
    name = "time_delay"
    family = "delay"
    slot = "delay"
    explanation = "a time delay between the force and response channels"
    params = (Param("delay", "s", -5e-4, 5e-4, 0.0, log=False, show=1e6, show_unit="µs",
                    starts=(2e-5, 5e-5, 1e-4, 2e-4, -3e-5, -1e-4)),)

    def chain(self, freq, values, level=0):
        return np.exp(-2j * np.pi * freq * values["delay"])


@register
def _factory(ctx):
    return [Gain(), Delay()]
