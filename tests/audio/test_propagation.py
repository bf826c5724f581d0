import numpy as np
import pytest

from hearsee.audio.arrays import MicArray
from hearsee.audio.propagation import add_noise, delay_signals, simulate_free_field
from hearsee.audio.signals import white_noise
from hearsee.errors import GeometryError


def test_integer_delay_is_exact_shift():
    x = white_noise(0.1, 16000, rng=1)
    y = delay_signals(x, [0.0, 5 / 16000], 16000)
    np.testing.assert_allclose(y[0], x, atol=1e-9)
    np.testing.assert_allclose(y[1, 5:], x[:-5], atol=1e-9)


def test_fractional_delay_matches_cross_spectrum_phase():
    fs = 16000
    x = white_noise(1.0, fs, rng=2)
    tau = 2.37 / fs
    y = delay_signals(x, [0.0, tau], fs)
    n = 4096
    X0, X1 = np.fft.rfft(y[0, 2000:2000 + n]), np.fft.rfft(y[1, 2000:2000 + n])
    f = np.fft.rfftfreq(n, 1 / fs)
    band = (f > 100) & (f < 4000)
    phase = np.unwrap(np.angle(X1[band] * np.conj(X0[band])))
    slope = np.polyfit(2 * np.pi * f[band], phase, 1)[0]
    assert -slope == pytest.approx(tau, rel=0.02)


def test_free_field_spreading_and_noise():
    arr = MicArray.from_preset("two-mic")
    x = white_noise(0.5, 16000, rng=3)
    src = np.array([0.0, 1.0, 0.0])
    y = simulate_free_field(x, 16000, arr, src)
    r = np.linalg.norm(arr.positions - src, axis=1)
    ratio = np.std(y[1, 200:]) / np.std(y[0, 200:])
    assert ratio == pytest.approx(r[0] / r[1], rel=0.02)
    noisy = add_noise(y, 10.0, rng=4)
    snr = 10 * np.log10(np.mean(y**2) / np.mean((noisy - y) ** 2))
    assert snr == pytest.approx(10.0, abs=0.3)
    with pytest.raises(GeometryError):
        simulate_free_field(x, 16000, arr, arr.positions[0])
