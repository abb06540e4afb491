"""demseis.plotting: the titles of the figures."""

from __future__ import annotations


def test_a_noise_free_sample_is_titled_no_noise():
    """issue 38: the plot of a noise-free sample was titled "SNR inf dB (band)"."""
    from demseis.plotting import noise_title

    assert noise_title(float("inf"), "band") == "no noise"
    assert noise_title("inf", "white") == "no noise"
    assert noise_title(10.0, "white") == "SNR 10 dB (white)"
