"""analytic.records.peak_times: near-equal maxima of x(t), ripple not counted."""

import numpy as np

from treeimpact.analytic.records import peak_times

T = np.linspace(0.0, 0.05, 5001)


def hump(t0, height, width=0.004):
    return height * np.exp(-((T - t0) / width) ** 2)


def test_two_humps_within_5_percent_are_two_peaks_and_further_apart_are_one():
    assert np.allclose(peak_times(T, hump(0.012, 1.0) + hump(0.025, 0.98)), [0.012, 0.025],
                       atol=2e-4)
    assert np.allclose(peak_times(T, hump(0.012, 1.0) + hump(0.025, 0.90)), [0.012], atol=2e-4)


def test_ripple_on_one_peak_is_not_a_second_one():
    x = hump(0.02, 1.0) + 0.005 * np.sin(2 * np.pi * 2000 * T)  # 0.5 % ripple, 0.5 ms
    assert len(peak_times(T, x)) == 1


def test_a_record_that_never_rises_has_no_peak():
    assert peak_times(T, -hump(0.02, 1.0)) == []
