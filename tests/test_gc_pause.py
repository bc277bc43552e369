"""curvenet.io.gc_pause: the collector is off inside the block and as it was after."""

from __future__ import annotations

import gc

import pytest

from curvenet.io.gc_pause import collector_paused


@pytest.mark.parametrize("enabled", [True, False])
def test_collector_paused_restores_the_state(enabled):
    was = gc.isenabled()
    try:
        (gc.enable if enabled else gc.disable)()
        with collector_paused():
            assert not gc.isenabled()
        assert gc.isenabled() is enabled
        with pytest.raises(ValueError):
            with collector_paused():
                raise ValueError("boom")
        assert gc.isenabled() is enabled
    finally:
        (gc.enable if was else gc.disable)()
