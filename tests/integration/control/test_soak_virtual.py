"""A short soak (tools/soak_virtual.py): 15 s of 200 Hz control in virtual time, nothing lost.

The full hour (720,000 cycles) is run by hand and recorded in docs/hardware.md.
"""

from __future__ import annotations

import os

import pytest

from tools.soak_virtual import soak


@pytest.mark.skipif(not os.path.exists("/proc/self/status"), reason="RSS from Linux /proc")
def test_a_short_soak_loses_no_cycle_and_does_not_grow() -> None:
    result = soak(3000, 200.0, samples=10)
    assert (result.cycles_run, result.lost_cycles, result.overruns) == (3000, 0, 0)
    assert result.virtual_s == pytest.approx(15.0, abs=0.01)
    assert (result.retries, result.group_retries, result.watchdog_trips) == (0, 0, 0)
    assert len(result.rss_samples) == 10
    assert result.growth(result.rss_samples) < 1 << 20  # < 1 MiB over 2700 cycles after warm-up
